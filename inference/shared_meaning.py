"""One command, several layouts: the behaviour term of one lifted meaning grounded in each layout.

A command of the Williams et al. (2018) corpus comes with (start, end) pairs in different layouts: "the
red room" is room0 in one and room2 in the next. The pairs are evidence of one lifted task L and one
binding constraint C, each grounded in its own layout. An interpretation of the command is read in
the first pair's layout (a grounded task T1 of L, whose bound objects words describe); the other pairs
enter through what T1's objects *are*:

    P(e_1, ..., e_m | L, T1) = P(e_1 | T1) * sum_C P(C | T1) * prod_{k >= 2} P(e_k | L, C)
    P(e_k | L, C)            = mean over the groundings g of L in layout k that satisfy C of P(e_k | g)

with ``P(e | g)`` the end state's likelihood (``inference.end_states``) and C ranging uniformly over the
descriptions of T1's bound objects that say one thing of each (its class alone, or one of its property
PFs: a colour, a shape, a size, "the largest room"); the data README judges a command by such
single-fact descriptions. A layout where no grounding satisfies C explains its pair only as noise (the
end-state likelihood's ``anywhere`` weight): workers sometimes describe one pair of three.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from itertools import product

import numpy as np

from groundlang.inference.end_states import EndStateNoise, distances, end_state_log_likelihood
from groundlang.logic.tasks import GroundedTask, TaskLibrary
from groundlang.model.features import goal_mask
from groundlang.model.pf_tables import library_pf_tables
from groundlang.model.relevance import abstract_space, exact_fits, relevant_toys
from groundlang.model.statespace import enumerate_states
from groundlang.model.tasks import candidate_tasks
from groundlang.model.world import State

__all__ = ["LayoutEvidence", "properties_of", "evidence_space", "layout_evidence", "shared_meaning_terms", "end_state_behaviour"]


def _log_mean_exp(values) -> float:
    """log of the mean of exp(values) (values not empty): a uniform prior over what they score."""
    top = max(values)
    return top + math.log(sum(math.exp(v - top) for v in values) / len(values))


def properties_of(task: GroundedTask, atoms) -> dict[str, frozenset[str]]:
    """Variable -> the property PFs of its object among ``atoms`` (a binding constraint's)."""
    variable = {obj: var for var, obj in task.binding}
    props: dict[str, set[str]] = {var: set() for var, _ in task.binding}
    for atom in atoms:
        if len(atom.args) == 1 and atom.args[0] in variable:
            props[variable[atom.args[0]]].add(atom.predicate)
    return {var: frozenset(p) for var, p in props.items()}


class LayoutEvidence:
    """Pair k's end-state likelihood under every grounding of every task in its own layout, with what
    each grounding's bound objects are, and the pair's noise floor. ``goals`` (in candidate order),
    ``groundings`` (task, properties of its bound objects, index into ``goals``) and ``floor`` are what
    :meth:`from_parts` takes back: what the evidence cache (``inference.evidence_cache``) stores, with
    ``new_relations``, the relations of which some fact holds at the pair's end and not at its start
    (``inference.end_habits.new_relations``; the cache fills it in, else None)."""

    def __init__(self, start: State, end: State, library: TaskLibrary, noise: EndStateNoise,
                 max_states: int | None = None):
        found = candidate_tasks(start, library)
        goals = list(dict.fromkeys(task.goal for task, _ in found))
        tables = library_pf_tables(start.layout, library)
        space = _space(start, end, max_states)
        end_index = space.index_of(end)  # StateSpaceError when the end cannot be reached
        dist = distances(space)
        masks = np.stack([goal_mask(space, goal, tables) for goal in goals]) if goals else None
        values = end_state_log_likelihood(dist, end_index, masks, noise) if goals else np.zeros(0)
        position = {goal: g for g, goal in enumerate(goals)}
        groundings = [(task.task, properties_of(task, constraints[0].atoms if constraints else ()),
                       position[task.goal]) for task, constraints in found]
        floor = math.log(noise.anywhere / int((dist >= 0).sum()))
        self._set(library, noise, goals, [float(v) for v in values], groundings, floor)

    @classmethod
    def from_parts(cls, library: TaskLibrary, noise: EndStateNoise, goals: Sequence[tuple], values: Sequence[float],
                   groundings: Sequence[tuple[str, dict[str, frozenset[str]], int]], floor: float,
                   new_relations: frozenset[str] | None = None) -> "LayoutEvidence":
        """The evidence from what an instance computed once held (``goals`` and their ``values``,
        ``groundings``, ``floor``, ``new_relations``), for the same library and noise."""
        self = cls.__new__(cls)
        self._set(library, noise, list(goals), [float(v) for v in values], list(groundings), float(floor))
        self.new_relations = new_relations
        return self

    def _set(self, library, noise, goals, values, groundings, floor) -> None:
        self.library = library
        self.new_relations: frozenset[str] | None = None
        self.noise = noise.key()
        self.goals, self.values, self.groundings, self.floor = goals, values, groundings, floor
        self.by_goal: dict[tuple, float] = dict(zip(goals, values))
        self.by_task: dict[str, list[tuple[dict[str, frozenset[str]], float]]] = {}
        for task, props, g in groundings:
            self.by_task.setdefault(task, []).append((props, values[g]))
        # A pair shown to several workers is one object read by every command of theirs, and each asks the
        # same few (task, description) values: kept, at most one per description its tasks admit.
        self._values: dict[tuple, float] = {}

    def goal_value(self, goal: tuple) -> float:
        """log P(e | g) for a grounded goal of this layout (the noise floor for one no task has)."""
        return self.by_goal.get(goal, self.floor)

    def value(self, task: str, description: dict[str, str | None]) -> float:
        """log P(e_k | L, C): the mean over the groundings satisfying ``description`` (variable -> the one
        property PF said of it, or None for its class alone), or the noise floor when none does."""
        key = (task, tuple(description.items()))
        if key not in self._values:
            values = [v for props, v in self.by_task.get(task, ())
                      if all(p is None or p in props[var] for var, p in description.items())]
            self._values[key] = _log_mean_exp(values) if values else self.floor
        return self._values[key]


def evidence_space(start: State, end: State, max_states: int | None = None) -> str:
    """Which space a pair's evidence is computed in (what its cache key records): ``"exact"``, or the
    abstraction and the toys that move in it."""
    if exact_fits(start, max_states):
        return "exact"
    return "abstraction moving " + ",".join(str(i) for i in relevant_toys(start, (), [(start, end)]))


def _space(start: State, end: State, max_states: int | None):
    """The exact space when it fits ``max_states``, else the relevance abstraction in which the toys the
    pair moves move and the others are walls: a toy the pair leaves where it stands is where every goal
    must be reached around it, so fixing it changes no goal's nearest states but by routes that would
    push it (model.relevance)."""
    if exact_fits(start, max_states):
        return enumerate_states(start, max_states=max_states)
    return abstract_space(start, relevant_toys(start, (), [(start, end)]), max_states)


def layout_evidence(pairs: Sequence[tuple[State, State]], library: TaskLibrary, noise: EndStateNoise | None = None,
                    max_states: int | None = None) -> list[LayoutEvidence]:
    """The evidence of each (start, end) pair, in its own layout."""
    noise = noise or EndStateNoise()
    return [LayoutEvidence(start, end, library, noise, max_states) for start, end in pairs]


def shared_meaning_terms(tasks: Sequence[GroundedTask], constraints: Sequence, others: Sequence[LayoutEvidence]) -> np.ndarray:
    """``[I]``: log sum_C P(C | T1) prod_k P(e_k | L, C) for each interpretation's grounded task T1 (in the
    first layout) and its largest binding constraint; 0 for every interpretation when there is no other
    pair. Cached per (task, properties): interpretations that differ only in words share it."""
    out = np.zeros(len(tasks))
    if not others:
        return out
    cache: dict[tuple, float] = {}
    for i, (task, constraint) in enumerate(zip(tasks, constraints)):
        props = properties_of(task, constraint.atoms)
        key = (task.task, tuple(sorted(props.items())))
        if key not in cache:
            variables = [var for var, _ in task.binding]
            options = [(None, *sorted(props[var])) for var in variables]
            terms = [sum(layout.value(task.task, dict(zip(variables, choice))) for layout in others)
                     for choice in product(*options)]
            cache[key] = _log_mean_exp(terms)
        out[i] = cache[key]
    return out


def instance_pairs(inst) -> tuple[tuple[State, State], ...]:
    """A training instance's (start, end) states: a command's pairs, or a demonstration's first and last."""
    return tuple(getattr(inst, "pairs", ())) or ((inst.initial_state, inst.final_state),)


def end_state_behaviour(instances: Sequence, interpretations: Sequence[Sequence], library: TaskLibrary,
                        noise: EndStateNoise | None = None, max_states: int | None = None) -> list[list[float]]:
    """The behaviour term of each interpretation of each instance of (start, end) pairs: the first pair's
    end-state likelihood under its grounded task, times, for an instance with more ``pairs``, the shared
    meaning's evidence from the others (:func:`shared_meaning_terms`). An instance may carry its pairs'
    ``evidence`` (computed for this library and noise when it was read, which also checked that each
    end can be reached); else it is computed here."""
    noise = noise or EndStateNoise()
    out = []
    # A pair shown to several workers is read by each of their commands: a corpus's commands share few
    # (evidence, interpretations) combinations (Williams: 1619 commands, 115 distinct pairs), each computed
    # once. Keyed by identity (the evidence cache and the learner share both by reference); each entry holds
    # what its key names, so that no id is reused while the key stands.
    done: dict[tuple, tuple] = {}
    for inst, group in zip(instances, interpretations):
        evidence = getattr(inst, "evidence", None)
        if not evidence or any(e.library is not library or e.noise != noise.key() for e in evidence):
            # made here for this instance alone: shared by none
            out.append(_behaviour(inst.initial_state, group, layout_evidence(instance_pairs(inst), library, noise,
                                                                             max_states), library))
            continue
        key = (*map(id, evidence), id(group))
        if key not in done:
            done[key] = (evidence, group, _behaviour(inst.initial_state, group, evidence, library))
        out.append(list(done[key][2]))
    return out


def _behaviour(start: State, group: Sequence, evidence: Sequence[LayoutEvidence], library: TaskLibrary) -> list[float]:
    values = [evidence[0].goal_value(i.goal) for i in group]
    if len(evidence) > 1:
        largest = {task: constraints[0] for task, constraints in candidate_tasks(start, library)}
        tasks = [i.task for i in group]
        shared = shared_meaning_terms(tasks, [largest.get(t, i.constraint) for t, i in zip(tasks, group)],
                                      evidence[1:])
        values = [v + float(x) for v, x in zip(values, shared)]
    return values
