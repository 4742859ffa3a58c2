"""End habits: what else a demonstration's end state shows besides its goal.

A demonstrator stops where the goal holds, and often where more holds too: sent to a room, a worker stops
next to the chair in it; having pushed a chair into a room, she stands beside it. What a command is
judged by, and what its user sees, is what holds where the agent ends, so following ends where the goal
holds and where what demonstrators of such goals also left true most probably holds.

Learned from the training demonstrations, each (start, end) pair on its own: the relations ``R`` (the
predicates a task of the library asks for) of which some fact holds at the end and not at the start.
Then ``q(R | L)``, how often a demonstration whose new facts include relations ``L`` (a goal's) has a
new fact of ``R`` too, shrunk by one pseudo-demonstration towards ``R``'s rate over all of them (itself
shrunk by half a demonstration either way, so that no rate is 0 or 1: what one more demonstration could
show otherwise is never ruled out)::

    q(R | L) = (n(L, R) + p(R)) / (n(L) + 1),    p(R) = (n(R) + 1/2) / (N + 1)

Following weighs each goal ``g`` of the posterior in a state ``s`` by
``prod_{R not in L(g)} (1 - q(R | L(g)) + q(R | L(g)) [some fact of R holds in s])``
(:func:`groundlang.goal_plans.expected_success_states`): a goal's states where its usual company holds
are worth more than those where it does not, and none is worth more than the goal alone.

A demonstrator also leaves alone what the goal does not need moved. A pair in which a toy (a movable
object but the one commands speak to) ends elsewhere than it started counts the pseudo-relation
:data:`MOVED` among its new ones, and with ``moved_toys`` a goal's states where a toy moved are weighed by
``q(MOVED | L(g))`` (those where none did by 1): sent to a room, a follower does not push a chair along to
stand beside it there, where the demonstrators of such goals left the chairs where they were. Where every
state of the goal has a toy moved (a toy's goal), moving is the goal's own business and weighs nothing.

What a demonstrator leaves true is often bound to what the goal names: having pushed a chair into a
room, she stands in that room, not in any. Two new facts of a pair that share an object count a *bound
habit* among its new ones (:func:`bound_name`: ``agentInRoom[1]=toyInRoom[1]``), and with ``bound`` a goal's
states where a relation's fact holds bound to the goal's objects as demonstrations showed are worth more
than those where only another fact of it holds (:meth:`EndHabits._bound_share`).
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from groundlang.inference.shared_meaning import instance_pairs
from groundlang.logic.atoms import Atom, canonical_predicate
from groundlang.model.language_model_base import HABIT_PRIORS
from groundlang.model.features import atoms_hold_along
from groundlang.model.pf_tables import library_pf_tables
from groundlang.model.world import State

__all__ = ["EndHabits", "MOVED", "new_relations", "demonstrated_pairs", "known_new_relations"]

# The pseudo-relation of a pair in which a toy ends elsewhere than it started (no PF has this name).
MOVED = "(a toy moved)"

# A saved model's table is untrusted: bounds on what a crafted file can make the loader build.
MAX_RELATION_SETS = 100_000
MAX_DEMONSTRATIONS = 10**12
# Following computes a rate per name, each a pass over the sets: a crafted table of many names makes each
# command slow, where a domain has tens of relations and a few hundred bound habits.
MAX_NAMES = 2_000
# A relation's name as a PF is named (an identifier), MOVED, or a bound habit of two of them (bound_name).
_NAME = re.compile(r"(?:\w{1,1000}|\(a toy moved\)|\w{1,1000}\[\d{1,2}\]=\w{1,1000}\[\d{1,2}\])\Z")


def new_relations(start: State, end: State, library) -> frozenset[str]:
    """The relations a task of ``library`` asks for of which some fact holds in ``end`` and not in
    ``start`` (the same layout), and :data:`MOVED` where a toy ends elsewhere than it started."""
    return _new_relations([(start, end)], library)[0]


def _new_relations(pairs: Sequence[tuple[State, State]], library) -> list[frozenset[str]]:
    """:func:`new_relations` of pairs of one layout, their states' facts read in one pass."""
    layout = pairs[0][0].layout
    moved = [bool((end.positions[1:] != start.positions[1:]).any()) for start, end in pairs]
    tables = library_pf_tables(layout, library)
    asked = frozenset(map(canonical_predicate, library.goal_relations))
    atoms = [a for a in tables.grids if canonical_predicate(a.predicate) in asked]
    if not atoms:
        return [frozenset([MOVED] if m else []) for m in moved]
    names = np.array([canonical_predicate(a.predicate) for a in atoms])
    holds = atoms_hold_along(layout, np.stack([s.positions for pair in pairs for s in pair]), atoms, tables)
    new = holds[1::2] & ~holds[0::2]
    return [frozenset(names[row].tolist() + _bound([atoms[i] for i in np.flatnonzero(row)]) + ([MOVED] if m else []))
            for row, m in zip(new, moved)]


