"""Saving and loading trained learners: JSON plus an ``.npz`` of tensors, never pickle.

A model directory holds ``model.json`` (format name and version, language
model and its settings, vocabulary, the words added to the lexicon, the palettes it was trained on, the task
library as ASP text, planning settings, the name and sha256 of the tensor
file) and the tensor file ``globals-<first 16 hex digits of its sha256>.npz``.

Saving is all-or-nothing: the tensors go to a new, content-named file first,
then ``model.json`` is renamed into place, and that one rename is the moment
the new model replaces the old (whose tensor file the old ``model.json``
still names until then). Only afterwards are tensor files no ``model.json``
names, and temporary files an interrupted save left, removed. A crash, a
``kill -9`` or a full disk at any point leaves the previous model loadable.

Loading reads nothing unbounded: ``model.json`` and the tensor file are read
with byte limits, the vocabulary's sizes are checked before any tensor is
built, and each array's shape and type are read from its ``.npy`` header and
checked against those the vocabulary implies before the array is read.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import logging
import math
import os
import re
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import numpy as np
import torch

from groundlang.interrupt import deferred_interrupts
from groundlang.logic import storage

__all__ = ["FORMAT", "FORMAT_VERSION", "ModelFormatError", "check_model_destination", "check_parameter_bound",
           "write_model", "read_model", "signed"]

FORMAT = "groundlang-model"
FORMAT_VERSION = 16  # 2: mention and arity globals; 3: transitive prepositions, spatial PF tokens; 4: rooms in the mention model; 5: alignment per lifted task; 6: last-phrase keys; 7: alignment and arity tables per lifted task, not per token; 8: arity per clause; 9: alignment tables span the roles a task offers (vocabulary task_roles), only referring phrases name objects; 10: verbs of negated clauses are frame words; 11: the start room role (other:start); 12: "|last" passes over verb-attached "from" and "with" phrases; 13: the words added to the lexicon (``lexicon``), multiword prepositions joined into one token; 14: content-named tensor file, palettes recorded; 15: model.json records the hash of its own fields (content_sha256); 16: end habits (end_habits)
log = logging.getLogger(__name__)
T = TypeVar("T")

MODEL_JSON = "model.json"
# The tensor file; plain "globals.npz" is its name before format 13, removed by the next save.
_TENSOR_FILE = re.compile(r"globals(-[0-9a-f]{16})?\.npz")
# An interrupted save's temporary files (storage.atomic_path names them ".NAME.HEX.tmp").
_TEMPORARY = re.compile(r"\.(model\.json|globals-[0-9a-f]{16}\.npz)\.[0-9a-f]{16}\.tmp")
# A model of the crowd corpus has a 60 KB model.json and 1 MB of tensors; these bound what a crafted
# file can make the loader read or build (float32 elements of all globals together).
MAX_JSON_BYTES = 32 * 2**20
MAX_GLOBAL_ELEMENTS = 20_000_000


class ModelFormatError(ValueError):
    """A model directory that is missing, corrupt, foreign or from another format version."""


def check_model_destination(directory: str | Path, option: str = "") -> Path:
    """``directory`` as a place to write a model, refused if writing there would mix the model with other
    files or overwrite a file that is not a groundlang model's: it must be new, empty, or hold only a model
    (of any format version: saving replaces it). ``train -o model`` run at the repository root would
    otherwise have written into the ``model/`` source package. Missing folders are created when saving;
    the nearest existing one must take a file. ``groundlang train`` asks before it trains; ``option``
    ("-o") starts its messages."""
    directory = Path(directory)
    where = f"{option} {directory}".strip()
    try:
        storage.check_folder(directory, where)
    except ValueError as exc:
        raise ModelFormatError(f"{exc}; a model is written to a folder") from None
    storage.check_writable(directory, MODEL_JSON, where)  # /proc/m, a read-only mount: now, not after training
    # Inside another model's folder, the new one would be a stray file of that model's, which refuses its next save.
    owner = next((p for p in directory.resolve().parents if (p / MODEL_JSON).is_file()), None)
    if owner is not None:
        raise ModelFormatError(f"{where}: inside the folder of the model in {owner}; write the model to a folder "
                               "of its own")
    if not directory.is_dir():
        return directory
    others = sorted(p.name for p in directory.iterdir() if p.name != MODEL_JSON
                    and not _TENSOR_FILE.fullmatch(p.name) and not p.name.startswith("."))
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


# The field of model.json that holds the hash of all its others: damage to the words or settings a
# model is read with (a flipped byte, a line lost) is refused like damage to its tensors.
CONTENT_HASH = "content_sha256"


def _content_digest(meta: dict) -> str:
    rest = {k: v for k, v in meta.items() if k != CONTENT_HASH}
    return hashlib.sha256(json.dumps(rest, sort_keys=True, separators=(",", ":")).encode("utf-8")).hexdigest()


def signed(meta: dict) -> dict:
    """``meta`` (a model.json's fields) with the hash of its fields recorded: what a program that rewrites
    a model.json on purpose writes back, so that it loads (its values are still checked as read)."""
    return {**meta, CONTENT_HASH: _content_digest(meta)}


def write_model(state: dict, directory: str | Path, replacing: str | None = None) -> tuple[Path, str]:
    """Write a learner's ``state_dict()`` to ``directory`` (created if needed; see
    :func:`check_model_destination`); returns the directory and the written model's content hash.
    ``replacing``: the content hash of the model the learner was read from there; when the folder now holds
    another (a run saved over it meanwhile), nothing is written (ValueError), so that an update of the
    older model does not silently replace the newer."""
    directory = check_model_destination(directory)
    arrays = {k: v.detach().cpu().numpy() for k, v in state["globals"].items()}
    # The loader refuses a tensor that is not finite: such a model is never written, so that a fit or an
    # update (`follow --learn`) that went wrong leaves the model there as it was.
    bad = next((k for k, a in arrays.items() if a.dtype.kind == "f" and not np.isfinite(a).all()), None)
    if bad is not None:
        raise ValueError(f"{directory}: not written: the learned {bad} holds values that are not finite "
                         "(the model there, if any, is unchanged)")
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    tensors = buffer.getvalue()
    digest = hashlib.sha256(tensors).hexdigest()
    tensor_name = f"globals-{digest[:16]}.npz"
    meta = signed({
        "format": FORMAT,
        "version": FORMAT_VERSION,
        **{k: v for k, v in state.items() if k != "globals"},
        "globals_file": tensor_name,
        "globals_sha256": digest,
    })
    meta_bytes = json.dumps(meta, indent=1).encode("utf-8")
    if len(meta_bytes) > MAX_JSON_BYTES:  # what the loader would refuse is not written over a model it reads
        raise ValueError(f"{directory}: not written: its model.json would be {len(meta_bytes):,} bytes, more than "
                         f"the {MAX_JSON_BYTES:,} a model is read with (the words of --lexicon files and the "
                         "programs of --library files are saved in it); the model there, if any, is unchanged")
    # Interrupts are held back so that the clean-up after the commit is not skipped; a kill -9 may still
    # land anywhere, and leaves the old model or the new one, plus files the next save removes.
    directory.mkdir(parents=True, exist_ok=True)  # to be locked
    with folder_lock(directory, exclusive=True), deferred_interrupts():
        if replacing is not None and (now := _content_hash_there(directory)) not in (None, replacing):
            raise ValueError(f"{directory}: not written: the model there changed after this learner read or wrote it "
                             f"(another run saved over it, content {now[:12]}); it is left as it is: load it again, "
                             "or save to another folder")
        storage.write_atomically(directory / tensor_name, tensors, follow=False)
        # The folder is synced after each rename: after a power cut, model.json must not name tensors whose
        # rename was lost, nor the old tensors be gone while the old model.json is back.
        _sync_folder(directory)
        storage.write_atomically(directory / MODEL_JSON, meta_bytes, follow=False)  # the commit
        _sync_folder(directory)
        _remove_leftovers(directory, keep=tensor_name)
    return directory, meta[CONTENT_HASH]


def _content_hash_there(directory: Path) -> str | None:
    """The content hash the model.json in ``directory`` records; None where there is none to read (no
    model, or one this version cannot read: check_model_destination has said whether it may be replaced)."""
    try:
        return _read_json(directory, any_version=True).get(CONTENT_HASH)
    except (ModelFormatError, OSError):
        return None


@contextlib.contextmanager
def folder_lock(directory: Path, exclusive: bool):
    """A save holds its model folder alone, a load shares it with other loads. Without it, of two saves
    into one folder at once, one's clean-up could remove the tensor file the other's model.json is about
    to name (both would say they saved; the model would not load), and a load could read a model.json
    whose tensors a save has just replaced. An advisory ``flock`` on the folder itself, so no lock file
    is left behind; where the platform has none, nothing is locked."""
    try:
        import fcntl
    except ImportError:  # not POSIX
        yield
        return
    fd = os.open(directory, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
        yield
    finally:
        os.close(fd)  # and with it the lock


def _sync_folder(directory: Path) -> None:
    fd = os.open(directory, os.O_RDONLY)
    try:
        os.fsync(fd)
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror or str(exc), str(directory)) from exc
    finally:
        os.close(fd)


def _remove_leftovers(directory: Path, keep: str) -> None:
    """Remove tensor files other than ``keep`` and temporary files of interrupted saves (best effort:
    a file that cannot be removed is left, and ignored by the next load)."""
    for path in directory.iterdir():
        if path.name != keep and (_TENSOR_FILE.fullmatch(path.name) or _TEMPORARY.fullmatch(path.name)):
            try:
                path.unlink()
            except OSError as exc:
                log.warning("%s: left behind (%s)", path, exc.strerror or exc)


def _read_json(directory: Path, any_version: bool = False) -> dict:
    """The model's metadata; ModelFormatError unless a groundlang model of this format version
    (``any_version``: of any, as a destination to save over)."""
    path = directory / MODEL_JSON
    if not directory.is_dir():
        raise ModelFormatError(f"{directory}: not a model directory (it does not exist or is not a folder)")
    if not path.exists():  # anything else there (a FIFO, a folder) is refused by kind when read
        raise ModelFormatError(f"{directory}: no {MODEL_JSON}; this is not a groundlang model directory")
    try:
        meta = json.loads(storage.read_limited(path, MAX_JSON_BYTES, "a model's model.json").decode("utf-8"))
    except storage.FileRefused as exc:
        raise ModelFormatError(str(exc)) from None
    except IsADirectoryError:  # the OS names no file: an API caller saw "[Errno 21] Is a directory"
        raise ModelFormatError(f"{path}: a folder, not a regular file; expected a model's {MODEL_JSON}") from None
    except (ValueError, RecursionError) as exc:  # JSONDecodeError, UnicodeDecodeError, an integer of 4,300+ digits
        raise ModelFormatError(f"{path}: not valid JSON ({exc})") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise ModelFormatError(f"{path}: not a groundlang model (format field is not {FORMAT!r})")
    if not any_version and meta.get("version") != FORMAT_VERSION:
        version = meta.get("version")
        given = ("no model format version" if version is None else f"model format version {version!r}"
                 + ("" if isinstance(version, int) else f" (a {type(version).__name__}, not a number)"))
        raise ModelFormatError(
            f"{path}: {given}, this groundlang reads version {FORMAT_VERSION}; "
            "train the model again with `groundlang train`"
        )
    if not any_version and meta.get(CONTENT_HASH) != _content_digest(meta):
        raise ModelFormatError(f"{path}: contents do not match the hash it records ({CONTENT_HASH}): damaged, or "
                               "edited by hand; save the model again, or write it with groundlang.model_io.signed")
    return meta


def read_model(directory: str | Path, from_state_dict: Callable[[dict], T]) -> T:
    """Read a model written by :func:`write_model`: ``from_state_dict`` (``Learner.from_state_dict``) builds
    the learner from ``model.json``'s fields, and its ``globals`` are then read from the tensor file, each
    checked against the shape the learner's vocabulary implies before it is read. Raises ModelFormatError
    on anything amiss."""
    directory = Path(directory)
    if not directory.is_dir():  # said by _read_json; a FIFO must not be opened to be locked
        return _read_model(directory, from_state_dict)
    with folder_lock(directory, exclusive=False):
        return _read_model(directory, from_state_dict)


def _read_model(directory: Path, from_state_dict: Callable[[dict], T]) -> T:
    meta = _read_json(directory)
    try:
        fields = {k: v for k, v in meta.items()
                  if k not in ("format", "version", "globals_file", "globals_sha256", CONTENT_HASH)}
        learner = from_state_dict(fields, where=f"{directory / MODEL_JSON}")
        # where it was read from, and which model that was: a save back there replaces it only if it is still there
        learner.models_seen[directory.resolve()] = meta[CONTENT_HASH]
        tensor_name = meta["globals_file"]
        if not isinstance(tensor_name, str) or not _TENSOR_FILE.fullmatch(tensor_name):
            raise ValueError(f"globals_file is {tensor_name!r}; expected globals-<16 hex digits>.npz")
        expected = _expected_globals(learner)
    except (KeyError, TypeError, AttributeError, ValueError, RecursionError, RuntimeError) as exc:
        raise ModelFormatError(f"{directory}: model files are incomplete or corrupt ({_reason(exc)})") from None
    tensor_path = directory / tensor_name
    if not tensor_path.exists():
        raise ModelFormatError(f"{tensor_path}: the model's tensor file is missing ({MODEL_JSON} names it)")
    # What np.savez writes for these arrays: each one's data and header, plus the archive's directories.
    limit = sum(8 * math.prod(t.shape) + 1024 for t, _ in expected.values()) + 4096
    try:
        data = storage.read_limited(tensor_path, limit, "the tensors of a model of this vocabulary")
    except storage.FileRefused as exc:
        raise ModelFormatError(str(exc)) from None
    except IsADirectoryError:
        raise ModelFormatError(f"{tensor_path}: a folder, not a regular file; expected the model's tensors") from None
    if hashlib.sha256(data).hexdigest() != meta.get("globals_sha256"):
        raise ModelFormatError(
            f"{tensor_path}: contents do not match the hash recorded in {MODEL_JSON} (truncated or swapped?)"
        )
    learner.globals = _read_globals(data, expected, tensor_path, learner.lm.name)
    return learner


def _reason(exc: BaseException) -> str:
    if isinstance(exc, KeyError):
        return f"no field {exc.args[0]!r}"
    return " ".join(f"{type(exc).__name__}: {exc}".split())[:300]


def check_parameter_bound(vocab) -> dict:
    """The sizes of the globals of a model of ``vocab`` (``generative.global_sizes``); ValueError when they
    could hold more than ``MAX_GLOBAL_ELEMENTS`` parameters. Loading asks it of a saved vocabulary before
    anything is built (a crafted one of 10^5 words made the prior tables alone take 10 GB); training asks it
    of the corpus's before the fit, so that no model is fitted, or written, that could not be loaded."""
    from groundlang.model.generative import global_sizes

    sizes = global_sizes(vocab)
    tokens, words, roles = sizes["num_tokens"], sizes["num_words"], sizes["num_roles"]
    tasks, preps = sizes["num_tasks"], sizes["num_preps"]
    # phi [tokens, words] is the largest table; alignment tables are at most [tasks * preps, roles].
    bound = tokens * words + (max(tasks, 1) * max(preps, 1) + 64) * max(roles, 1) + 64 * (tasks + preps + 64)
    if bound > MAX_GLOBAL_ELEMENTS:
        raise ValueError(f"the vocabulary ({tokens} tokens, {words} words, {roles} roles, {preps} prepositions, "
                         f"{tasks} tasks) implies up to {bound:,} parameters; at most {MAX_GLOBAL_ELEMENTS:,} "
                         "are loaded")
    return sizes


