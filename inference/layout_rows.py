"""The behaviour log-likelihoods of the demonstrations of one layout under its candidate goals, the rows of
:func:`groundlang.inference.likelihoods.behaviour_likelihood_table` (which caches them): in the whole state space
where it fits, else per demonstration in a relevance abstraction or stepwise."""

from __future__ import annotations

import logging

import numpy as np

from groundlang.inference.planning import as_transitions, demonstration_log_likelihood, solve_task, threads_for

__all__ = ["layout_rows"]

logger = logging.getLogger(__name__)


def layout_rows(initial, by_goal: dict, instances, tables, settings, method: str):
    """``(goal, [((i, k), value)])`` per goal of one layout: in its whole state space where it fits (or ``method``
    says "exact"), else per demonstration, every goal in a relevance abstraction or stepwise
    (inference/stepwise.py), all solved together."""
    from groundlang.inference.stepwise import approximate_likelihoods
    from groundlang.model.relevance import exact_fits

    if method == "exact" or (method == "auto" and exact_fits(initial)):
        yield from _exact_rows(initial, by_goal, instances, tables, settings)
        return
    by_demo: dict = {}  # actions -> [(goal, i, k)]
    for goal, entries in by_goal.items():
        for i, k in entries:
            by_demo.setdefault(tuple(int(a) for a in instances[i].actions), []).append((goal, i, k))
    for rows in by_demo.values():
        goals = list(dict.fromkeys(g for g, _, _ in rows))
        inst = instances[rows[0][1]]
        values = approximate_likelihoods(initial, goals, list(inst.states), inst.actions, tables, settings)
        for goal, value in zip(goals, values):
            yield goal, [((i, k), float(value)) for g, i, k in rows if g == goal]


def _exact_rows(initial, by_goal: dict, instances, tables, settings):
    """``(goal, [((i, k), value)])`` per goal: the whole state space, enumerated once, solved per goal."""
    from groundlang.model.features import goal_mask
    from groundlang.model.relevance import state_space_for
    from groundlang.model.statespace import trajectory_indices

    space = state_space_for(initial, method="exact")
    with threads_for(space.num_states):  # small spaces: one thread (others may share the cores)
        transitions = as_transitions(space.next_state)
    paths: dict[int, np.ndarray] = {}
    for goal, entries in by_goal.items():
        with threads_for(space.num_states):
            result = solve_task(transitions, goal_mask(space, goal, tables), settings)
        if not result.converged:
            logger.warning("goal %s: soft value iteration stopped after %d sweeps (residual %.3g)",
                           " ".join(map(str, goal)), result.sweeps, result.residual)
        out = []
        for i, k in entries:
            if i not in paths:
                paths[i] = trajectory_indices(space, list(instances[i].states))
            actions = [int(a) for a in instances[i].actions]
            out.append(((i, k), float(demonstration_log_likelihood(result.log_policy, paths[i], actions))))
        yield goal, out
