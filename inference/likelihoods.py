"""Behaviour likelihood tables: each demonstration's log-likelihood under each candidate grounded goal.

``behaviour_likelihood_table(instances, candidates)`` returns, per instance,
an array ``[len(candidates[i])]`` of ``log P(demonstration | goal)`` under the
Boltzmann policy of the task "make the goal hold, then terminate"
(:func:`groundlang.inference.planning.solve_task`). The table is ragged (one
array per instance, because instances have different candidate lists);
:func:`pad_table` turns it into ``[instances, max candidates]`` with ``-inf``
padding and a mask, the shape Pyro's ``Vindex`` lookups want.

Work is shared: the state space is enumerated once per distinct initial
state, the task is solved once per (initial state, goal), and every
demonstration starting there is scored against that one solution. (The
commands-to-tasks corpus has 240 instances but 6 demonstrations.) Where the
whole world is too large, each demonstration's goals are scored by
:func:`groundlang.inference.stepwise.approximate_likelihoods`: each goal in the
relevance abstraction of the toys it names and the demonstration moves, or
stepwise over the placements the demonstration visits, all solved together.

Cache: one small JSON file per (layout, initial state, goal, demonstration,
settings), named by the sha256 of a canonical JSON description of those, in
``cache_dir/behaviour/ab/abcdef....json``. The directory is the caller's
``cache_dir``, else ``$GROUNDLANG_CACHE``, else ``.groundlang-cache`` in the
working directory; ``cache_dir=False`` turns caching off. Files are written
atomically (temporary file + ``os.replace``), so an interrupted run leaves
only whole entries. They are not fsynced: a power cut may lose the latest
ones, which only costs recomputing them, while an fsync per entry would
slow every run.

Each entry records a checksum over its key and the exact text of its value,
so a flipped bit in the number (a sign, a digit) is detected rather than read
as another likelihood. An entry that is damaged (checksum, key or value
wrong, not JSON, not a regular file or too large) is recomputed and
rewritten; one warning per table says how many there were. The cache is
only an optimisation: a cache folder that cannot be written (read-only,
full) gives one warning and the run goes on without writing to it.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import logging
import math
import os
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from groundlang.inference.layout_rows import layout_rows
from groundlang.inference.planning import TaskSettings
from groundlang.logic.atoms import Atom, parse_atom
from groundlang.logic.storage import FileRefused, check_folder, read_limited, write_atomically
from groundlang.model.state_search import StateSpaceError

__all__ = ["CACHE_FOLDERS", "CACHE_VERSION", "DamagedEntry", "behaviour_likelihood_table", "cache_directory",
           "check_cache_dir", "environment_cache", "entry_key", "layout_description",
           "pad_table", "read_entry_json"]

# The cache folder's subfolders of entries: behaviour likelihoods (here), end-state evidence of (start, end)
# pairs (inference.evidence_cache) and readings of training commands (inference.parse_cache).
BEHAVIOUR_FOLDER, EVIDENCE_FOLDER, PARSES_FOLDER = "behaviour", "evidence", "parses"
CACHE_FOLDERS = (BEHAVIOUR_FOLDER, EVIDENCE_FOLDER, PARSES_FOLDER)

logger = logging.getLogger(__name__)

# Bump when the meaning of a cached number changes (planner or reward semantics). 2: entries carry a checksum.
CACHE_VERSION = 2
# An entry is about 200 bytes; anything far larger is not one (a FIFO or /dev/zero is refused by kind).
MAX_ENTRY_BYTES = 64 * 1024


def environment_cache() -> str | None:
    """``$GROUNDLANG_CACHE``, or None where it is unset, empty or blank: a blank value is no folder a person
    names (it made a folder " " in the working folder), and an empty one has always meant unset."""
    value = os.environ.get("GROUNDLANG_CACHE", "")
    return value if value.strip() else None


def check_cache_dir(cache_dir, where: str) -> None:
    """TypeError unless ``cache_dir`` is a folder's path, False (no cache) or None (the default); ValueError for
    an empty or blank path, which would put the cache in the working folder. ``where`` names the argument."""
    if cache_dir is None or cache_dir is False:
        return
    if not isinstance(cache_dir, (str, os.PathLike)):
        raise TypeError(f"{where} must be a folder's path (a str or os.PathLike), False for no cache or None for "
                        f"$GROUNDLANG_CACHE or ./.groundlang-cache, got {type(cache_dir).__name__}")
    if not os.fsdecode(cache_dir).strip():
        raise ValueError(f"{where} is empty or blank; name a folder (or None for $GROUNDLANG_CACHE or ./.groundlang-cache)")


def cache_directory(cache_dir: str | os.PathLike | None = None) -> Path:
    """The cache root: ``cache_dir``, else ``$GROUNDLANG_CACHE`` (:func:`environment_cache`), else
    ``./.groundlang-cache``; ValueError when it, or a folder above it, is a file, or ``cache_dir`` is empty."""
    check_cache_dir(cache_dir, "cache_dir")
    if cache_dir is not None:
        root, what = Path(cache_dir), "the cache folder"
    elif env := environment_cache():
        root, what = Path(env), "GROUNDLANG_CACHE"
    else:
        root, what = Path.cwd() / ".groundlang-cache", "the cache folder"
    # A file there made every entry read "unreadable", then the first write failed.
    return check_folder(root, f"{what} {root}")


def layout_description(layout) -> dict:
    """The layout as cache keys describe it: everything its states and PFs depend on but the palette's values."""
    return {
        "rooms": [[r.colour, r.left, r.top, r.right, r.bottom] for r in layout.rooms],
        "doors": [[d.left, d.top, d.right, d.bottom] for d in layout.doors],
        "toys": [list(t) for t in layout.toy_attributes],
        "palette": layout.palette.name,
        **({"added": [list(t) for t in layout.added_attributes]} if layout.added_attributes else {}),
    }