def _expected_globals(learner) -> dict:
    """The globals a model of this vocabulary and language model has, each as ``(template, simplex)``: the
    template gives its shape and dtype, sized before anything is built (:func:`check_parameter_bound`), and
    ``simplex`` says whether its prior draws rows that are distributions (a Dirichlet's), which a saved
    table must then be too."""
    import pyro.poutine
    from torch.distributions import constraints

    sizes = check_parameter_bound(learner.vocab)
    with pyro.poutine.block():
        trace = pyro.poutine.trace(learner.lm.sample_globals).get_trace(**sizes)
    templates = trace.nodes["_RETURN"]["value"]
    supports = {name: site["fn"].support for name, site in trace.nodes.items()
                if site["type"] == "sample" and not site["is_observed"] and name in templates}
    return {name: (t, supports.get(name) is constraints.simplex) for name, t in templates.items()}


# How far a saved row of a distribution may sum from one: float32 sums of a few thousand entries stray by
# about 1e-5; a table edited by hand or damaged strays by far more.
_SIMPLEX_TOLERANCE = 1e-3


def _check_distributions(name: str, tensor: torch.Tensor) -> None:
    if bool((tensor < 0).any()):
        raise ValueError(f"{name} holds negative probabilities; each row must be a distribution")
    sums = tensor.double().reshape(-1, tensor.shape[-1]).sum(-1)
    astray = ((sums - 1.0).abs() > _SIMPLEX_TOLERANCE).nonzero()
    if len(astray):
        row = int(astray[0])
        raise ValueError(f"{name}: row {row} sums to {float(sums[row]):.6g}; each row must be a distribution (sum 1)")


