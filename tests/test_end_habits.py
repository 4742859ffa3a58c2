"""End habits: what the demonstrations of a goal also left true where they ended
(``inference.end_habits``), learned in training, saved with the model, and weighed where following ends."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from groundlang.bdm import parse_bdm_state
from groundlang.bdm_check import default_library
from groundlang.confidence import GoalMasks
from groundlang.goal_plans import expected_success_states, planning_space
from groundlang.inference.end_habits import MOVED, EndHabits, demonstrated_pairs, known_new_relations, new_relations
from groundlang.inference.end_states import distances
from groundlang.learner import Learner
from groundlang.logic.atoms import parse_goal
from groundlang.model.language_models import get_language_model
from groundlang.model_io import ModelFormatError, signed
from groundlang.pair_corpus import training_instances

LIBRARY = default_library()
_ROOMS = ("door0 (door): [locked: {0} top: {4} left: {6} bottom: {4} right: {6} canbelocked: {false} ] , "
          "door1 (door): [locked: {0} top: {4} left: {2} bottom: {4} right: {2} canbelocked: {false} ] , "
          "room0 (room): [top: {4} left: {0} bottom: {0} right: {8} colour: {red} ] , "
          "room1 (room): [top: {8} left: {0} bottom: {4} right: {4} colour: {green} ] , "
          "room2 (room): [top: {8} left: {4} bottom: {4} right: {8} colour: {blue} ] , ")


def _state(agent: tuple[int, int], chair: tuple[int, int] = (6, 7)):
    """Three rooms; a chair in the blue room (top right), the agent where given."""
    return parse_bdm_state("{agent0 (agent): [x: {%d} y: {%d} direction: {south} ] , " % agent + _ROOMS
                           + "block0 (block): [x: {%d} y: {%d} shape: {chair} colour: {red} ] , }" % chair)[0]


START = _state((2, 6))  # in the green room


def _mask(masks: GoalMasks, goal: str) -> np.ndarray:
    return masks.mask(parse_goal(goal))


def _unbound(relations) -> set[str]:
    return {r for r in relations if "[" not in r}


def test_a_demonstration_shows_the_relations_that_newly_hold_at_its_end():
    assert new_relations(START, _state((6, 5)), LIBRARY) == {"agentInRoom"}
    # below the chair: next to it, neither left nor right of it
    assert _unbound(new_relations(START, _state((6, 6)), LIBRARY)) == {"agentInRoom", "agentNextToToy"}
    left = new_relations(START, _state((5, 7)), LIBRARY)
    assert _unbound(left) == {"agentInRoom", "agentNextToToy", "agentLeftOfToy"}
    # two new facts naming one object: the toy the agent is left of is the toy it is next to
    assert {"agentLeftOfToy[1]=agentNextToToy[1]", "agentNextToToy[1]=agentLeftOfToy[1]"} <= left
    assert new_relations(START, START, LIBRARY) == frozenset()
    # a relation that already held is not new: the agent stays in the green room
    assert new_relations(START, _state((1, 6)), LIBRARY) == frozenset()


def test_with_bound_habits_the_agent_ends_in_the_room_the_toy_was_pushed_into():
    """Demonstrators who pushed a chair into a room stood in that room at the end. From the doorway below the
    blue room, pushing the chair into it, the follower may step back into the red room or push on into the
    blue one: the relation's habit ("in some room") weighs both alike, the bound habit only the blue room."""
    start = _state((6, 2), chair=(6, 3))
    pushed = _state((6, 5), chair=(6, 6))
    shown = new_relations(start, pushed, LIBRARY)
    assert {"toyInRoom", "agentInRoom", "agentInRoom[1]=toyInRoom[1]", "toyInRoom[1]=agentInRoom[1]"} <= shown
    habits = EndHabits.learn([(start, pushed)] * 3, LIBRARY)
    assert habits.relations == {"toyInRoom", "agentInRoom", MOVED}  # bound ones apart (next to it all along)
    assert ("agentInRoom[1]=toyInRoom[1]", 1, "toyInRoom", 1) in habits.bound["agentInRoom"]
    # q(b | {L}) = 3 / (3 + 1): every one of three demonstrations, shrunk by one that did not show it
    assert habits.bound_table()["agentInRoom[1]=toyInRoom[1]"] == pytest.approx(3 / 4)
    assert habits.bound_table("overall")["agentInRoom[1]=toyInRoom[1]"] == pytest.approx((3 + 3.5 / 4) / 4)
    space = planning_space(start, None, LIBRARY)
    masks = GoalMasks(space, LIBRARY)
    goal = parse_goal("toyInRoom(block0, room2)")
    in_blue, in_red = _mask(masks, "agentInRoom(agent0, room2)"), _mask(masks, "agentInRoom(agent0, room0)")
    plain, _ = expected_success_states([(goal, 1.0)], masks, 0.005, habits)
    assert (plain & in_red).any()  # as good as the blue room by the relation's habit, and nearer
    bound, said = expected_success_states([(goal, 1.0)], masks, 0.005, habits, bound=True)
    assert said == goal and bound.any() and (bound <= in_blue & _mask(masks, "toyInRoom(block0, room2)")).all()
    dist = distances(space)
    (weight,) = habits.weights([goal], masks, dist >= 0, bound=True)
    (unbound,) = habits.weights([goal], masks, dist >= 0)
    goal_states = _mask(masks, "toyInRoom(block0, room2)") & (dist >= 0)
    # in the blue room: worth as much as without the binding; in the red room: less, by the bound share
    assert np.allclose(weight[goal_states & in_blue], unbound[goal_states & in_blue])
    assert (weight[goal_states & in_red] < unbound[goal_states & in_red]).all()
    assert weight.max() <= 1.0 and weight.min() > 0.0


