"""Graceful interruption: SIGTERM behaves like Ctrl-C, and the CLI says what an interrupted run kept.

Every file groundlang writes goes through a temporary file and a rename, so
an interruption can only lose the piece of work in progress. Four helpers:

- :func:`terminate_as_interrupt` (a context manager used by ``cli.main``)
  makes SIGTERM raise ``KeyboardInterrupt`` as SIGINT does, and restores
  the previous handler on exit (main thread only; elsewhere it does nothing);
- :func:`deferred_interrupts` holds SIGINT/SIGTERM back while a group of
  renames that belong together runs (a model's tensors and its JSON), then
  delivers the interrupt;
- :func:`close_progress_bars` ends the progress bars a run left open;
- :func:`what_was_kept` describes, after an interruption, the outputs named
  by a command's arguments (model directory, result file, picture) and the
  cache entries (behaviour likelihoods, end-state evidence, readings) written since the command started.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

__all__ = ["terminate_as_interrupt", "deferred_interrupts", "interrupts_ignored", "HeldInterrupt", "what_was_kept",
           "close_progress_bars"]


class HeldInterrupt(KeyboardInterrupt):
    """An interruption :func:`deferred_interrupts` held until its block (a save) had finished."""

_SIGNALS = tuple(s for s in (signal.SIGINT, getattr(signal, "SIGTERM", None)) if s is not None)


# Non-empty while a deferred_interrupts block runs in the main thread.
_deferring: list[bool] = []


def _raise_interrupt(signum, frame) -> None:
    raise KeyboardInterrupt(signal.Signals(signum).name)


@contextlib.contextmanager
def terminate_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM raises KeyboardInterrupt (like Ctrl-C)."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "SIGTERM"):
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@contextlib.contextmanager
def deferred_interrupts() -> Iterator[None]:
    """Hold SIGINT/SIGTERM until the block ends, then raise KeyboardInterrupt if one arrived.

    For a few renames that must all happen or none, or a temporary file that
    must not be left behind. Nested blocks defer to the outermost one. Main
    thread only; elsewhere, and for signals whose handler is not Python's,
    it does nothing.
    """
    if threading.current_thread() is not threading.main_thread() or _deferring:
        yield
        return
    received: list[int] = []
    previous = {}
    for sig in _SIGNALS:
        handler = signal.getsignal(sig)
        # Only take over signals that would raise in Python anyway; leave ignored/default ones alone.
        if callable(handler):
            previous[sig] = signal.signal(sig, lambda signum, frame: received.append(signum))
    _deferring.append(True)
    try:
        yield
    finally:
        _deferring.pop()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if received:  # also when the block failed (a save refused): the user asked to stop, and is told so
            raise HeldInterrupt(signal.Signals(received[0]).name)


@contextlib.contextmanager
def interrupts_ignored() -> Iterator[None]:
    """SIGINT ignored within the block (main thread only): the report of an interruption is made once, whole,
    however often Ctrl-C is pressed again while it counts the cache and prints (a second press had printed a
    second traceback from inside the first's report). SIGTERM keeps its handler: ``kill`` still ends a report
    that takes too long (a cache of millions of entries)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def close_progress_bars() -> None:
    """Close the tqdm bars an interruption left open, so that the report starts on a line of its own."""
    tqdm_module = sys.modules.get("tqdm")  # never import tqdm just for this
    for bar in list(getattr(getattr(tqdm_module, "tqdm", None), "_instances", ())):
        with contextlib.suppress(Exception):
            bar.close()


def _describe_output(path: Path, what: str, started: float, held: bool = False) -> str:
    stamp = path / "model.json" if path.is_dir() else path
    if not path.exists():
        return f"nothing written to {path}"
    if not stamp.exists():
        return f"{path} holds no complete {what}"
    if stamp.stat().st_mtime < started:
        return f"{path} left as it was (the previous complete {what})"
    if held:  # the signal came while it was being written, and waited for the write to finish
        return f"the {what} in {path} is this run's, written whole (the interruption came while it was saved)"
    return f"the {what} in {path} was complete before the interruption"


def cache_entry_count(args) -> int:
    """Whole cache entries now in the cache a command uses (0 without one), of every kind it keeps."""
    if getattr(args, "no_cache", False) is True:
        return 0
    given = getattr(args, "cache_dir", None)
    if isinstance(given, str) and not given.strip():  # the command refuses it by its option's name (cache_option),
        return 0                                      # not cache_directory by the API's "cache_dir"
    from groundlang.inference.likelihoods import CACHE_FOLDERS, cache_directory

    root = cache_directory(given)
    # Temporary files start with "."; only renamed, whole entries count.
    return sum(1 for name in CACHE_FOLDERS if (root / name).is_dir()
               for p in (root / name).glob("*/*.json") if not p.name.startswith("."))


# (argument name, what it holds); a command's arguments name its outputs.
_OUTPUTS = (("output", "output"), ("json", "result"), ("out", "picture"), ("plot", "picture"))  # plot: ablate's
# What ``-o/--output`` holds, per command.
_OUTPUT_KIND = {"train": "model", "discover": "task library"}


def what_was_kept(args, started: float, uses_cache: bool, cache_entries_before: int | None = 0,
                  held: bool = False) -> str:
    """One line saying what an interrupted command left behind.

    ``started`` is ``time.time()`` at the start; ``cache_entries_before`` is
    :func:`cache_entry_count` then (counting, not mtimes, tells which entries
    are new: a run that starts right after another must not claim its entries), None when the
    interrupt came before it was counted.
    """
    parts = []
    for attr, what in _OUTPUTS:
        value = getattr(args, attr, None)
        if isinstance(value, (str, Path)):
            if attr == "output":
                what = _OUTPUT_KIND.get(getattr(args, "command", None), what)
            parts.append(_describe_output(Path(value), what, started, held))
    if getattr(args, "learn", False) is True and isinstance(getattr(args, "model", None), (str, Path)):
        # follow --learn saves what it learned over its --model: an output as much as -o is
        parts.append(_describe_output(Path(args.model), "model", started, held))
    # Only when the cache's module was imported whole: an interrupt during its import (torch's takes seconds)
    # leaves torch half-initialised, and importing it again can crash the process in native code. A failed
    # import is not in sys.modules: no entry was written. Nor before the entries at the start were counted
    # (``cache_entries_before`` None): every entry would be taken for a new one.
    likelihoods = sys.modules.get("groundlang.inference.likelihoods")
    if (uses_cache and getattr(args, "no_cache", False) is not True and likelihoods is not None
            and cache_entries_before is not None):
        count = cache_entry_count(args) - cache_entries_before
        if count > 0:  # fewer than at the start: the cache was cleared meanwhile, and no count says what is new
            root = likelihoods.cache_directory(getattr(args, "cache_dir", None))
            entries = "entry is" if count == 1 else "entries are"
            parts.append(f"{count} new cache {entries} kept in {root} (behaviour likelihoods, end-state evidence "
                         "and readings; a rerun resumes from them)")
    return "; ".join(parts) or "no output files were due"
