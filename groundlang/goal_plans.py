"""Planning for a grounded goal in a state: the state space to plan in, and the plan carried out.

Plans depend on the world only, never on the words: :class:`groundlang.learner.Learner` keeps them
per (state, goal, step limit).
"""

from __future__ import annotations

import numpy as np

from groundlang.inference.acting import rollout, rollout_states, stop_before
from groundlang.inference.planning import TaskSettings, solve_task
from groundlang.logic.atoms import Atom
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.features import goal_mask
from groundlang.model.pf_tables import pf_tables
from groundlang.model.relevance import exact_fits, placement_sample, pushes_scenery, state_space_for
from groundlang.model.statespace import StateSpace
from groundlang.model.world import State

__all__ = ["planning_space", "plan_for_goal"]


def planning_space(state: State, goal: tuple[Atom, ...] | None, library: TaskLibrary) -> StateSpace:
    """The exact state space where it fits; else, to plan for ``goal``, its relevance abstraction, and
    to compare goals (``goal`` None), a sample of placements."""
    tables = pf_tables(state.layout, library.tabulation_program)
    return (placement_sample(state) if not exact_fits(state) and goal is None
            else state_space_for(state, goal or (), tables=tables))


def plan_for_goal(space: StateSpace, state: State, goal: tuple[Atom, ...], library: TaskLibrary,
                  settings: TaskSettings, max_steps: int) -> tuple[list, list, bool, str]:
    """Plan for ``goal`` in ``space`` (built from ``state``) and act: ``(states, actions, reached, reason)``,
    at most ``max_steps`` moves, stopping before a move that would push a toy the space holds still."""
    mask = goal_mask(space, goal, pf_tables(state.layout, library.tabulation_program))
    solved = solve_task(space.next_state, mask, settings)
    trajectory = rollout(space.next_state, solved, 0, goal_mask=mask, max_steps=max_steps)
    trajectory = stop_before(trajectory, pushes_scenery(space, trajectory.states[:-1], trajectory.actions))
    states, actions = rollout_states(space, trajectory)
    reached = bool(mask[int(trajectory.states[-1])])
    # The space holds only states reachable from ``state``: no goal state in it means no plan can succeed
    # (in a relevance abstraction: none that leaves the toys it holds still where they are).
    reason = trajectory.reason if reached or bool(np.asarray(mask).any()) else "unreachable"
    return states, actions, reached, reason