def test_the_rate_is_counted_and_shrunk_by_one_demonstration_that_did_not_show_it():
    habits = EndHabits(((frozenset({"agentInRoom"}), 3), (frozenset({"agentInRoom", "agentNextToToy"}), 1)))
    assert habits.demonstrations == 4
    # q(R | L) = n(L, R) / (n(L) + 1)
    assert habits.rate("agentNextToToy", frozenset({"agentInRoom"})) == pytest.approx(1 / (4 + 1))
    # every demonstration that went next to a toy changed rooms, yet one more might not: below 1
    assert habits.rate("agentInRoom", frozenset({"agentNextToToy"})) == pytest.approx(1 / (1 + 1))
    # a goal no demonstration showed has no habit: none was seen
    assert habits.rate("agentNextToToy", frozenset({"toyInRoom"})) == 0.0
    assert EndHabits(()).rate("agentInRoom", frozenset()) == 0.0
    more = habits.plus([(START, _state((5, 7)))], LIBRARY)
    assert more.demonstrations == 5 and more.rate("agentLeftOfToy", frozenset({"agentNextToToy"})) == pytest.approx(
        1 / (2 + 1))
    with pytest.raises(ValueError, match="habit prior 'none': expected one of absent, overall"):
        habits.rate("agentInRoom", frozenset(), "none")


def test_with_the_overall_prior_the_rate_is_shrunk_towards_the_relations_own_rate():
    habits = EndHabits(((frozenset({"agentInRoom"}), 3), (frozenset({"agentInRoom", "agentNextToToy"}), 1)))
    # q(R | L) = (n(L, R) + p(R)) / (n(L) + 1), p(R) = (n(R) + 1/2) / (N + 1)
    assert habits.rate("agentNextToToy", frozenset({"agentInRoom"}), "overall") == pytest.approx((1 + 1.5 / 5) / (4 + 1))
    assert habits.rate("agentInRoom", frozenset({"agentNextToToy"}), "overall") == pytest.approx((1 + 4.5 / 5) / (1 + 1))
    # a goal no demonstration showed gets the relation's own rate
    assert habits.rate("agentNextToToy", frozenset({"toyInRoom"}), "overall") == pytest.approx(1.5 / 5)