def _read_globals(data: bytes, expected: dict, tensor_path: Path, lm_name: str) -> dict:
    """The tensors of an ``.npz``, each refused from its header (name, shape, dtype) before it is read."""
    try:
        if not data.startswith(b"PK\x03\x04"):
            # np.load would guess "pickled data" for any non-archive and suggest loading it unsafely.
            raise ValueError(f"not an .npz archive (it starts with {data[:8]!r}); expected the tensors groundlang saved")
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            names = sorted(n.removesuffix(".npy") for n in archive.namelist())
            if names != sorted(expected) or len(set(archive.namelist())) != len(expected):
                raise ValueError(f"holds {names}; language model {lm_name} needs {sorted(expected)}")
            out = {}
            for name, (template, simplex) in expected.items():
                with archive.open(f"{name}.npy") as member:
                    version = np.lib.format.read_magic(member)
                    header = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                              else np.lib.format.read_array_header_2_0)
                    shape, fortran, dtype = header(member)
                    if tuple(shape) != tuple(template.shape) or dtype.kind != "f" or dtype.itemsize > 8 or fortran:
                        raise ValueError(f"{name} is {dtype} {tuple(shape)}; expected finite floats of shape "
                                         f"{tuple(template.shape)} for this vocabulary")
                with archive.open(f"{name}.npy") as member:
                    array = np.lib.format.read_array(member, allow_pickle=False)
                tensor = torch.from_numpy(np.array(array))
                if not bool(torch.isfinite(tensor).all()):
                    raise ValueError(f"{name} is {array.dtype} {tuple(array.shape)} with values that are not "
                                     "finite; expected finite floats")
                if simplex:
                    _check_distributions(name, tensor)
                out[name] = tensor.to(template.dtype)
            return out
    except (ValueError, EOFError, zipfile.BadZipFile, OSError, NotImplementedError, RuntimeError) as exc:
        said = exc if isinstance(exc, ValueError) else f"model files are incomplete or corrupt ({_reason(exc)})"
        raise ModelFormatError(f"{tensor_path}: {said}") from None
