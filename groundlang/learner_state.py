"""A learner's state as plain values, what a saved model holds, and the checks when it is read back.

:meth:`groundlang.learner.Learner.state_dict` and :meth:`~groundlang.learner.Learner.from_state_dict`
are the public face; :mod:`groundlang.model_io` writes and reads the values as files. A state read from
a file is untrusted: every field is checked here before anything is built from it.
"""

from __future__ import annotations

import numbers
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import torch

from groundlang.inference.em import EM_ACCELERATIONS
from groundlang.inference.end_habits import EndHabits
from groundlang.inference.likelihoods import check_cache_dir
from groundlang.inference.planning import TaskSettings
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.palette import Palette
from groundlang.model.palette_records import checked_palettes
from groundlang.model.pf_tables import check_table_size
from groundlang.model.language_models import get_language_model
from groundlang.model.vocabulary import Vocabulary
from groundlang.model.world import State

__all__ = ["learner_state", "learner_from_state", "check_count", "check_training_options", "check_state",
           "word_sources"]


def check_count(method: str, name: str, value) -> None:
    """TypeError unless ``value`` is an integer, ValueError unless it is positive (``method`` and ``name`` say
    where)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{method}: {name} must be a positive integer, got {type(value).__name__} {value!r:.40}")
    if value < 1:
        raise ValueError(f"{method}: {name} must be a positive integer, got {value!r:.40}")


def check_threshold(method: str, name: str, value) -> None:
    """ValueError unless ``value`` is None or a number from 0 to 1 (a confidence threshold): with nan, every
    comparison is false and the learner acted however unsure."""
    if value is not None and (isinstance(value, bool) or not isinstance(value, numbers.Real) or not 0 <= value <= 1):
        raise ValueError(f"{method}: {name} must be a number from 0 to 1 (or None), got {value!r:.40}")


def check_state(palettes: list[dict] | None, method: str, command: str, state: State) -> None:
    """The checks of a command and a state a learner trained on ``palettes`` is asked to read: TypeError for
    arguments of the wrong type; ValueError for a state of a palette not trained on, TabulationError for one
    whose layout is too large to tabulate."""
    if not isinstance(command, str):
        raise TypeError(f"{method}: command must be a str, got {type(command).__name__}")
    if not isinstance(state, State):
        raise TypeError(f"{method}: state must be a State (read_state_file, read_initial_state), "
                        f"got {type(state).__name__}")
    palette = state.layout.palette
    # by meaning: a palette drawn otherwise (glyph/2, rgb/2) reads the same words
    if palettes is not None and palette not in [Palette.from_record(p) for p in palettes]:
        trained = ", ".join(p["name"] for p in palettes)
        same_name = (" of the same name but other values"
                     if any(p["name"] == palette.name for p in palettes) else "")
        raise ValueError(f"{method}: the state is of palette {palette.name!r}; this model was trained on "
                         f"palette {trained}{same_name} (colours and shapes must be the same to read its words)")
    check_table_size(state.layout)  # before grounding it: a layout of 40,000 cells had run out the time limit


def check_model_parts(language_model, library) -> None:
    """TypeError unless ``Learner(language_model=..., library=...)`` are a model's name or a LanguageModel,
    and a TaskLibrary or None: either, wrong, failed only inside fit with an AttributeError."""
    from groundlang.logic.tasks import TaskLibrary
    from groundlang.model.language_models import LANGUAGE_MODELS, LanguageModel

    if not isinstance(language_model, (str, LanguageModel)):
        raise TypeError(f"Learner: language_model must be a name ({', '.join(LANGUAGE_MODELS)}) or a "
                        f"LanguageModel, got {type(language_model).__name__}")
    if library is not None and not isinstance(library, TaskLibrary):
        raise TypeError(f"Learner: library must be a TaskLibrary (TaskLibrary.load(path)) or None, got "
                        f"{type(library).__name__}")


def check_training_options(steps, lr, seed, settings, em_acceleration, cache_dir=None) -> None:
    """The checks of ``Learner(...)``'s training options, whether given or read from a saved model."""
    check_count("Learner", "steps", steps)
    # at construction: an empty one put the cache in the working folder, a number failed inside fit
    check_cache_dir(cache_dir, "Learner: cache_dir")
    if isinstance(lr, bool) or not isinstance(lr, (int, float)) or not 0 < lr < float("inf"):
        raise ValueError(f"Learner: lr must be a positive number, got {lr!r}")
    # numpy's and torch's generators take seeds of 32 bits; a wider one failed only inside fit, minutes in
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < 2**32:
        raise ValueError(f"Learner: seed must be an integer from 0 to 2**32 - 1, got {seed!r:.40}")
    if settings is not None and not isinstance(settings, TaskSettings):
        raise TypeError(f"Learner: settings must be a TaskSettings, got {type(settings).__name__}")
    if em_acceleration not in EM_ACCELERATIONS:
        raise ValueError(f"Learner: em_acceleration must be one of {', '.join(EM_ACCELERATIONS)}, "
                         f"got {em_acceleration!r}")


