"""Rollouts: greedy runs reach the goal and terminate, limits are honoured, sampling is reproducible by seed."""

from __future__ import annotations

import numpy as np
import pytest

from groundlang.inference.acting import Rollout, rollout, rollout_states, stop_before
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


def test_rollout_states_turns_a_trajectory_into_corpus_states_and_actions():
    from groundlang.model.statespace import enumerate_states
    from groundlang.model.world import Action, Agent, Door, Layout, Room, State, Toy, get_palette, step

    rooms = (Room("green", 0, 6, 6, 3), Room("red", 0, 3, 6, 0))
    layout = Layout(rooms, (Door(2, 3, 2, 3),), (("yellow", "star"),), get_palette("sokoban"))
    start = State(layout, Agent(1, 1), (Toy("yellow", "star", 4, 4),))
    space = enumerate_states(start)
    goal = np.array([space.state_at(i).positions[0, 1] == 4 for i in range(space.num_states)])  # agent at y = 4
    path = rollout(space.next_state, solve_task(space.next_state, goal), start=space.index_of(start), goal_mask=goal)
    states, actions = rollout_states(space, path)
    assert path.reason == "goal" and states[0] == start and len(states) == len(actions) + 1
    assert all(isinstance(a, Action) for a in actions)
    for before, action, after in zip(states, actions, states[1:]):
        assert step(before, action) == after
    assert states[-1].positions[0, 1] == 4


def test_stop_before_cuts_a_trajectory_at_its_first_flagged_move():
    path = Rollout(np.array([0, 1, 1, 2]), np.array([2, 0, 2]), "goal")
    cut = stop_before(path, [False, True, True])
    assert cut.states.tolist() == [0, 1] and cut.actions.tolist() == [2] and cut.reason == "scenery"
    assert stop_before(path, [False] * 3) is path
