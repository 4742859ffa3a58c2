"""Saving and loading trained learners: JSON plus an ``.npz`` of tensors, never pickle.

A model directory holds ``model.json`` (format name and version, language
model and its settings, vocabulary, the words added to the lexicon, the task
library as ASP text, planning settings, the sha256 of the tensor file) and ``globals.npz``. Both are
written to temporary files and renamed; the JSON goes last and names the
tensor file's hash, so a directory whose tensors were swapped or truncated
is refused on load instead of giving silently different answers.
"""

from __future__ import annotations

import hashlib
import io
import json
import zipfile
from pathlib import Path

import numpy as np
import torch

from groundlang.interrupt import deferred_interrupts
from groundlang.model import storage

__all__ = ["FORMAT", "FORMAT_VERSION", "ModelFormatError", "check_model_destination", "save_learner", "load_learner"]

FORMAT = "groundlang-model"
FORMAT_VERSION = 13  # 2: mention and arity globals; 3: transitive prepositions, spatial PF tokens; 4: rooms in the mention model; 5: alignment per lifted task; 6: last-phrase keys; 7: alignment and arity tables per lifted task, not per token; 8: arity per clause; 9: alignment tables span the roles a task offers (vocabulary task_roles), only referring phrases name objects; 10: verbs of negated clauses are frame words; 11: the start room role (other:start); 12: "|last" passes over verb-attached "from" and "with" phrases; 13: the words added to the lexicon (``lexicon``), multiword prepositions joined into one token
MODEL_JSON = "model.json"
GLOBALS = "globals.npz"


class ModelFormatError(ValueError):
    """A model directory that is missing, corrupt, foreign or from another format version."""


def check_model_destination(directory: str | Path, option: str = "") -> Path:
    """``directory`` as a place to write a model, refused if writing there would mix the model with other
    files or overwrite a file that is not a groundlang model's: it must be new, empty, or hold only a model
    (of any format version: saving replaces it). ``train -o model`` run at the repository root would
    otherwise have written into the ``model/`` source package. ``groundlang train`` asks before it trains;
    ``option`` ("-o") starts its messages."""
    directory = Path(directory)
    where = f"{option} {directory}".strip()
    try:
        storage.check_folder(directory, where)
    except ValueError as exc:
        raise ModelFormatError(f"{exc}; a model is written to a folder") from None
    if not directory.is_dir():
        return directory
    others = sorted(p.name for p in directory.iterdir() if p.name not in (MODEL_JSON, GLOBALS)
                    and not p.name.startswith("."))
    if others:
        shown = ", ".join(others[:3]) + (", ..." if len(others) > 3 else "")
        raise ModelFormatError(f"{where}: holds other files ({shown}); write the model to a new or empty "
                               "folder, or over a model")
    if (directory / MODEL_JSON).exists():
        try:
            _read_json(directory, any_version=True)
        except ModelFormatError as exc:
            raise ModelFormatError(f"{exc}; saving would overwrite it") from None
    return directory


def save_learner(learner, directory: str | Path) -> Path:
    """Write a fitted learner to ``directory`` (created if needed; see :func:`check_model_destination`);
    returns the directory."""
    from groundlang.learner import NotFittedError

    if learner.globals is None or learner.vocab is None:
        raise NotFittedError("cannot save a learner that has not been trained")
    directory = check_model_destination(directory)
    buffer = io.BytesIO()
    np.savez(buffer, **{k: v.detach().cpu().numpy() for k, v in learner.globals.items()})
    tensors = buffer.getvalue()
    meta = {
        "format": FORMAT,
        "version": FORMAT_VERSION,
        "language_model": learner.lm.name,
        "language_model_settings": learner.lm.settings(),
        "vocabulary": learner.vocab.to_json(),
        # the words themselves, not the files' paths: the model parses alike where the files are not
        "lexicon": learner.lexicon_words,
        "task_library": learner.library.source_text(),
        "planning": learner.settings.as_dict(),
        "training": {"steps": learner.steps, "lr": learner.lr, "seed": learner.seed},
        "globals_sha256": hashlib.sha256(tensors).hexdigest(),
    }
    # Ctrl-C between the two renames would leave new tensors beside the old JSON: hold it back.
    with deferred_interrupts():
        storage.write_atomically(directory / GLOBALS, tensors)
        storage.write_atomically(directory / MODEL_JSON, json.dumps(meta, indent=1).encode("utf-8"))
    return directory