def check_fit_arguments(instances, steps, init) -> list:
    """``fit``'s instances as a list, after TypeError or ValueError for what it cannot train on."""
    if instances is None or isinstance(instances, (str, bytes)):
        raise TypeError(f"fit: instances must be a sequence of corpus instances, not {type(instances).__name__}")
    instances = list(instances)
    if not instances:
        raise ValueError("cannot fit on an empty corpus")
    # the index, not the instance: a None among them had been found as None, read as "nothing wrong"
    bad = next((i for i, x in enumerate(instances) if not isinstance(getattr(x, "initial_state", None), State)), None)
    if bad is not None:
        bad = instances[bad]
        raise TypeError(f"fit: each instance needs command, initial_state, states and actions (a corpus "
                        f"Instance); got {type(bad).__name__}")
    check_count("fit", "steps", steps)
    if init is not None and not (isinstance(init, Mapping) and all(isinstance(v, torch.Tensor) for v in init.values())):
        raise TypeError(f"fit: init must map global names to tensors (a learner's globals), got {type(init).__name__}")
    return instances


def learner_state(learner) -> dict:
    """The fields of a trained learner's state dict (JSON-ready values and ``globals``, tensors by name)."""
    if not learner.palettes:
        raise ValueError("cannot save a learner whose training palettes are unknown (train it with fit())")
    return {
        "language_model": learner.lm.name,
        "language_model_settings": learner.lm.settings(),
        "vocabulary": learner.vocab.to_json(),
        # the words themselves, not the files' paths: the model parses alike where the files are not
        "lexicon": learner.lexicon_words,
        "palettes": learner.palettes,
        "task_library": learner.library.source_text(),
        "planning": learner.settings.as_dict(),
        "training": {"steps": learner.steps, "lr": learner.lr, "seed": learner.seed,
                     "em_acceleration": learner.em_acceleration},
        "end_habits": None if learner.habits is None else _readable(learner.habits),
        "globals": learner.globals,
    }


def learner_from_state(cls, state: dict, where: str):
    """A ``cls`` (:class:`~groundlang.learner.Learner`) built from a state dict's values; see
    ``Learner.from_state_dict``."""
    if not isinstance(state["lexicon"], dict):  # never a path: loading a model reads no other file
        raise ValueError(f"lexicon is {type(state['lexicon']).__name__}, expected words by category")
    for key, kind, expected in (("language_model_settings", dict, "names with values"),
                                ("training", dict, "names with values"), ("planning", dict, "names with values"),
                                ("vocabulary", dict, "names with values"), ("language_model", str, "a name"),
                                ("task_library", str, "the text of an ASP program")):
        if not isinstance(state[key], kind):
            raise ValueError(f"{key} is {type(state[key]).__name__}, expected {expected}")
    # A model saved before habit_prior existed weighed its habits by the rule it now names "overall", and one
    # saved before success_confidence (or held_goals_confidence) was as confident as its goal (its end): it acts
    # and asks as it did; one saved before last_passes_over_negated learned its tables with the last phrase's key
    # on a negated phrase, and reads words with the keys it learned; one saved before negated_phrases_unbiased
    # learned (and updates) under the prior it had; one saved before other_starts follows a command given in several
    # start states as it did (a setting absent from older models is otherwise its default).
    before = {"habit_prior": "overall", "success_confidence": False, "held_goals_confidence": False,
              "last_passes_over_negated": False, "negated_phrases_unbiased": False, "other_starts": False}
    known = get_language_model(state["language_model"]).settings()
    settings = {**{k: v for k, v in before.items() if k in known}, **state["language_model_settings"]}
    learner = cls(
        get_language_model(state["language_model"], **settings),
        library=TaskLibrary.from_saved_text(state["task_library"], f"{where}:task_library"),
        steps=state["training"]["steps"], lr=state["training"]["lr"], seed=state["training"]["seed"],
        settings=TaskSettings(**state["planning"]), lexicon=[state["lexicon"]],
        # models saved before the setting existed were fitted by plain EM
        em_acceleration=state["training"].get("em_acceleration", "none"),
    )
    learner.vocab = Vocabulary.from_json(state["vocabulary"], learner.word_lexicon)
    learner.palettes = checked_palettes(state["palettes"])
    missing = {t.name for t in learner.library.tasks} - set(learner.vocab.tasks)
    if missing:
        raise ValueError(f"the vocabulary lacks the lifted tasks {sorted(missing)} of the saved task library")
    if state.get("end_habits") is not None:
        learner.habits = EndHabits.from_json(state["end_habits"])
        if unknown := learner.habits.unknown_to(learner.library):
            raise ValueError(f"end_habits names {', '.join(repr(n[:80]) for n in unknown[:3])}"
                             f"{f' and {len(unknown) - 3} more' if len(unknown) > 3 else ''}: no goal of the saved "
                             "task library is made of it")
    if state.get("globals") is not None:
        learner.globals = dict(state["globals"])
    return learner


def _readable(habits) -> list:
    """The habit table as saved, refused (ValueError, one line) where the loader would refuse it: a save that
    succeeds leaves a model that loads (a library's relations past the table's bounds are said here)."""
    value = habits.to_json()
    try:
        type(habits).from_json(value)
    except ValueError as exc:
        raise ValueError(f"cannot save the end habits: {exc}") from None
    return value


def word_sources(method: str, lexicon) -> list:
    """``lexicon`` as a list of word sources (a word file's path, or words by category); TypeError naming
    ``method`` for anything else (a number had failed as "'int' object is not iterable")."""
    if isinstance(lexicon, (str, Path, Mapping)):
        return [lexicon]
    if isinstance(lexicon, (list, tuple)) and all(isinstance(x, (str, Path, Mapping)) for x in lexicon):
        return list(lexicon)
    raise TypeError(f"{method}: lexicon must be a word file's path, words by category ({{'NOUN': [...]}}) or a "
                    f"list of them, got {type(lexicon).__name__}")

