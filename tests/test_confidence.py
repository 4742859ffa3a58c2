"""Confidence measures (ECE, risk-coverage, AUROC, threshold) and goals merged by their outcome."""

from __future__ import annotations

import math

import pytest

from groundlang.confidence import (GoalGroup, accuracy_at_coverage, auroc, calibration_report, choose_threshold,
                                   expected_calibration_error, format_calibration, group_goals, reliability,
                                   risk_coverage)
from groundlang.corpus import parse_state
from groundlang.logic.atoms import parse_goal
from groundlang.model.statespace import enumerate_states

# The star sits in the corner of room0 (red): walls on two sides, so nothing can push it out.
STUCK = "room,10,0,8,5,0 room,1,5,8,10,0 room,5,10,8,15,0 door,5,3,5,3 door,10,5,10,5 block,12,0,1,1 agent,7,5"


def test_ece_of_a_perfectly_calibrated_and_of_an_overconfident_model():
    # 10 at confidence 0.8, 8 right: calibrated; 10 at 0.9, 5 right: off by 0.4
    assert expected_calibration_error([0.8] * 10, [True] * 8 + [False] * 2) == pytest.approx(0.0)
    assert expected_calibration_error([0.9] * 10, [True] * 5 + [False] * 5) == pytest.approx(0.4)
    rows = reliability([0.05, 0.95, 1.0], [False, True, True])
    assert [(r["n"], r["accuracy"]) for r in rows] == [(1, 0.0), (2, 1.0)]  # 1.0 falls in the last bin


def test_risk_coverage_drops_the_least_confident_first_and_keeps_ties_together():
    conf = [0.9, 0.8, 0.8, 0.3]
    right = [True, True, False, False]
    assert risk_coverage(conf, right) == [(1.0, 0.5), (0.75, pytest.approx(2 / 3)), (0.25, 1.0)]
    assert accuracy_at_coverage(conf, right, 0.5) == (pytest.approx(2 / 3), 0.75)  # ties: 0.75 is the least above 0.5
    assert accuracy_at_coverage(conf, right, 0.25) == (1.0, 0.25)


def test_auroc_counts_pairs_and_ties_half():
    assert auroc([0.9, 0.8, 0.2, 0.1], [True, True, False, False]) == 1.0
    assert auroc([0.1, 0.9], [True, False]) == 0.0
    assert auroc([0.5, 0.5], [True, False]) == 0.5
    assert math.isnan(auroc([0.5, 0.6], [True, True]))


def test_threshold_is_the_widest_that_reaches_the_target():
    conf = [0.95, 0.9, 0.8, 0.7, 0.6]
    right = [True, True, True, False, True]
    assert choose_threshold(conf, right, 1.0) == 0.8
    assert choose_threshold(conf, right, 0.8) == 0.6  # 4 of 5
    assert choose_threshold([0.9], [False], 0.5) == 1.0  # none reaches it: act on nothing below certainty
    report = calibration_report(conf, right, coverages=(0.6,), threshold=0.8)
    assert report["threshold"] == {"min_confidence": 0.8, "acted": 3, "coverage": 0.6, "accuracy": 1.0}
    assert report["at_coverage"] == [{"coverage": 0.6, "reached": 0.6, "accuracy": 1.0}]


def test_the_report_says_what_it_counts_and_when_nothing_was_acted_on():
    report = calibration_report([0.4, 0.6, 0.2], [True, False, True], threshold=0.7)
    assert report["threshold"]["acted"] == 0 and math.isnan(report["threshold"]["accuracy"])
    text = format_calibration(report, "confidence", unit="executions")
    assert text.startswith("confidence (3 executions): expected calibration error")
    assert "acting at confidence >= 0.7 (--min-confidence): 0 of 3 (0.0%), none acted on" in text
    assert "nan" not in text
    acted = format_calibration(calibration_report([0.8, 0.9, 0.2], [True, False, True], threshold=0.7))
    assert "(3 commands)" in acted and "2 of 3 (66.7%), accuracy 50.00%" in acted
    one = format_calibration(calibration_report([0.9], [True], threshold=0.7), unit="executions")
    assert "(1 execution)" in one and "AUROC for correctness - (every reading right, or every one wrong)" in one