def bound_name(relation: str, position: int, other: str, other_position: int) -> str:
    """The name of a bound habit: a new fact of ``relation`` whose argument ``position`` (from 0) is the
    argument ``other_position`` of a new fact of ``other`` (``agentInRoom[1]=toyInRoom[1]``: the agent
    ends in the room a toy was pushed into)."""
    return f"{relation}[{position}]={other}[{other_position}]"


_BOUND = re.compile(r"(\w+)\[(\d+)\]=(\w+)\[(\d+)\]\Z")


def _bound(new_facts: Sequence[Atom]) -> list[str]:
    """The bound habits (:func:`bound_name`) two of a pair's new facts of different relations show."""
    out = set()
    for fact in new_facts:
        for other in new_facts:
            relation, other_relation = canonical_predicate(fact.predicate), canonical_predicate(other.predicate)
            if relation == other_relation:
                continue
            out.update(bound_name(relation, i, other_relation, j)
                       for i, a in enumerate(fact.args) for j, b in enumerate(other.args) if a == b)
    return sorted(out)


def demonstrated_pairs(instances) -> list[tuple[State, State]]:
    """The (start, end) states of training instances, every pair of each (:func:`instance_pairs`)."""
    return [pair for inst in instances for pair in instance_pairs(inst)]


def known_new_relations(instances, library) -> dict[tuple[State, State], frozenset[str]]:
    """The new relations of the instances' pairs that their end-state evidence (computed for ``library``)
    carries (``LayoutEvidence.new_relations``)."""
    known = {}
    for inst in instances:
        evidence = getattr(inst, "evidence", ())
        for pair, shown in zip(instance_pairs(inst), evidence):
            if shown.library is library and shown.new_relations is not None:
                known[pair] = shown.new_relations
    return known