def test_a_habit_no_demonstration_of_the_goal_showed_is_not_worth_a_step():
    """The example corpus: twelve demonstrations pushed the star into a room, none ended with the agent in a
    room it had not started in. Having pushed the star into the red room from its doorway, the agent stays
    there; shrunk towards the agent's overall rate of changing rooms (a half: the other twelve were sent to
    a room), that habit was worth 0.5 / 13 of the goal, a step back into the blue room (0.005)."""
    star = frozenset({"toyInRoom", MOVED})
    habits = EndHabits(((star, 12), (frozenset({"agentInRoom"}), 12)))
    assert habits.rate("agentInRoom", star) == 0.0
    assert habits.rate("agentInRoom", star, "overall") == pytest.approx((12.5 / 25) / 13)
    # where it ends: in the doorway, having pushed the chair into the blue room; "overall" took a step more
    pushed = _state((6, 4), chair=(6, 5))
    space = planning_space(pushed, None, LIBRARY)
    masks, dist = GoalMasks(space, LIBRARY), distances(space)
    goal = parse_goal("toyInRoom(block0, room2)")
    absent, _ = expected_success_states([(goal, 1.0)], masks, 0.005, habits)
    overall, _ = expected_success_states([(goal, 1.0)], masks, 0.005, habits, habit_prior="overall")
    assert set(dist[absent]) == {0}
    assert set(dist[overall]) == {1} and (overall <= _mask(masks, "agentInRoom(agent0, room0)")
                                          | _mask(masks, "agentInRoom(agent0, room2)")).all()


def test_following_ends_where_the_goals_usual_company_holds_too():
    """Sent to the blue room, demonstrators mostly stopped next to a toy there: one step more takes the
    agent next to the chair, where without habits it stops at the room's first cell."""
    space = planning_space(START, None, LIBRARY)
    masks = GoalMasks(space, LIBRARY)
    room, next_to = "agentInRoom(agent0, room2)", "agentNextToToy(agent0, block0)"
    goals = [(parse_goal(room), 1.0)]
    habits = EndHabits(((frozenset({"agentInRoom"}), 1), (frozenset({"agentInRoom", "agentNextToToy"}), 3)))
    plain, said = expected_success_states(goals, masks, 0.005)
    assert said == parse_goal(room) and not (plain & _mask(masks, next_to)).any()
    weighed, said = expected_success_states(goals, masks, 0.005, habits)
    assert said == parse_goal(room) and weighed.any()
    assert (weighed <= _mask(masks, room) & _mask(masks, next_to)).all()
    dist = distances(space)
    assert dist[weighed].min() == dist[plain].min() + 1
    # a habit is never worth more than the goal: a goal's states all weigh at most 1, so none leaves it
    for weight in habits.weights([parse_goal(room), parse_goal(next_to)], masks, dist >= 0):
        assert weight is not None and 0.0 < weight.min() and weight.max() <= 1.0


def test_with_moved_toys_a_habit_is_not_bought_by_pushing_a_toy_its_demonstrators_left_alone():
    """Sent to the blue room, demonstrators stopped next to a toy there, and never moved one. The chair is
    in the red room: a follower that counts only the company pushes it into the blue room to stand beside
    it; with moved_toys (a toy moved is counted as shown, and the company looked for where none moved) it
    walks to the blue room and leaves the chair where it is."""
    start = _state((2, 6), chair=(6, 2))
    space = planning_space(start, None, LIBRARY)
    masks = GoalMasks(space, LIBRARY)
    room = "agentInRoom(agent0, room2)"
    goals = [(parse_goal(room), 1.0)]
    habits = EndHabits(((frozenset({"agentInRoom"}), 1), (frozenset({"agentInRoom", "agentNextToToy"}), 3)))
    chair = space.positions[:, 1]
    pushed, _ = expected_success_states(goals, masks, 0.005, habits)
    assert (chair[pushed] != (6, 2)).any(axis=1).all()  # it ends where the chair was pushed along
    left, said = expected_success_states(goals, masks, 0.005, habits, moved_toys=True)
    assert said == parse_goal(room) and left.any()
    assert (chair[left] == (6, 2)).all() and (left <= _mask(masks, room)).all()
    # a pair that moved a toy shows it; a goal whose every state moves one (a toy's) is not weighed by it
    assert MOVED in new_relations(start, _state((6, 5), chair=(6, 6)), LIBRARY)
    toy_goal = parse_goal("toyInRoom(block0, room2)")
    dist = distances(space)
    (counted,) = habits.weights([toy_goal], masks, dist >= 0, moved_toys=True)
    (plain,) = habits.weights([toy_goal], masks, dist >= 0)
    assert np.array_equal(counted, plain)


