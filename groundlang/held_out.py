"""Held-out likelihood of a corpus under a language model, and of each switch of it on and off.

The corpus is split into ``folds`` folds by position (instance n in fold ``n % folds``); for each fold
a model is trained on the others, without labels, and scores the fold's instances by

    log P(words, demonstration) = log sum_j P(j) P(demonstration | j) P(words | j)

summed over the fold, j running over the instance's interpretations (and, words only,
``log sum_j P(j) P(words | j)``). The sum over folds is the held-out log-likelihood. Their difference,
``log P(demonstration | words)``, is how well the words predict what is done, which is what the learner is
used for (following a command is predicting its demonstration from its words): it is what chooses a
default without looking at the accuracy the README reports (ABLATIONS.md keeps all three). The joint
figure alone also rewards a model for explaining the words better, whatever they say of the task.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import torch

from groundlang.learner import Learner
from groundlang.model.language_model_base import FOLLOWING_SETTINGS
from groundlang.model.language_models import get_language_model, setting_names, setting_value

__all__ = ["HeldOutLikelihood", "SwitchRow", "held_out_likelihood", "switch_settings", "compare_switches",
           "format_switches"]

log = logging.getLogger(__name__)


@dataclass
class HeldOutLikelihood:
    """The held-out log-likelihoods (nats) of a corpus, words and demonstrations and words alone."""

    joint: float
    words: float
    folds: int
    n: int
    seconds: float = 0.0

    @property
    def demonstrations(self) -> float:
        """``log P(demonstration | words)``, summed over the held-out instances: the joint less the words."""
        return self.joint - self.words


@dataclass
class SwitchRow:
    """One switch: the setting it changes, to what, and the held-out likelihood with and without."""

    setting: str
    default: object
    value: object
    on: HeldOutLikelihood  # the defaults
    off: HeldOutLikelihood  # the setting at ``value``

    @property
    def favours(self) -> str:
        """``"default"``, ``"other"`` or ``"tie"``: which value the held-out likelihood of the demonstrations given
        the words prefers (an exact tie had been said to favour the default)."""
        if self.off.demonstrations == self.on.demonstrations:
            return "tie"
        return "other" if self.off.demonstrations > self.on.demonstrations else "default"


def held_out_likelihood(instances: Sequence, language_model: str = "parse", settings: Mapping | None = None,
                        folds: int = 10, learner_options: Mapping | None = None) -> HeldOutLikelihood:
    """The ``folds``-fold held-out log-likelihood of ``instances`` (with demonstrations) under
    ``language_model`` with ``settings`` (its keywords); see the module docstring. ValueError for
    fewer instances than folds, fewer than 2 folds, or a bad setting."""
    instances = list(instances)
    if folds < 2 or len(instances) < folds:
        raise ValueError(f"held-out likelihood: {folds} folds need at least 2 folds and as many instances, "
                         f"not {len(instances)}")
    started = time.perf_counter()
    lm = get_language_model(language_model, **dict(settings or {}))
    learner = Learner(language_model=lm, **dict(learner_options or {}))
    # Interpretations and behaviour likelihoods depend on the instance alone: observed once, each fold
    # builds its own vocabulary from its training part.
    observations = learner.observe(instances)
    joint = words = 0.0
    for k in range(folds):
        train = [n for n in range(len(instances)) if n % folds != k]
        test = [n for n in range(len(instances)) if n % folds == k]
        learner.fit([instances[n] for n in train], observations=[observations[n] for n in train])
        batch = lm.encode([observations[n] for n in test], learner.vocab)
        with torch.no_grad():
            said = lm.log_likelihood(learner.globals, batch)  # [I, J]
            joint += float(torch.logsumexp(batch.log_prior + batch.behaviour + said, -1).sum())
            words += float(torch.logsumexp(batch.log_prior + said, -1).sum())
        log.debug("fold %d of %d: %d held out", k + 1, folds, len(test))
    return HeldOutLikelihood(joint, words, folds, len(instances), time.perf_counter() - started)


def switch_settings(language_model: str, switch: str, base: Mapping | None = None) -> tuple[str, object, object]:
    """``(setting, default, other value)`` of a switch written ``NAME`` (a true/false setting: its other
    value) or ``NAME=VALUE`` (VALUE read as JSON, else as text); the default is the model's, or ``base``'s
    where it sets the setting. ValueError, in one line, for a setting the model lacks, a wrong value, or
    a ``NAME`` that is not true/false."""
    name, sep, text = switch.partition("=")
    name = name.strip()
    if name not in setting_names(language_model):
        raise ValueError(f"--switch {switch!r}: language model {language_model} has no setting {name!r}; "
                         f"its settings: {', '.join(setting_names(language_model))}")
    if name in FOLLOWING_SETTINGS:  # the two columns would tie, read as "no effect on held-out data"
        raise ValueError(f"--switch {switch!r}: {name} acts only when following (where a plan ends, how confident "
                         "it is), so the held-out likelihood, which training alone makes, cannot tell its values "
                         "apart; compare its values with evaluate --lm-setting on held-out commands")
    default = get_language_model(language_model, **dict(base or {})).settings()[name]
    if sep:
        try:
            value = setting_value(text.strip())
        except ValueError as exc:
            raise ValueError(f"--switch {name}={exc}") from None
    elif isinstance(default, bool):
        value = not default
    else:
        raise ValueError(f"--switch {switch!r}: {name} is not true or false (default {default!r}); "
                         f"give the other value, e.g. --switch {name}=VALUE")
    get_language_model(language_model, **{**dict(base or {}), name: value})  # refused here, before any training
    if value == default and type(value) is type(default):  # the comparison would be of one setting with itself
        raise ValueError(f"--switch {switch!r}: {value!r} is {name}'s default here; give another value to compare")
    return name, default, value


def compare_switches(instances: Sequence, switches: Sequence[str], language_model: str = "parse",
                     folds: int = 10, learner_options: Mapping | None = None,
                     base: Mapping | None = None) -> list[SwitchRow]:
    """Per switch (:func:`switch_settings`), the held-out likelihood with the defaults (``base`` over the
    model's; computed once) and with the switch's setting changed."""
    base = dict(base or {})
    parsed = [switch_settings(language_model, s, base) for s in switches]  # all checked before training
    on = held_out_likelihood(instances, language_model, base, folds, learner_options)
    return [SwitchRow(name, default, value, on,
                      held_out_likelihood(instances, language_model, {**base, name: value}, folds, learner_options))
            for name, default, value in parsed]


def format_switches(rows: Sequence[SwitchRow]) -> str:
    """A table: per switch, the held-out log-likelihood of the demonstrations given the words, of words and
    demonstrations and of words alone, with the default and with the other value, and which the first
    favours."""
    lines = [f"{'setting':<26} {'default':>9} {'other':>9} {'demo|words, default':>20} {'other':>9} "
             f"{'joint, default':>15} {'other':>9} {'words, default':>15} {'other':>9}  favours"]
    for r in rows:
        lines.append(f"{r.setting:<26} {_text(r.default):>9} {_text(r.value):>9} {r.on.demonstrations:>20.2f} "
                     f"{r.off.demonstrations:>9.2f} {r.on.joint:>15.1f} {r.off.joint:>9.1f} {r.on.words:>15.1f} "
                     f"{r.off.words:>9.1f}  {r.favours}")
    return "\n".join(lines)


def _text(value) -> str:
    import json

    return value if isinstance(value, str) else json.dumps(value)
