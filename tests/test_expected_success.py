"""Following ends where what was meant most probably holds (``goal_plans.expected_success_states``,
the language models' ``expected_success`` and ``step_cost``)."""

from __future__ import annotations

import numpy as np
import pytest

from groundlang.confidence import GoalMasks
from groundlang.corpus import example_corpus_path, read_state_file
from groundlang.goal_plans import expected_success_states, planning_space
from groundlang.inference.end_states import distances
from groundlang.logic.atoms import parse_goal
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.features import goal_mask
from groundlang.model.language_models import get_language_model
from groundlang.model.pf_tables import pf_tables

LIBRARY = TaskLibrary.load()
STATE = read_state_file(example_corpus_path() / "novel_a.state", "sokoban")  # the star, three rooms


@pytest.fixture(scope="module")
def space():
    return planning_space(STATE, None, LIBRARY)


def _mask(space, goal: str) -> np.ndarray:
    return goal_mask(space, parse_goal(goal), pf_tables(STATE.layout, LIBRARY.tabulation_program))


def test_two_goals_that_can_hold_at_once_are_both_ended_in(space):
    """0.6 the star in the red room, 0.4 the agent there: ending where both hold succeeds with 1.0, not 0.6."""
    star, agent = "toyInRoom(block0, room2)", "agentInRoom(agent0, room2)"
    goals = [(parse_goal(star), 0.6), (parse_goal(agent), 0.4)]
    target, said = expected_success_states(goals, GoalMasks(space, LIBRARY), step_cost=0.0)
    assert target.any() and (target <= (_mask(space, star) & _mask(space, agent))).all()
    assert said == parse_goal(star)
    # the most probable goal alone is the special case of a posterior sure of it: its nearest states
    alone, _ = expected_success_states([(parse_goal(star), 1.0)], GoalMasks(space, LIBRARY), step_cost=0.0)
    assert (alone == _mask(space, star)).all()


def test_a_step_cost_keeps_a_small_share_from_buying_a_long_detour(space):
    """0.99 the agent in the red room, 0.01 the star there too: pushing the star for 0.01 is not worth its
    steps at a cost of 0.005 a step, and is at none."""
    star, agent = "toyInRoom(block0, room2)", "agentInRoom(agent0, room2)"
    goals = [(parse_goal(agent), 0.99), (parse_goal(star), 0.01)]
    dist = distances(space)
    costly, said = expected_success_states(goals, GoalMasks(space, LIBRARY), step_cost=0.005)
    assert said == parse_goal(agent) and not (costly & _mask(space, star)).any()
    reach = _mask(space, agent) & (dist >= 0)
    assert dist[costly].max() == dist[reach].min()  # the nearest states where the agent is in the red room
    free, _ = expected_success_states(goals, GoalMasks(space, LIBRARY), step_cost=0.0)
    assert (free <= _mask(space, star) & _mask(space, agent)).all()


def test_goals_that_cannot_hold_at_once_go_with_the_more_probable(space):
    goals = [(parse_goal("agentInRoom(agent0, room0)"), 0.45), (parse_goal("agentInRoom(agent0, room2)"), 0.55)]
    target, said = expected_success_states(goals, GoalMasks(space, LIBRARY), step_cost=0.005)
    assert said == parse_goal("agentInRoom(agent0, room2)") and (target <= _mask(space, "agentInRoom(agent0, room2)")).all()


def test_the_settings_are_checked_and_kept():
    model = get_language_model("parse")
    assert model.settings()["expected_success"] is True and model.settings()["step_cost"] == 0.005
    assert get_language_model("bow").settings()["step_cost"] == 0.005
    for bad in (-0.1, 1.5):
        with pytest.raises(ValueError, match="step_cost must be between 0 and 1"):
            get_language_model("parse", step_cost=bad)
    with pytest.raises(ValueError, match="step_cost: expected a number, not nan"):
        get_language_model("parse", step_cost=float("nan"))


def test_no_goal_within_reach_leaves_the_goal_acted_on_to_say_so():
    """Walled in, the agent can reach no state where a goal holds: staying put must not count as success."""
    from pathlib import Path

    walled = read_state_file(Path(__file__).parent / "fixtures" / "bad_input" / "walled_in.state", "sokoban")
    space = planning_space(walled, None, LIBRARY)
    red = "agentInRoom(agent0, room1)"
    assert not _mask_of(walled, space, red)[distances(space) >= 0].any()
    assert expected_success_states([(parse_goal(red), 1.0)], GoalMasks(space, LIBRARY), step_cost=0.005) is None


def _mask_of(state, space, goal: str) -> np.ndarray:
    return goal_mask(space, parse_goal(goal), pf_tables(state.layout, LIBRARY.tabulation_program))