def test_goals_that_hold_in_the_same_states_count_as_one():
    space = enumerate_states(parse_state(STUCK, "sokoban"))
    goals = [(parse_goal("toyInRoom(block0, room1)"), 0.4), (parse_goal("agentInRoom(agent0, room2)"), 0.35),
             (parse_goal("toyInRoom(block0, room2)"), 0.25)]
    groups = group_goals(goals, space)
    # The star can reach neither room: both goals hold nowhere, one outcome with 0.65 of the mass.
    assert [g.probability for g in groups] == [pytest.approx(0.65), pytest.approx(0.35)]
    assert groups[0].goals == (goals[0][0], goals[2][0]) and groups[0].goal == goals[0][0]
    assert groups[1] == GoalGroup((goals[1][0],), 0.35)


def test_given_achievable_moves_the_mass_of_goals_out_of_reach_to_the_others():
    import numpy as np

    from groundlang.confidence import GoalMasks, given_achievable, unachievable_goals
    from groundlang.model.relevance import placement_sample

    state = parse_state(STUCK, "sokoban")
    space = enumerate_states(state)
    stuck1, agent2, stuck2 = (parse_goal(g) for g in ("toyInRoom(block0, room1)", "agentInRoom(agent0, room2)",
                                                      "toyInRoom(block0, room2)"))
    masks = GoalMasks(space)
    assert unachievable_goals([stuck1, agent2, stuck2], space, masks=masks) == {stuck1, stuck2}
    # readings of the same goal share it; the reachable goal takes the whole mass
    probs = np.array([0.3, 0.1, 0.35, 0.25])
    given = given_achievable(probs, [stuck1, stuck1, agent2, stuck2], masks)
    assert given.tolist() == pytest.approx([0.0, 0.0, 1.0, 0.0])
    # when no goal can be reached, nothing is ruled out (acting fails and says so)
    assert given_achievable(np.array([0.6, 0.4]), [stuck1, stuck2], masks).tolist() == [0.6, 0.4]
    # a sample of placements cannot say what is reachable: nothing changes
    sample = placement_sample(state, count=256)
    assert unachievable_goals([stuck1, agent2], sample) == set()
    assert given_achievable(probs, [stuck1, stuck1, agent2, stuck2], GoalMasks(sample)).tolist() == probs.tolist()


def test_out_of_reach_is_the_mass_on_goals_no_reachable_state_satisfies():
    import numpy as np

    from groundlang.confidence import GoalMasks, out_of_reach, unachievable_goals
    from groundlang.model.relevance import placement_sample

    state = parse_state(STUCK, "sokoban")
    masks = GoalMasks(enumerate_states(state))
    stuck1, agent2, stuck2 = (parse_goal(g) for g in ("toyInRoom(block0, room1)", "agentInRoom(agent0, room2)",
                                                      "toyInRoom(block0, room2)"))
    out = unachievable_goals({stuck1, agent2, stuck2}, masks.space, masks=masks)
    share, goal = out_of_reach(np.array([0.3, 0.1, 0.35, 0.25]), [stuck1, stuck1, agent2, stuck2], out)
    assert share == pytest.approx(0.65) and goal == stuck1  # readings of one goal summed: 0.4 against 0.25
    assert out_of_reach(np.array([0.6, 0.4]), [stuck1, stuck2], out) == (pytest.approx(1.0), stuck1)  # all of it
    assert out_of_reach(np.array([1.0]), [agent2], out) == (0.0, None)
    sample = placement_sample(state, count=256)  # a sample cannot say what is out of reach
    assert out_of_reach(np.array([0.5, 0.5]), [stuck1, agent2],
                        unachievable_goals({stuck1, agent2}, sample, masks=GoalMasks(sample))) == (0.0, None)
