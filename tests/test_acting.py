"""Rollouts: greedy runs reach the goal and terminate, limits are honoured, sampling is reproducible by seed."""

from __future__ import annotations

import numpy as np
import pytest

from groundlang.inference.acting import rollout
from groundlang.inference.planning import PlanningError, soft_value_iteration, solve_task

# The corridor of test_planning: 0-1-2-3, action 2 = east, 3 = west, 0 and 1 bump into walls.
CORRIDOR = np.array([[0, 0, 1, 0], [1, 1, 2, 0], [2, 2, 3, 1], [3, 3, 3, 2]])


def test_greedy_rollout_reaches_the_goal_and_terminates():
    goal = np.array([False, False, False, True])
    result = solve_task(CORRIDOR, goal)
    path = rollout(CORRIDOR, result, start=0)
    assert path.states.tolist() == [0, 1, 2, 3] and path.actions.tolist() == [2, 2, 2]
    assert path.reason == "terminated"
    stopped = rollout(CORRIDOR, result, start=0, goal_mask=goal)
    assert stopped.reason == "goal" and stopped.states[-1] == 3
    capped = rollout(CORRIDOR, result.q_values, start=0, max_steps=2)
    assert capped.reason == "max_steps" and len(capped.actions) == 2


def test_sampled_rollouts_are_reproducible_by_seed():
    result = soft_value_iteration(CORRIDOR, -0.3, 0.9, 1.0, stop_reward=np.array([0, 0, 0, 3.0]))
    a = rollout(CORRIDOR, result, greedy=False, seed=7, max_steps=30)
    b = rollout(CORRIDOR, result, greedy=False, seed=7, max_steps=30)
    assert a.states.tolist() == b.states.tolist() and a.reason == b.reason
    runs = {tuple(rollout(CORRIDOR, result, greedy=False, seed=s, max_steps=30).states) for s in range(20)}
    assert len(runs) > 1


def test_a_policy_table_of_the_wrong_size_is_a_value_error():
    with pytest.raises(PlanningError, match=r"policy must be \[4, A\], got shape \(3, 5\)"):
        rollout(CORRIDOR, np.zeros((3, 5)))