def test_with_habits_made_true_a_relation_that_held_at_the_start_weighs_nothing():
    """Sent next to the chair, demonstrators mostly ended in a room they had not been in. The chair is in the
    green room, where the agent starts: every state next to it has the agent in the room it started in,
    which weighs those states by the habit where facts that hold count, and not where only facts made
    true count."""
    start = _state((1, 6), chair=(2, 6))
    space = planning_space(start, None, LIBRARY)
    masks = GoalMasks(space, LIBRARY)
    goal = parse_goal("agentNextToToy(agent0, block0)")
    habits = EndHabits(((frozenset({"agentNextToToy", "agentInRoom"}), 3), (frozenset({"agentNextToToy"}), 1)))
    dist = distances(space)
    (holding,) = habits.weights([goal], masks, dist >= 0)
    (made,) = habits.weights([goal], masks, dist >= 0, made_true=True)
    in_green = _mask(masks, "agentInRoom(agent0, room1)")
    in_blue = _mask(masks, "agentInRoom(agent0, room2)")
    assert holding[in_green].max() == 1.0 and made[in_green].max() < 1.0
    assert made[in_blue].min() == 1.0  # another room is made true there
    plain, _ = expected_success_states([(goal, 1.0)], masks, 0.005, habits)
    assert (plain <= in_green).all() and dist[plain].min() == 0  # next to the chair already, and in a room


def test_a_habit_that_cannot_hold_with_the_goal_does_not_make_another_goal_preferred():
    """0.6 the green room, without a toy, 0.4 the blue room, with the chair: demonstrators sent to the green
    room could not have stopped next to a toy there, so the green room keeps its 0.6 against the blue
    room's 0.4 (weighed by the habit, the green room would have had 0.6 x 0.25)."""
    state = _state((6, 1))  # in the red room below
    space = planning_space(state, None, LIBRARY)
    masks = GoalMasks(space, LIBRARY)
    green, blue = "agentInRoom(agent0, room1)", "agentInRoom(agent0, room2)"
    goals = [(parse_goal(green), 0.6), (parse_goal(blue), 0.4)]
    habits = EndHabits(((frozenset({"agentInRoom"}), 1), (frozenset({"agentInRoom", "agentNextToToy"}), 3)))
    target, said = expected_success_states(goals, masks, 0.005, habits)
    assert said == parse_goal(green) and (target <= _mask(masks, green)).all()
    weights = habits.weights([parse_goal(green), parse_goal(blue)], masks, distances(space) >= 0)
    assert weights[0] is None and weights[1] is not None


@pytest.fixture(scope="module")
def trained(williams_commands, tmp_path_factory):
    """The project's two-command fixture: its instances, a learner trained on them, and where it is saved."""
    instances = training_instances(williams_commands, LIBRARY, cache_dir=False).instances
    learner = Learner(library=LIBRARY, cache_dir=False).fit(instances)
    return instances, learner, learner.save(tmp_path_factory.mktemp("habits") / "model")


def test_learned_in_training_saved_with_the_model_and_switched_off_by_a_setting(williams_commands, trained):
    instances, learner, directory = trained
    pairs = demonstrated_pairs(instances)
    assert learner.habits.demonstrations == len(pairs) == sum(len(c.pairs) for c in williams_commands)
    assert learner.habits == EndHabits(()).plus(pairs, LIBRARY)
    # read from each pair's end-state evidence, which keeps them (in the cache too): no layout grounded again
    assert set(known_new_relations(instances, LIBRARY)) == set(pairs)
    assert Learner.load(directory).habits == learner.habits
    assert get_language_model("parse").settings()["end_habits"] is True
    off = Learner(get_language_model("parse", end_habits=False), library=LIBRARY, cache_dir=False).fit(instances)
    assert off.lm.settings()["end_habits"] is False and off.habits == learner.habits  # learned, not used


