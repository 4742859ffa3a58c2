"""One kind of entry of the cache folder (``evidence``, ``parses``): where an entry lives, how it is read
and written, and how damage is counted and said.

The folder is the behaviour likelihoods' (``inference.likelihoods``: ``cache_dir``, else
``$GROUNDLANG_CACHE``, else ``.groundlang-cache``); an entry is a JSON object in ``<kind>/ab/abcdef....json``
named by the sha256 of what it depends on. Entries are written atomically, not fsynced (a lost entry is
made again), and read with a size limit; a folder that cannot be written gives one warning, after which
the run reads it and writes nothing. A damaged entry is counted, made again and rewritten; :meth:`report`
gives one warning per run with how many and the first, and one info line of counts. Memory stays
bounded: counts and the first damaged entry, not a list of them.
"""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path

from groundlang.inference.likelihoods import (DamagedEntry, cache_directory, only_the_entry_lost, read_entry_json,
                                              remove_stale_temporaries)
from groundlang.logic.storage import write_atomically

__all__ = ["EntryFolder"]


# Cache roots said to be unwritable in this process: the behaviour, parse and evidence entries of one run share
# a root, and a read-only one had been said once for each.
_UNWRITABLE: set[Path] = set()


def warn_unwritable(logger: logging.Logger, kind: str, root, exc: OSError) -> None:
    """The warning that the cache ``root`` cannot be written, once a root and process (later kinds' at debug
    level); the run goes on without writing to it."""
    said = (f"cache {root} cannot be written ({exc.filename or root}: {exc.strerror or exc}); going on without "
            f"writing to it ({kind} entries first)")
    if Path(root) in _UNWRITABLE:
        logger.debug(said)
    else:
        _UNWRITABLE.add(Path(root))
        logger.warning(said)


def kind_root(root: Path | None, kind: str, logger: logging.Logger) -> Path | None:
    """``root``, or None with one warning where its ``kind`` folder is something else than a folder (a file
    there had been counted as every entry corrupt, one by one, and its entries were neither read nor written)."""
    if root is not None and os.path.lexists(root / kind) and not (root / kind).is_dir():
        logger.warning("cache %s: %s is not a folder; this run neither reads nor writes %s entries (move it away)",
                       root, root / kind, kind)
        return None
    return root


class EntryFolder:
    """The entries of one ``kind`` in the cache folder ``cache_dir`` (None: the default; False: none, when
    nothing is read or written). ``made`` names what is done to an entry that is not there or is
    damaged ("recomputed", "reparsed"); ``logger`` is the caller's."""

    def __init__(self, cache_dir: str | os.PathLike | None | bool, kind: str, made: str, logger: logging.Logger):
        self.root = None if cache_dir is False else kind_root(cache_directory(cache_dir), kind, logger)
        self.kind, self.made, self.logger = kind, made, logger
        self.new = made.removeprefix("re")  # what the count of entries made for the first time says
        self.hits = self.computed = self.damaged = 0
        self._writable = True  # until a write fails: a cache that cannot be written is still read
        self._first_damaged: tuple[Path, str] | None = None
        self._cleaned: set[Path] = set()  # entry folders cleared of a killed writer's temporary files

    def path(self, key: str) -> Path:
        return self.root / self.kind / key[:2] / f"{key}.json"

    def read(self, key: str, max_bytes: int, what: str, restore):
        """``restore(data)`` of the entry named ``key``, or None when there is none, the folder is off, or
        the entry is damaged (counted). ``restore`` raises ValueError, TypeError, KeyError, ArithmeticError
        (a number too large for a float) or DamagedEntry for an entry it cannot trust."""
        if self.root is None:
            return None
        path = self.path(key)
        try:
            data = read_entry_json(path, max_bytes, what)
            if data is None:
                return None
            if data.get("key") != key:
                raise DamagedEntry("records another key")
            found = restore(data)
        except DamagedEntry as exc:
            self._damaged(path, str(exc))
            return None
        except KeyError as exc:
            self._damaged(path, f"lacks its field {exc}")
            return None
        except (ValueError, TypeError, AttributeError, RecursionError, ArithmeticError) as exc:
            self._damaged(path, str(exc) or type(exc).__name__)
            return None
        self.hits += 1
        return found

    def _damaged(self, path: Path, why: str) -> None:
        self.damaged += 1
        self._first_damaged = self._first_damaged or (path, why)

    def write(self, key: str, entry: dict) -> None:
        """Write ``{"key": key, **entry}`` (nothing when the folder is off or could not be written)."""
        if self.root is None or not self._writable:
            return
        try:
            remove_stale_temporaries(self.path(key).parent, self._cleaned)
            write_atomically(self.path(key), json.dumps({"key": key, **entry}, separators=(",", ":")),
                             durable=False, follow=False)
        except OSError as exc:
            if only_the_entry_lost(exc, self.path(key), self.root / self.kind):
                return  # counted as damaged when read: only it is lost
            warn_unwritable(self.logger, self.kind, self.root, exc)
            self._writable = False

    def report(self, counted: str, hits: str = "from the cache") -> None:
        """One warning for damaged entries (how many, the first and why), one info line of counts:
        ``"<counted>: <n> <hits>, <n> computed"``."""
        if self.damaged:
            first, why = self._first_damaged
            self.logger.warning("%s cache: %d corrupt entr%s %s (first: %s: %s)", self.kind, self.damaged,
                                "y" if self.damaged == 1 else "ies", self.made, first, why)
        self.logger.info("%s: %d %s, %d %s", counted, self.hits, hits, self.computed, self.new)
