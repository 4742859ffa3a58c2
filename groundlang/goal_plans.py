"""Planning for a grounded goal in a state: the state space to plan in, the states to end in, and the
plan carried out.

Plans depend on the world only, never on the words: :class:`WorldPlans` keeps them per (state, goal or
states to end in, step limit), with the state spaces they were made in, for a learner's ``follow``.
"""

from __future__ import annotations

import hashlib

import numpy as np

from groundlang.confidence import NEGLIGIBLE, GoalMasks
from groundlang.inference.acting import rollout, rollout_states, stop_before
from groundlang.inference.end_habits import EndHabits
from groundlang.inference.end_states import distances
from groundlang.inference.planning import TaskSettings, solve_task
from groundlang.logic.atoms import Atom
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.features import goal_mask
from groundlang.model.pf_tables import library_pf_tables
from groundlang.model.relevance import exact_fits, placement_sample, pushes_scenery, state_space_for
from groundlang.model.statespace import StateSpace, StateSpaceError
from groundlang.model.world import State

__all__ = ["planning_space", "plan_for_goal", "plan_for_states", "expected_success_states", "success_at", "nearest_of",
           "WorldPlans"]

# State spaces kept for grouping goals and planning (crowd layouts: about 100 states each).
_SPACES_KEPT = 16
# A plan holds up to max_steps states; a follower that reads commands for hours keeps the latest this many.
_PLANS_KEPT = 256
# Goal masks kept, for the last spaces read (WorldPlans.goal_masks).
_MASKS_KEPT = 2


def planning_space(state: State, goal: tuple[Atom, ...] | None, library: TaskLibrary) -> StateSpace:
    """The exact state space where it fits; else, to plan for ``goal``, its relevance abstraction, and
    to compare goals (``goal`` None), a sample of placements."""
    tables = library_pf_tables(state.layout, library)
    return (placement_sample(state) if not exact_fits(state) and goal is None
            else state_space_for(state, goal or (), tables=tables))


def plan_for_goal(space: StateSpace, state: State, goal: tuple[Atom, ...], library: TaskLibrary,
                  settings: TaskSettings, max_steps: int) -> tuple[list, list, bool, str]:
    """Plan for ``goal`` in ``space`` (built from ``state``) and act: ``(states, actions, reached, reason)``,
    at most ``max_steps`` moves, stopping before a move that would push a toy the space holds still."""
    return plan_for_states(space, goal_mask(space, goal, library_pf_tables(state.layout, library)),
                           settings, max_steps)


def plan_for_states(space: StateSpace, mask: np.ndarray, settings: TaskSettings,
                    max_steps: int) -> tuple[list, list, bool, str]:
    """Plan to end in a state of ``mask`` (``[S]`` bool over ``space``) and act, as :func:`plan_for_goal`."""
    solved = solve_task(space.next_state, mask, settings)
    trajectory = rollout(space.next_state, solved, 0, goal_mask=mask, max_steps=max_steps)
    trajectory = stop_before(trajectory, pushes_scenery(space, trajectory.states[:-1], trajectory.actions))
    states, actions = rollout_states(space, trajectory)
    reached = bool(mask[int(trajectory.states[-1])])
    # The space holds only states reachable from ``state``: no goal state in it means no plan can succeed
    # (in a relevance abstraction: none that leaves the toys it holds still where they are).
    reason = trajectory.reason if reached or bool(np.asarray(mask).any()) else "unreachable"
    return states, actions, reached, reason


def expected_success_states(goals, masks: GoalMasks, step_cost: float, habits: EndHabits | None = None,
                            moved_toys: bool = False, made_true: bool = False, bound: bool = False,
                            habit_prior: str = "absent") -> tuple[np.ndarray, tuple[Atom, ...]] | None:
    """Where to end so that the final state most probably satisfies what was meant: the reachable states
    ``s`` of most ``sum_g P(g | words) [s satisfies g] - step_cost * steps(s)``, over the posterior's goals
    ``goals`` (``Posterior.goals()``) as ``masks`` says where they hold over its space (shared with the
    posterior that grouped them), and the most probable goal the nearest of them satisfies (what is
    said to be acted on). The goal acted on alone is the special case of a posterior sure of it; where
    two goals can hold at once ("next to the chair", "right of the chair"), ending where both hold wins
    the mass of both. ``step_cost``: how much probability of success one more step is worth (0: none; a
    step then only breaks ties). None where ``space`` is not enumerated breadth-first from the start (a
    sample of placements): its states' distances are unknown (in a relevance abstraction they are those
    of plans that leave its scenery where it stands, the plans following makes there); and None where
    no goal holds in a reachable state, or none where the cost leaves the agent: acting on the most
    probable goal then says what cannot be done. With ``habits``, each goal's term is weighed, state by
    state, by what demonstrations of such goals also left true (:mod:`groundlang.inference.end_habits`), and
    with ``moved_toys`` by how often they moved a toy; ``made_true``, ``bound``, ``habit_prior`` (its ``prior``):
    see ``EndHabits.weights``."""
    space = masks.space
    if getattr(space, "level_sizes", None) is None:
        return None
    kept = [(goal, p) for goal, p in goals if p >= NEGLIGIBLE]
    masks.prepare(goal for goal, _ in kept)
    dist = distances(space)
    score = np.zeros(space.num_states)
    weights = ([None] * len(kept) if habits is None else
               habits.weights([goal for goal, _ in kept], masks, within=dist >= 0, moved_toys=moved_toys,
                              made_true=made_true, bound=bound, prior=habit_prior))
    for (goal, p), weight in zip(kept, weights):
        score += p * masks.mask(goal) * (1.0 if weight is None else weight)
    if not (score[dist >= 0] > 0).any():
        return None  # no goal holds where the agent can go: the goal acted on is said to be out of reach
    value = np.where(dist >= 0, score - step_cost * dist, -np.inf)
    target = value >= value.max() - 1e-9
    said = goal_holding_at(kept, masks, nearest_of(target, space))
    return None if said is None else (target, said)


