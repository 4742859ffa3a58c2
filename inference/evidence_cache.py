"""A disk cache of end-state evidence (:class:`~groundlang.inference.shared_meaning.LayoutEvidence`).

Scoring a (start, end) pair enumerates its states (or its relevance abstraction), measures distances
and tabulates a goal mask per candidate goal; the result is a few numbers per grounded task. They are
kept in the cache folder of the behaviour likelihoods (``inference.likelihoods``: ``cache_dir``, else
``$GROUNDLANG_CACHE``, else ``.groundlang-cache``), one JSON file per pair in
``evidence/ab/abcdef....json``, with the same guarantees:

- the name is the sha256 of everything the numbers depend on: the layout (rooms, doors, toys, the
  palette's name and values), the start and end positions, the text of every ASP source of the
  library (the package's included: the tasks, PFs and relations the goals are made of), the noise
  parameters, which space was searched (exact, or the abstraction moving which toys) and
  :data:`EVIDENCE_VERSION`, bumped when the meaning of a stored number changes;
- an entry records its key and a checksum over the key and the canonical text of its contents, so a
  changed digit, a truncated file or an entry copied under another name is detected: it is
  recomputed and rewritten, with one warning per run giving how many;
- entries are written atomically, not fsynced (a lost entry is recomputed), read with a size limit;
- a folder that cannot be written gives one warning, and the run goes on without writing.

Pairs repeat within a corpus (a demonstration shown to several workers), so the last
:data:`REMEMBERED` pieces of evidence are also kept in memory by key, read or computed once per run
and shared by reference, with the cache folder or without it. Memory stays bounded: that many entries,
one file read at a time, and counts and the first damaged entry rather than a list of them.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import weakref
from collections import OrderedDict

from groundlang.inference.end_habits import new_relations
from groundlang.inference.end_states import EndStateNoise
from groundlang.inference.cache_entries import EntryFolder
from groundlang.inference.likelihoods import EVIDENCE_FOLDER, layout_description
from groundlang.inference.shared_meaning import LayoutEvidence, evidence_space
from groundlang.logic.atoms import Atom
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.world import State

__all__ = ["EVIDENCE_VERSION", "EvidenceCache", "evidence_key", "library_digest"]

logger = logging.getLogger(__name__)

# Bump when the meaning of a stored number changes (the end-state likelihood, the spaces it is computed in).
# Bump too when end_habits.new_relations, whose results entries keep, changes what it finds.
# 2: the relations new at the pair's end (``new``); 3: and whether a toy moved (end_habits.MOVED); 4: and
# the bound habits its new facts show (end_habits.bound_name)
EVIDENCE_VERSION = 4
# An entry holds a few numbers per grounded task (tens of bytes each); far more is not an entry.
MAX_ENTRY_BYTES = 4 * 1024 * 1024
# Pieces of evidence kept in memory per EvidenceCache (a few KB each), the most recently used.
REMEMBERED = 1024

_DIGESTS: "weakref.WeakKeyDictionary[TaskLibrary, str]" = weakref.WeakKeyDictionary()


def library_digest(library: TaskLibrary) -> str:
    """sha256 of the names and texts of every ASP source the library grounds, tabulates and solves with
    (computed once per library object)."""
    if library not in _DIGESTS:
        text = json.dumps([[s.name, s.text] for program in (library.program, library.grounding_program,
                                                             library.tabulation_program) for s in program.sources])
        _DIGESTS[library] = hashlib.sha256(text.encode()).hexdigest()
    return _DIGESTS[library]


def evidence_key(start: State, end: State, digest: str, noise: EndStateNoise, space: str) -> str:
    """sha256 (hex) of what one pair's evidence depends on; ``digest``: :func:`library_digest`;
    ``space``: which space is searched (:func:`groundlang.inference.shared_meaning.evidence_space`)."""
    palette = start.layout.palette
    description = {
        "version": EVIDENCE_VERSION,
        "layout": layout_description(start.layout),
        "palette": [list(vs) for _, vs in palette.all_values],
        "start": start.positions.tolist(),
        "end": end.positions.tolist(),
        "library": digest,
        "noise": list(noise.key()),
        "space": space,
    }
    text = json.dumps(description, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def _contents(evidence: LayoutEvidence) -> dict:
    return {
        "goals": [[[a.predicate, list(a.args)] for a in goal] for goal in evidence.goals],
        "values": evidence.values,
        "groundings": [[task, {var: sorted(p) for var, p in props.items()}, g] for task, props, g in evidence.groundings],
        "floor": evidence.floor,
        "new": sorted(evidence.new_relations),
    }


def _checksum(key: str, contents: dict) -> str:
    # Floats' reprs round-trip exactly through JSON, so the text re-made from what was read matches the
    # text written unless a character of it changed.
    text = json.dumps(contents, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(f"{key} {text}".encode()).hexdigest()


def _restore(data: dict, key: str, library: TaskLibrary, noise: EndStateNoise, objects: frozenset[str]) -> LayoutEvidence:
    contents = {name: data[name] for name in ("goals", "values", "groundings", "floor", "new")}
    if data.get("checksum") != _checksum(key, contents):
        raise ValueError("checksum does not match the contents")
    goals = [tuple(Atom(p, tuple(args)) for p, args in goal) for goal in contents["goals"]]
    if any(not set(atom.args) <= objects for goal in goals for atom in goal):
        raise ValueError("a goal names an object the layout does not have")
    values = [float(v) for v in contents["values"]]
    groundings = [(task, {var: frozenset(p) for var, p in props.items()}, int(g))
                  for task, props, g in contents["groundings"]]
    if len(values) != len(goals) or any(not 0 <= g < len(goals) for _, _, g in groundings):
        raise ValueError("goals, values and groundings do not match")
    if any(v != v or v > 0 for v in [*values, contents["floor"]]):
        raise ValueError("holds a number that is not a log-probability")
    if values and max(values) == float("-inf"):
        raise ValueError("no goal of it has a probability above 0")  # a pair's evidence would be nan
    # The checksum says the entry is whole, not that it is this library's: a grounding's task and variables
    # are looked up by name where the evidence is read.
    variables = {t.name: {v.name for v in t.variables} for t in library.tasks}
    if any(task not in variables or not set(props) <= variables[task] for task, props, _ in groundings):
        raise ValueError("names a task or variable the library does not have")
    if not isinstance(contents["new"], list) or not all(isinstance(r, str) and r for r in contents["new"]):
        raise ValueError("its new relations are not a list of names")
    return LayoutEvidence.from_parts(library, noise, goals, values, groundings, contents["floor"],
                                     frozenset(contents["new"]))


class EvidenceCache:
    """The evidence of pairs, read from the cache folder or computed and written there. ``cache_dir``:
    the folder (see the module docstring), None for the default, False for no cache. Counts ``hits``,
    ``computed`` and ``damaged`` entries (hits from memory included); :meth:`report` logs them once."""

    def __init__(self, library: TaskLibrary, noise: EndStateNoise, cache_dir: str | os.PathLike | None | bool = None):
        self.library, self.noise = library, noise
        self.entries = EntryFolder(cache_dir, EVIDENCE_FOLDER, "recomputed", logger)
        self.digest = library_digest(library)
        self._memory: OrderedDict[str, LayoutEvidence] = OrderedDict()

    hits = property(lambda self: self.entries.hits)
    computed = property(lambda self: self.entries.computed)
    damaged = property(lambda self: self.entries.damaged)

    def evidence(self, start: State, end: State, max_states: int | None = None) -> LayoutEvidence:
        """The pair's LayoutEvidence; StateSpaceError (not cached) when its end cannot be reached."""
        key = evidence_key(start, end, self.digest, self.noise, evidence_space(start, end, max_states))
        if key in self._memory:
            self._memory.move_to_end(key)
            self.entries.hits += 1
            return self._memory[key]
        found = self.entries.read(key, MAX_ENTRY_BYTES, "an evidence cache entry",
                                  lambda data: _restore(data, key, self.library, self.noise,
                                                        frozenset(start.layout.movable_names + start.layout.room_names
                                                                  + start.layout.door_names)))
        if found is None:
            found = LayoutEvidence(start, end, self.library, self.noise, max_states)
            # What end habits learn from the pair, kept with it: a warm cache then grounds no layout's PFs.
            found.new_relations = new_relations(start, end, self.library)
            self.entries.computed += 1
            contents = _contents(found)
            self.entries.write(key, {**contents, "checksum": _checksum(key, contents)})
        self._memory[key] = found
        if len(self._memory) > REMEMBERED:
            self._memory.popitem(last=False)
        return found

    def report(self) -> None:
        """One warning for damaged entries (how many, the first and why), one info line of counts."""
        self.entries.report("end-state evidence", "pairs from the cache or repeated")
