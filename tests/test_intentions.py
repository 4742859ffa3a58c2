"""Multiple-intentions EM separates demonstrations of two goals."""

from __future__ import annotations

import numpy as np
import pytest

from groundlang.inference.acting import rollout
from groundlang.inference.intentions import multiple_intentions
from groundlang.inference.planning import PlanningError, solve_task


def _world():
    from groundlang.model.pf_tables import pf_tables
    from groundlang.model.statespace import enumerate_states
    from groundlang.model.world import Agent, Door, Layout, Room, State, get_palette

    rooms = (Room("green", 0, 10, 6, 4), Room("red", 6, 10, 10, 4), Room("blue", 0, 4, 10, 0))
    doors = (Door(3, 4, 3, 3), Door(8, 4, 8, 3), Door(5, 6, 6, 6))
    layout = Layout(rooms, doors, (), get_palette("sokoban"))
    return enumerate_states(State(layout, Agent(4, 2), ())), pf_tables(layout)


def _demos(space, goal, starts, seed):
    expert = solve_task(space.next_state, goal)
    out = []
    for k, s in enumerate(starts):
        path = rollout(space.next_state, expert, start=s, greedy=False, seed=seed + k, max_steps=60)
        assert goal[path.states[-1]]
        out.append((path.states, path.actions))
    return out


@pytest.mark.slow
def test_em_separates_demonstrations_of_two_goals():
    from groundlang.logic.atoms import parse_atom
    from groundlang.model.features import feature_matrix, goal_mask, position_atoms

    space, tables = _world()
    atoms = position_atoms(space.layout)
    red = goal_mask(space, [parse_atom("agentInRoom(agent0, room1)")], tables)
    green = goal_mask(space, [parse_atom("agentInRoom(agent0, room0)")], tables)
    blue = goal_mask(space, [parse_atom("agentInRoom(agent0, room2)")], tables)
    starts = np.flatnonzero(blue)[::3][:8]  # the agent starts in the blue room
    assert len(starts) == 8
    demos = _demos(space, red, starts[::2], 0) + _demos(space, green, starts[1::2], 10)
    features = feature_matrix(space, atoms, tables)
    result = multiple_intentions(space.next_state, features, demos, 2, seed=0)
    labels = result.assignments
    assert len(set(labels[:4])) == 1 and len(set(labels[4:])) == 1 and labels[0] != labels[4]
    assert result.responsibilities.min(axis=1).max() < 0.05  # confident
    # Each cluster's largest weight is its goal.
    assert atoms[int(np.argmax(result.weights[labels[0]]))] == parse_atom("agentInRoom(agent0, room1)")
    assert atoms[int(np.argmax(result.weights[labels[4]]))] == parse_atom("agentInRoom(agent0, room0)")
    np.testing.assert_allclose(result.priors, [0.5, 0.5], atol=0.05)
    again = multiple_intentions(space.next_state, features, demos, 2, seed=0)
    np.testing.assert_array_equal(again.responsibilities, result.responsibilities)


def test_number_of_intentions_is_checked():
    ns = np.array([[1, 0, 0, 0], [1, 0, 1, 1]])
    with pytest.raises(PlanningError, match="num_intentions"):
        multiple_intentions(ns, np.zeros((2, 1)), [([0, 1], [0])], 2)