@pytest.mark.parametrize("setting, argument, default", [("habits_made_true", "made_true", False),
                                                       ("bound_habits", "bound", True)])
def test_a_habits_setting_reaches_where_following_ends_and_is_saved(williams_commands, trained, tmp_path,
                                                                    monkeypatch, setting, argument, default):
    import groundlang.learner as learner_module

    instances, _, _ = trained
    assert get_language_model("parse").settings()[setting] is default
    on = Learner(get_language_model("parse", **{setting: not default}), library=LIBRARY,
                 cache_dir=False).fit(instances)
    seen = []
    real = learner_module.expected_success_states

    def spy(*args, **kwargs):
        seen.append(kwargs.get(argument))
        return real(*args, **kwargs)

    monkeypatch.setattr(learner_module, "expected_success_states", spy)
    command = williams_commands[0]
    on.follow(command.text, command.pairs[0].start)
    assert seen == [not default]
    assert getattr(Learner.load(on.save(tmp_path / "model")).lm, setting) is (not default)


@pytest.mark.parametrize("value, expected", [
    ("many", "end_habits must be a list"),
    ([["agentInRoom", 3]], "is not \\[relations, count\\]"),
    ([[["agentInRoom"], 0]], "is not \\[relations, count\\]"),
    ([[["agentInRoom"], True]], "is not \\[relations, count\\]"),
    ([[["agentInRoom"], 1], [["agentInRoom"], 2]], "names a set of relations twice"),
    # a bound habit's position is read as a number when following: thousands of digits are refused on loading
    ([[["agentInRoom[" + "9" * 5000 + "]=toyInRoom[1]"], 3]], "is not a relation's name"),
    ([[["agent in room"], 3]], "is not a relation's name"),
    # each name costs a pass over the sets per goal followed: a table of very many names is refused
    ([[[f"r{i}" for i in range(2001)], 1]], "names 2001 relations and bound habits, more than the 2000"),
    ([[["agentInRoom\n", "toyInRoom"], 5]], "is not a relation's name"),  # $ would match before the newline
    # well formed, but no goal of the saved library is made of them: a forged table, not one training counted
    ([[["nonsense"], 3]], "end_habits names 'nonsense': no goal of the saved task library is made of it"),
    ([[["agentInRoom[1]=toyFlies[1]", "agentInRoom"], 3]], "end_habits names 'agentInRoom\\[1\\]=toyFlies\\[1\\]'"),
])
def test_a_damaged_table_in_a_saved_model_is_refused(trained, tmp_path, value, expected):
    directory = tmp_path / "model"
    shutil.copytree(trained[2], directory)
    meta = json.loads((directory / "model.json").read_text())
    meta["end_habits"] = value
    (directory / "model.json").write_text(json.dumps(signed(meta)))
    with pytest.raises(ModelFormatError, match=expected):
        Learner.load(directory)


def test_a_table_the_loader_would_refuse_is_not_saved_and_counts_stay_within_its_bounds(trained, tmp_path):
    """What a save writes, the loader reads back: counts are clamped where the table is bounded, a relation of
    a 134-letter name (a library may name one so) is read, and a table the loader would refuse is refused at
    the save, in one line, leaving the saved model as it was."""
    from groundlang.inference.end_habits import MAX_DEMONSTRATIONS

    _, learner, directory = trained
    big = EndHabits(((frozenset({"agentInRoom"}), MAX_DEMONSTRATIONS),)).plus([(START, _state((6, 5)))], LIBRARY)
    assert dict(big.shown)[frozenset({"agentInRoom"})] == MAX_DEMONSTRATIONS
    long_name = "agentIsIn" + "X" * 125
    assert EndHabits.from_json([[[long_name], 3]]).relations == {long_name}
    before = (directory / "model.json").read_bytes()
    saved = learner.habits
    try:
        learner.habits = EndHabits(((frozenset(f"r{i}" for i in range(2001)), 1),))
        with pytest.raises(ValueError, match="^cannot save the end habits: end_habits names 2001"):
            learner.save(directory)
    finally:
        learner.habits = saved
    assert (directory / "model.json").read_bytes() == before