@dataclass(frozen=True)
class EndHabits:
    """How many demonstrations showed each set of new relations at their end (module docstring)."""

    shown: tuple[tuple[frozenset[str], int], ...]

    @classmethod
    def learn(cls, pairs: Iterable[tuple[State, State]], library,
              known: Mapping[tuple[State, State], frozenset[str]] | None = None) -> "EndHabits":
        """From demonstrations' (start, end) states; ``known``: the new relations of some of them, computed
        before (:func:`known_new_relations`)."""
        return cls(()).plus(pairs, library, known)

    def plus(self, pairs: Iterable[tuple[State, State]], library,
             known: Mapping[tuple[State, State], frozenset[str]] | None = None) -> "EndHabits":
        """These counts and those of more demonstrations (``Learner.update``)."""
        counts = Counter(dict(self.shown))
        distinct = Counter(pairs)  # a corpus repeats its pairs (Williams: 115 distinct of 4857)
        by_layout: dict = {}
        for pair in distinct:
            if known and pair in known:
                counts[known[pair]] += distinct[pair]
            else:
                by_layout.setdefault(pair[0].layout, []).append(pair)
        for same in by_layout.values():
            for pair, relations in zip(same, _new_relations(same, library)):
                counts[relations] += distinct[pair]
        # Clamped where a saved table is bounded: what this saves, from_json reads back.
        counts = Counter({k: min(n, MAX_DEMONSTRATIONS) for k, n in counts.items()})
        return EndHabits(tuple(sorted(counts.items(), key=lambda kv: (sorted(kv[0]), kv[1]))))

    @cached_property
    def demonstrations(self) -> int:
        return sum(n for _, n in self.shown)

    @cached_property
    def _counts(self) -> dict[frozenset[str], int]:
        return {}

    def _count(self, relations: frozenset[str]) -> int:
        # Kept: following asks the same few counts for every goal of every command.
        if (n := self._counts.get(relations)) is None:
            n = self._counts[relations] = sum(n for shown, n in self.shown if relations <= shown)
        return n

    def rate(self, relation: str, given: frozenset[str], prior: str = "absent") -> float:
        """``q(relation | given)``: how often a demonstration whose new relations include ``given`` has a
        new fact of ``relation`` too (module docstring), shrunk by one pseudo-demonstration: with ``prior``
        ``"absent"`` one that did not show it (``n(L, R) / (n(L) + 1)``: a habit is what demonstrations of
        such goals were seen to do, never certain), with ``"overall"`` one at the relation's rate over all
        demonstrations (``(n(L, R) + p(R)) / (n(L) + 1)``, ``p(R) = (n(R) + 1/2) / (N + 1)``: a habit no
        demonstration of the goal showed still has the relation's own rate). 0 where no demonstration was seen."""
        if prior not in HABIT_PRIORS:
            raise ValueError(f"habit prior {prior!r}: expected one of {', '.join(HABIT_PRIORS)}")
        if not self.demonstrations:
            return 0.0
        mean = (self._count(frozenset([relation])) + 0.5) / (self.demonstrations + 1) if prior == "overall" else 0.0
        return (self._count(given | {relation}) + mean) / (self._count(given) + 1)

    @cached_property
    def relations(self) -> frozenset[str]:
        """The relations demonstrations left new (and :data:`MOVED`), not their bound habits."""
        return frozenset(name for name in self.names if not _BOUND.match(name))

    def unknown_to(self, library) -> list[str]:
        """The names of the table (sorted) that no goal of ``library`` is made of: a relation, or either side of
        a bound habit, that is not one of its goals' relations (canonically spelled), nor :data:`MOVED`. A
        table counted with ``library`` has none; a saved model's that has some was not (a forged table)."""
        asked = frozenset(map(canonical_predicate, library.goal_relations)) | {MOVED}

        def known(name: str) -> bool:
            m = _BOUND.match(name)
            return name in asked if m is None else m.group(1) in asked and m.group(3) in asked

        return sorted(name for name in self.names if not known(name))

    @cached_property
    def names(self) -> frozenset[str]:
        """Every name the table counts: relations, :data:`MOVED` and bound habits."""
        return frozenset().union(*(shown for shown, _ in self.shown)) if self.shown else frozenset()

    @cached_property
    def bound(self) -> dict[str, tuple[tuple[str, int, str, int], ...]]:
        """Per relation, its bound habits demonstrations showed: ``(name, position, other, other_position)``."""
        out: dict[str, set] = {}
        for shown, _ in self.shown:
            for name in shown:
                if (m := _BOUND.match(name)) is not None:
                    out.setdefault(m[1], set()).add((name, int(m[2]), m[3], int(m[4])))
        return {relation: tuple(sorted(found)) for relation, found in out.items()}

    def table(self, prior: str = "absent") -> dict[str, dict[str, float]]:
        """``q(R | {L})`` for every two relations demonstrations showed: ``{L: {R: rate}}``, to read what
        was learned (``prior``: see :meth:`rate`; following weighs habits with the language model's
        ``habit_prior``, ``"absent"`` by default)."""
        return {given: {r: self.rate(r, frozenset([given]), prior) for r in sorted(self.relations - {given})}
                for given in sorted(self.relations)}

    def shown_at(self, goal: tuple[Atom, ...], start: State, end: State, library, prior: str = "absent",
                 moved: bool = False, least: float = 0.1) -> dict[str, float]:
        """The relations new at ``end`` (from ``start``) besides ``goal``'s own, each with :meth:`rate` given
        the goal's relations, those of at least ``least``: what following left true because demonstrations
        of such goals did (``follow`` says so). :data:`MOVED` only with ``moved`` (the language model's
        ``moved_toys``, without which it weighs nothing); bound habits are not listed."""
        given = frozenset(canonical_predicate(atom.predicate) for atom in goal)
        shown = {}
        for relation in sorted(new_relations(start, end, library) - given):
            if _BOUND.match(relation) or (relation == MOVED and not moved):
                continue
            if (q := self.rate(relation, given, prior)) >= least:
                shown[relation] = q
        return shown

    def bound_table(self, prior: str = "absent") -> dict[str, float]:
        """``q(b | {L})`` for every bound habit ``b`` demonstrations showed, ``L`` the relation it binds to
        (``{"agentInRoom[1]=toyInRoom[1]": 0.9, ...}``), to read what was learned."""
        return {name: self.rate(name, frozenset([other]), prior)
                for found in self.bound.values() for name, _, other, _ in found}

    def weights(self, goals: Iterable[tuple[Atom, ...]], masks, within: np.ndarray,
                moved_toys: bool = False, made_true: bool = False, bound: bool = False,
                prior: str = "absent") -> list[np.ndarray | None]:
        """Per goal, ``[S]``: each state's weight for it over ``masks.space`` (a :class:`GoalMasks`), the
        product over the relations demonstrations showed that can hold with it in a state of ``within``
        (``[S]`` bool, those the agent can reach); None where it is 1 everywhere. A relation that cannot
        hold where the goal does is not one its demonstrators could have left true there, so it weighs
        nothing: habits say where to end among a goal's states, not which goal to prefer. With
        ``moved_toys``, :data:`MOVED` weighs the goal's states where a toy moved (module docstring). With
        ``made_true``, a relation weighs the states where some fact of it holds that did not in the space's
        initial state (as :func:`new_relations` counted the demonstrations), not every state where one holds.
        With ``bound``, a relation's states where its fact is bound to the goal's objects as demonstrations
        showed (:meth:`_bound_share`) are worth more than those where only another of its facts holds.
        ``prior``: what each relation's and bound habit's share is shrunk towards (:meth:`rate`). Moving a
        toy keeps ``"overall"``: that none ever did says "rarely", not "never"."""
        holds: dict = {}  # [S] masks by relation, and by (relation, position, objects) for bound habits
        # Weighed whether or not a demonstration moved a toy: that none ever did is the strongest evidence.
        moving = _moved(masks.space) if moved_toys and self.demonstrations else None
        out = []
        for goal in goals:
            given = frozenset(canonical_predicate(a.predicate) for a in goal)
            region = masks.mask(goal) & within
            weight, company = None, region
            # Where no state of the goal leaves every toy in place, moving one is the goal's own business.
            if moving is not None and (still := region & ~moving).any():
                weight = 1.0 - (1.0 - self.rate(MOVED, given, prior="overall")) * moving
                # Demonstrators who left the toys alone left true only what could hold without moving one.
                company = still
            for relation in sorted(self.relations - given - {MOVED}):
                q = self.rate(relation, given, prior)
                if q <= 0.0:
                    continue
                if relation not in holds:
                    holds[relation] = _holds(relation, masks, made_true)
                if not (holds[relation] & company).any():
                    continue
                factor = (1.0 - q) + q * holds[relation]
                if bound and (share := self._bound_share(relation, goal, given, q, masks, company, made_true,
                                                         holds, prior)):
                    factor = factor - share[0] * holds[relation] + share[0] * share[1]
                weight = factor if weight is None else weight * factor
            out.append(weight)
        return out

    def _bound_share(self, relation: str, goal: tuple[Atom, ...], given: frozenset[str], q: float, masks,
                     company: np.ndarray, made_true: bool, holds: dict,
                     prior: str = "absent") -> tuple[float, np.ndarray] | None:
        """``(q_b, [S] bool)``: of the demonstrations of such goals that left a new fact of ``relation``
        (share ``q``), the share ``q_b`` whose fact was bound to a fact of the goal's relations as it is in
        the states returned (``agentInRoom[1]=toyInRoom[1]``: the agent in the room the goal pushes the
        toy into), the habit of largest share that can hold with the goal and tells some of its states
        apart from the relation's own (``holds[relation]``, where some fact of it holds: a binding to the one
        agent every fact names says nothing more); None where none does. ``holds``: masks read so far, by
        relation and by binding, shared by the posterior's goals (many name the same objects).

        A demonstration showing a bound fact showed a fact of the relation, so the truth asks for a fact
        of it with probability ``q``, for the bound one with ``q_b`` (at most ``q``): a state where the
        bound fact holds is worth 1, one where only another fact of it holds ``1 - q_b``, one where none
        does ``1 - q`` (the relation's factor ``1 - q + (q - q_b) [R] + q_b [bound]``)."""
        best = None
        for name, position, other, other_position in self.bound.get(relation, ()):
            if other not in given:
                continue
            q_b = min(q, self.rate(name, given, prior))
            objects = {a.args[other_position] for a in goal
                       if canonical_predicate(a.predicate) == other and other_position < len(a.args)}
            if q_b <= 0.0 or not objects or (best is not None and q_b <= best[0]):
                continue
            key = (relation, position, frozenset(objects))
            if key not in holds:
                holds[key] = _holds(relation, masks, made_true, position=position, objects=objects)
            where = holds[key]
            if (where & company).any() and ((where ^ holds[relation]) & company).any():
                best = (q_b, where)
        return best

    def to_json(self) -> list:
        return [[sorted(shown), n] for shown, n in self.shown]

    @classmethod
    def from_json(cls, value) -> "EndHabits":
        """From :meth:`to_json`'s value, checked (a saved model is untrusted): ValueError saying what is wrong."""
        if not isinstance(value, list) or len(value) > MAX_RELATION_SETS:
            raise ValueError(f"end_habits must be a list of at most {MAX_RELATION_SETS} [relations, count] pairs")
        shown = []
        for entry in value:
            if (not isinstance(entry, list) or len(entry) != 2 or not isinstance(entry[0], list)
                    or not all(isinstance(r, str) and r for r in entry[0]) or isinstance(entry[1], bool)
                    or not isinstance(entry[1], int) or not 0 < entry[1] <= MAX_DEMONSTRATIONS):
                raise ValueError(f"end_habits: {entry!r} is not [relations, count] (names, a positive count)")
            if bad := next((r for r in entry[0] if not _NAME.match(r)), None):
                raise ValueError(f"end_habits: {bad[:80]!r} is not a relation's name, {MOVED!r} or a bound habit "
                                 "such as agentInRoom[1]=toyInRoom[1]")
            shown.append((frozenset(entry[0]), entry[1]))
        if len({s for s, _ in shown}) != len(shown):
            raise ValueError("end_habits names a set of relations twice")
        if len(names := frozenset().union(*(s for s, _ in shown))) > MAX_NAMES:
            raise ValueError(f"end_habits names {len(names)} relations and bound habits, more than the {MAX_NAMES} "
                             "allowed")
        return cls(tuple(shown))


def _moved(space) -> np.ndarray:
    """``[S]`` bool over ``space`` (enumerated from its initial state): where a toy is elsewhere than there."""
    start = space.initial.positions[1:]
    return (space.positions[:, 1:] != start[None]).any(axis=(1, 2))


def _holds(relation: str, masks, made_true: bool = False, position: int = 0, objects=None) -> np.ndarray:
    """``[S]`` bool over ``masks.space``: where some fact of ``relation`` holds (``made_true``: one that does
    not hold in the initial state, index 0; ``objects``: one whose argument ``position`` is one of them)."""
    atoms = [(a,) for a in masks.tables.grids if canonical_predicate(a.predicate) == relation
             and (objects is None or (position < len(a.args) and a.args[position] in objects))]
    masks.prepare(atoms)
    found = [masks.mask(atom) for atom in atoms]
    if made_true:
        found = [mask for mask in found if not mask[0]]
    if not found:
        return np.zeros(masks.space.num_states, dtype=bool)
    return np.logical_or.reduce(found)