def _read_json(directory: Path, any_version: bool = False) -> dict:
    """The model's metadata; ModelFormatError unless a groundlang model of this format version
    (``any_version``: of any, as a destination to save over)."""
    path = directory / MODEL_JSON
    if not directory.is_dir():
        raise ModelFormatError(f"{directory}: not a model directory (it does not exist or is not a folder)")
    if not path.is_file():
        raise ModelFormatError(f"{directory}: no {MODEL_JSON}; this is not a groundlang model directory")
    try:
        meta = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise ModelFormatError(f"{path}: not valid JSON ({exc})") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise ModelFormatError(f"{path}: not a groundlang model (format field is not {FORMAT!r})")
    if not any_version and meta.get("version") != FORMAT_VERSION:
        raise ModelFormatError(
            f"{path}: model format version {meta.get('version')!r}, this groundlang reads version {FORMAT_VERSION}; "
            "train the model again with `groundlang train`"
        )
    return meta


def load_learner(directory: str | Path):
    """Read a learner written by :func:`save_learner`; raises ModelFormatError on anything amiss."""
    from groundlang.learner import Learner
    from groundlang.inference.planning import TaskSettings
    from groundlang.logic.tasks import TaskLibrary
    from groundlang.model.language_models import get_language_model
    from groundlang.model.vocabulary import Vocabulary

    directory = Path(directory)
    meta = _read_json(directory)
    tensor_path = directory / GLOBALS
    if not tensor_path.is_file():
        raise ModelFormatError(f"{directory}: {GLOBALS} is missing")
    data = tensor_path.read_bytes()
    if hashlib.sha256(data).hexdigest() != meta.get("globals_sha256"):
        raise ModelFormatError(
            f"{tensor_path}: contents do not match the hash recorded in {MODEL_JSON} (truncated or swapped?)"
        )
    if not data.startswith(b"PK\x03\x04"):
        # np.load would guess "pickled data" for any non-archive and suggest loading it unsafely.
        raise ModelFormatError(f"{tensor_path}: not an .npz archive (it starts with {data[:8]!r}); "
                               "expected the tensors groundlang saved")
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as npz:
            values = {k: torch.from_numpy(np.array(npz[k])) for k in npz.files}
        if not isinstance(meta["lexicon"], dict):  # never a path: loading a model reads no other file
            raise ValueError(f"lexicon is {type(meta['lexicon']).__name__}, expected words by category")
        learner = Learner(
            get_language_model(meta["language_model"], **meta["language_model_settings"]),
            library=TaskLibrary.from_text(meta["task_library"], f"{directory / MODEL_JSON}:task_library"),
            steps=meta["training"]["steps"], lr=meta["training"]["lr"], seed=meta["training"]["seed"],
            settings=TaskSettings(**meta["planning"]), lexicon=[meta["lexicon"]],
        )
        learner.vocab = Vocabulary.from_json(meta["vocabulary"], learner.word_lexicon)
        missing = {t.name for t in learner.library.tasks} - set(learner.vocab.tasks)
        if missing:
            raise ValueError(f"the vocabulary lacks the lifted tasks {sorted(missing)} of the saved task library")
    except (KeyError, TypeError, AttributeError, ValueError, EOFError, zipfile.BadZipFile, OSError) as exc:
        raise ModelFormatError(f"{directory}: model files are incomplete or corrupt ({exc!r})") from None
    learner.globals = _checked_globals(learner, values, tensor_path)
    return learner


def _checked_globals(learner, values: dict, tensor_path: Path) -> dict:
    """The loaded tensors, refused unless names, shapes and finiteness fit the vocabulary and language model."""
    import pyro.poutine

    from groundlang.model.generative import global_sizes

    v = learner.vocab
    with pyro.poutine.block():
        expected = learner.lm.sample_globals(**global_sizes(v))
    if sorted(values) != sorted(expected):
        raise ModelFormatError(
            f"{tensor_path}: holds {sorted(values)}; language model {learner.lm.name} needs {sorted(expected)}"
        )
    out = {}
    for name, want in expected.items():
        got = values[name]
        if tuple(got.shape) != tuple(want.shape) or not (got.is_floating_point() and bool(torch.isfinite(got).all())):
            raise ModelFormatError(
                f"{tensor_path}: {name} is {got.dtype} {tuple(got.shape)}; expected finite floats of shape "
                f"{tuple(want.shape)} for this vocabulary"
            )
        out[name] = got.to(want.dtype)
    return out