def _goal(goal) -> tuple[Atom, ...]:
    atoms = (goal,) if isinstance(goal, (Atom, str)) else tuple(goal)
    return tuple(parse_atom(a) if isinstance(a, str) else a for a in atoms)


def entry_key(initial_state, goal: Sequence[Atom], actions: Sequence[int], settings: TaskSettings,
              pfs: str | None = None, abstraction: bool = False) -> str:
    """sha256 (hex) of the canonical description of one table entry; ``pfs``: a digest of PF rules
    other than the package's (what the goal's PFs mean); ``abstraction``: computed in the relevance
    abstraction rather than the exact space (a different number)."""
    description = {
        "version": CACHE_VERSION,
        "layout": layout_description(initial_state.layout),
        "initial": initial_state.positions.tolist(),
        "goal": sorted(str(a) for a in goal),
        # The dynamics are deterministic: the initial state and the actions fix the states.
        "actions": [int(a) for a in actions],
        "settings": settings.as_dict(),
    }
    if pfs is not None:
        description["pfs"] = pfs
    if abstraction:  # absent otherwise: entries of the exact space keep their keys
        description["space"] = "relevance abstraction"
    text = json.dumps(description, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def _entry_path(root: Path, key: str) -> Path:
    return root / BEHAVIOUR_FOLDER / key[:2] / f"{key}.json"


# A writer's temporary file lives for the moment of one write; one this old was left by a killed process.
STALE_TEMPORARY_SECONDS = 3600


def remove_stale_temporaries(folder: Path, done: set) -> None:
    """Remove from ``folder`` (an entry's two-letter folder) the temporary files (``.<entry>.<hex>.tmp``)
    of writes a ``kill -9`` cut short, once per folder per run (``done`` holds the folders seen), so that
    they do not pile up; best effort, and never a file another writer may still be renaming."""
    if folder in done:
        return
    done.add(folder)
    now = time.time()
    try:
        for path in folder.glob(".*.tmp"):
            with contextlib.suppress(OSError):
                if now - path.lstat().st_mtime > STALE_TEMPORARY_SECONDS:
                    path.unlink()
    except OSError:
        pass


def only_the_entry_lost(exc: OSError, path: Path, kind_folder: Path) -> bool:
    """Whether a failed write of the entry ``path`` loses that entry (and its two-letter folder's) alone:
    something else stands at its path or at its folder's (a folder, a file), or that folder alone cannot be
    written. Not when the kind's folder (``behaviour``, ``evidence``) is not a writable folder, nor for any
    other error (a full disk, a read-only cache): then nothing more can be written this run."""
    if not kind_folder.is_dir():
        return False
    if exc.errno in (errno.EISDIR, errno.ENOTDIR, errno.EEXIST):
        return True
    return exc.errno in (errno.EACCES, errno.EPERM) and os.access(kind_folder, os.W_OK | os.X_OK) \
        and path.parent != kind_folder


def _checksum(key: str, value_text: str) -> str:
    """Over the key and the value's text: a sign or digit changed in the file no longer matches."""
    return hashlib.sha256(f"{key} {value_text}".encode()).hexdigest()[:16]


class DamagedEntry(ValueError):
    """A cache entry that exists but cannot be trusted (the message says why)."""


def read_entry_json(path: Path, max_bytes: int, what: str) -> dict | None:
    """A cache entry's JSON object, or None when the file is absent; DamagedEntry when it cannot be read
    or is not a JSON object (truncated, overwritten, not UTF-8)."""
    try:
        raw = read_limited(path, max_bytes, what)
    except FileNotFoundError:
        return None
    except (OSError, FileRefused) as exc:
        raise DamagedEntry(f"unreadable: {exc.strerror if isinstance(exc, OSError) and exc.strerror else exc}") from None
    try:
        data = json.loads(raw.decode("utf-8"))
    except (ValueError, RecursionError):  # JSONDecodeError, UnicodeDecodeError, an integer of 4,300+ digits
        raise DamagedEntry("not JSON (truncated or overwritten)") from None
    if not isinstance(data, dict):
        raise DamagedEntry("not a cache entry (no key)")
    return data


def _read_entry(path: Path, key: str) -> float | None:
    """The cached value, or None when absent; DamagedEntry (saying why) when present but not trustworthy."""
    data = read_entry_json(path, MAX_ENTRY_BYTES, "a behaviour cache entry")
    if data is None:
        return None
    try:
        if data.get("key") != key:
            raise ValueError(f"records key {str(data.get('key'))[:12]}..., expected {key[:12]}...")
        value = data["log_likelihood"]
        # A float's repr round-trips exactly through JSON, so the checksum of the value read matches that
        # of the value written unless a character of it changed.
        if not isinstance(value, float) or data.get("checksum") != _checksum(key, repr(value)):
            raise ValueError("checksum does not match the value")
        if math.isnan(value) or value > 0:
            raise ValueError(f"holds {value}; a log-likelihood is at most 0")
        return value
    except (ValueError, TypeError, KeyError, AttributeError) as exc:
        raise DamagedEntry(str(exc)) from None


def _write_entry(path: Path, key: str, value: float, goal: Sequence[Atom]) -> None:
    value = float(value)
    entry = {"key": key, "goal": " ".join(str(a) for a in goal), "log_likelihood": value,
             "checksum": _checksum(key, repr(value))}
    # A lost entry is recomputed: no fsync per entry. An entry is ours: a FIFO planted there is replaced.
    write_atomically(path, json.dumps(entry), durable=False, follow=False)


def behaviour_likelihood_table(
    instances: Sequence,
    candidates: Sequence[Sequence],
    settings: TaskSettings = TaskSettings(),
    cache_dir: str | os.PathLike | None | bool = None,
    progress: bool = False,
    library=None,
    method: str = "auto",
) -> list[np.ndarray]:
    """Log-likelihood of each instance's demonstration under each of its candidate goals.

    Args:
        instances: objects with ``initial_state`` (a model.world State), ``states``
            (the demonstration's States, first = initial) and ``actions`` (Actions),
            e.g. ``groundlang.corpus.Instance``.
        candidates: per instance, a list of goals; a goal is a conjunction given as a
            tuple of Atoms (or atom strings, or a single Atom).
        settings: reward and solver settings (part of the cache key).
        cache_dir: cache root (see module docstring); False for no cache.
        library: the TaskLibrary whose PF rules say what the goals mean (default: the package's PFs);
            a library with PF rules of its own keys its entries by their text.
        method: "auto" (the exact space where the whole world fits ``max_states``, else the approximation
            of inference/stepwise.py; logged by model.relevance), or "exact" / "abstraction" to force one.
    Returns a list of float64 arrays, ``result[i][k]`` for candidate ``k`` of instance ``i``.
    Raises ValueError when the lists differ in length or a goal names an unknown object.
    """
    from groundlang.model.pf_tables import pf_tables, program_digest, tabulation_program
    from groundlang.model.relevance import exact_fits

    if method not in ("auto", "exact", "abstraction"):
        raise ValueError(f"method {method!r}: expected auto, exact or abstraction")
    if len(candidates) != len(instances):
        raise ValueError(f"{len(instances)} instances but {len(candidates)} candidate lists")
    from groundlang.inference.cache_entries import kind_root  # it reads this module's entries

    root = None if cache_dir is False else kind_root(cache_directory(cache_dir), BEHAVIOUR_FOLDER, logger)
    cleaned: set = set()  # entry folders this run has cleared of a killed writer's temporary files
    goals = [[_goal(g) for g in row] for row in candidates]
    program = library.tabulation_program if library is not None else tabulation_program(())
    pfs = program_digest(program)
    table = [np.full(len(row), np.nan) for row in goals]
    keys: list[list[str]] = []
    # (initial state) -> {goal: [(instance, candidate)]} for the entries still to compute.
    todo: dict = {}
    hits = 0
    damaged: dict[Path, str] = {}  # path -> why; an entry shared by many instances is counted once
    for i, (inst, row) in enumerate(zip(instances, goals)):
        actions = [int(a) for a in inst.actions]
        abstraction = method == "abstraction" or (method == "auto" and not exact_fits(inst.initial_state))
        keys.append([entry_key(inst.initial_state, g, actions, settings, pfs, abstraction) for g in row])
        for k, (g, key) in enumerate(zip(row, keys[i])):
            value = None
            if root is not None:
                path = _entry_path(root, key)
                try:
                    value = None if path in damaged else _read_entry(path, key)
                except DamagedEntry as exc:
                    damaged[path] = str(exc)
            if value is None:
                todo.setdefault(inst.initial_state, {}).setdefault(g, []).append((i, k))
            else:
                table[i][k] = value
                hits += 1
    if damaged:
        first, why = next(iter(damaged.items()))
        logger.warning("behaviour cache: %d corrupt entr%s recomputed (first: %s: %s)",
                       len(damaged), "y" if len(damaged) == 1 else "ies", first, why)
    solves = sum(len(by_goal) for by_goal in todo.values())
    logger.info("behaviour likelihoods: %d cached, %d to compute with %d solves in %d state spaces (each solve "
                "one cache entry)", hits, sum(len(v) for by_goal in todo.values() for v in by_goal.values()), solves,
                len(todo))
    bar = None
    if progress and solves:
        from tqdm import tqdm

        bar = tqdm(total=solves, desc="behaviour likelihoods", unit="solve")
    for initial, by_goal in todo.items():
        tables = pf_tables(initial.layout, program, *(() if library is None else (library.time_limit,)))
        try:
            for goal, entries in layout_rows(initial, by_goal, instances, tables, settings, method):
                for (i, k), value in entries:
                    table[i][k] = value
                    root = _store(root, keys[i][k], value, goal, cleaned)
                if bar is not None:
                    bar.update(1)
        except StateSpaceError as exc:  # a layout too large to key or plan in: the file of a demonstration in it
            if bar is not None:
                bar.close()
            where = getattr(instances[next(iter(by_goal.values()))[0][0]], "path", None)
            raise exc if where is None else type(exc)(f"{where}: {exc}") from None
    if bar is not None:
        bar.close()
    return table


def _store(root, key: str, value: float, goal, cleaned: set) -> Path | None:
    """Write one entry; the root, or None once the cache cannot be written (warned once)."""
    if root is None:
        return None
    try:
        path = _entry_path(root, key)
        remove_stale_temporaries(path.parent, cleaned)
        _write_entry(path, key, value, goal)
        return root
    except OSError as exc:
        if only_the_entry_lost(exc, _entry_path(root, key), Path(root) / BEHAVIOUR_FOLDER):
            return root  # counted as damaged when read: only it is lost
        from groundlang.inference.cache_entries import warn_unwritable  # it reads this module's entries

        warn_unwritable(logger, "behaviour", root, exc)
        return None


def pad_table(rows: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Ragged rows -> ``(table [N, K] float64 padded with -inf, mask [N, K] bool, True = real entry)``."""
    width = max((len(r) for r in rows), default=0)
    table = np.full((len(rows), width), -np.inf)
    mask = np.zeros((len(rows), width), dtype=bool)
    for i, r in enumerate(rows):
        table[i, : len(r)] = r
        mask[i, : len(r)] = True
    return table, mask