def goal_holding_at(goals, masks: GoalMasks, index: int) -> tuple[Atom, ...] | None:
    """The most probable of ``goals`` (``(goal, probability)``, most probable first) of a share of at least
    NEGLIGIBLE that holds in the state ``index`` of ``masks.space``; None where none does."""
    return next((goal for goal, p in goals if p >= NEGLIGIBLE and masks.mask(goal)[index]), None)


def nearest_of(target: np.ndarray, space) -> int:
    """The index of the reachable state of ``target`` (``[S]`` bool) fewest moves from the start: where a
    plan for ``target`` ends."""
    dist = distances(space)
    within = np.flatnonzero(target & (dist >= 0))
    return int(within[np.argmin(dist[within])])


def success_at(goals, masks: GoalMasks, index: int) -> float:
    """The posterior probability that what was meant holds in the state ``index`` of ``masks.space``:
    ``sum_g P(g) [s satisfies g]`` over ``goals`` (``(goal, probability)``) of a share of at least
    NEGLIGIBLE, at most 1."""
    return min(1.0, float(sum(p for goal, p in goals if p >= NEGLIGIBLE and masks.mask(goal)[index])))


class WorldPlans:
    """What following keeps of the world between commands: the last few state spaces, where goals hold
    over the last two read (following reads again the columns its posterior computed: every goal's
    atoms over every state, the costly part), and the plans made, by target. Nothing here depends on
    the words, so a plan serves every command that ends in the same states."""

    def __init__(self, library: TaskLibrary, settings: TaskSettings):
        self.library = library
        self.settings = settings
        self.plans: dict = {}
        self.spaces: dict = {}
        self._masks: list[GoalMasks] = []

    def space(self, state: State, goal: tuple[Atom, ...] | None = None) -> StateSpace:
        """The state space to plan for ``goal`` in, or to compare goals in (``goal`` None); see
        :func:`planning_space`. The last few are kept."""
        key = state if exact_fits(state) else (state, goal)
        if key not in self.spaces:
            if len(self.spaces) >= _SPACES_KEPT:
                self.spaces.pop(next(iter(self.spaces)))
            self.spaces[key] = planning_space(state, goal, self.library)
        return self.spaces[key]

    def goal_masks(self, space: StateSpace) -> GoalMasks:
        """Where goals hold over ``space``, kept for the last space."""
        found = next((m for m in self._masks if m.space is space), None)
        if found is None:
            # Two kept: where the world is too large, goals are compared over a sample of placements and where
            # to end is chosen over the best goal's abstraction, and each is read again by the next command.
            found = GoalMasks(space, self.library)
            self._masks = [found, *self._masks][:_MASKS_KEPT]
        return found

    def success_where(self, goals, state: State, over: tuple[Atom, ...], final: State) -> float | None:
        """:func:`success_at` the state ``final`` of the space goals are compared in (``self.space(state,
        over)``); None where that space's states are not enumerated from the start, or ``final`` is not one."""
        space = self.space(state, over)
        if getattr(space, "level_sizes", None) is None:
            return None
        try:
            index = space.index_of(final)
        except StateSpaceError:
            return None
        return success_at(goals, self.goal_masks(space), index)

    def act(self, state: State, goal: tuple[Atom, ...], max_steps: int,
            ending: np.ndarray | None = None, over: tuple[Atom, ...] | None = None) -> tuple[list, list, bool, str]:
        """Plan for ``goal``, or to end in a state of ``ending`` (``[S]`` bool over ``self.space(state, over)``),
        and act: ``(states, actions, reached, reason)`` as :func:`plan_for_goal`."""
        if ending is not None and over is None and not exact_fits(state):
            raise ValueError("an ending in a layout too large to enumerate is over a goal's abstraction: give over")
        # The plan is the target's alone; an ending is keyed by its digest, not its [S] bytes (megabytes).
        target = goal if ending is None else hashlib.blake2b(np.packbits(ending).tobytes(), digest_size=16).digest()
        key = (state, target, max_steps, over if ending is not None and not exact_fits(state) else None)
        if key not in self.plans:
            if len(self.plans) >= _PLANS_KEPT:
                self.plans.pop(next(iter(self.plans)))
            self.plans[key] = (plan_for_goal(self.space(state, goal), state, goal, self.library, self.settings,
                                             max_steps) if ending is None else
                               plan_for_states(self.space(state, over), ending, self.settings, max_steps))
        return self.plans[key]
