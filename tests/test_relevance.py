"""Relevance abstraction: soundness of its moves, the automatic choice, agreement with the exact space, and
acting in layouts of more than 10^9 states."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

from groundlang.corpus import example_corpus_path, read_corpus, read_state_file
from groundlang.goal_plans import plan_for_goal
from groundlang.inference.likelihoods import behaviour_likelihood_table
from groundlang.inference.planning import TaskSettings, demonstration_log_likelihood, solve_task
from groundlang.logic.atoms import parse_goal
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.features import goal_mask
from groundlang.model.interpretations import interpretations
from groundlang.model.pf_tables import pf_tables
from groundlang.model.relevance import (
    AbstractStateSpace,
    abstract_space,
    check_abstraction_possible,
    placement_sample,
    pushes_scenery,
    relevant_toys,
    state_space_for,
)
from groundlang.model.statespace import StateSpaceError, state_count_bound, trajectory_indices
from groundlang.model.world import Action, replay, step

FIXTURES = Path(__file__).parent / "fixtures"
LARGE = FIXTURES / "large"
SHARED_WILLIAMS = Path(__file__).parent.parent.parent / "shared" / "data" / "williams2018" / "train"


@pytest.fixture(scope="module")
def sixteen():
    """16x16, three toys (the star is block0), about 1.7 x 10^9 states."""
    return read_state_file(LARGE / "sixteen.state", "sokoban")


@pytest.fixture(scope="module")
def learner():
    from groundlang.learner import Learner

    return Learner(cache_dir=False).fit(read_corpus(example_corpus_path(), "sokoban").instances)


def _bound(state) -> int:
    return state_count_bound(int(state.layout.walkable.sum()), len(state.toys))


def test_the_large_fixtures_are_beyond_enumeration(sixteen):
    thirtytwo = read_state_file(LARGE / "thirtytwo.state", "sokoban")
    assert _bound(sixteen) > 10**9 and len(sixteen.toys) == 3 and sixteen.layout.width == 17
    assert _bound(thirtytwo) > 10**17 and len(thirtytwo.toys) == 5 and thirtytwo.layout.width == 33


def test_every_move_of_the_abstraction_is_the_real_move(sixteen):
    space = abstract_space(sixteen, (0,))
    assert isinstance(space, AbstractStateSpace) and space.scenery == (1, 2)
    # scenery stands still in every state
    assert (space.positions[:, 2:] == sixteen.positions[2:]).all()
    rng = np.random.default_rng(1)
    sampled = rng.choice(space.num_states, 300, replace=False)
    pushes = 0
    for s in sampled:
        flagged = pushes_scenery(space, np.full(4, s), np.arange(4))
        for a in Action:
            real = step(space.state_at(int(s)), a)
            if flagged[a]:  # blocked here, a push in the world
                assert space.next_state[s, a] == s and (real.positions[2:] != sixteen.positions[2:]).any()
                pushes += 1
            else:
                assert (real.positions == space.positions[space.next_state[s, a]]).all()
    assert pushes  # the sample met scenery
    # a state whose scenery stands elsewhere is not in the abstraction
    moved = sixteen.positions.copy()
    moved[2] = (6, 12)
    assert space.indices_of(np.stack([sixteen.positions, moved])).tolist() == [0, -1]


def test_relevant_toys_are_those_the_goal_names_and_the_demonstration_moves(sixteen):
    states = replay(sixteen, [Action.EAST] * 6)  # the agent walks from (3,3) east and pushes nothing
    assert relevant_toys(sixteen, parse_goal("toyInRoom(block2, room1)"), [states]) == (2,)
    pushed = replay(sixteen.with_positions(np.array([[9, 4], [10, 4], [5, 11], [13, 12]])), [Action.EAST])
    assert relevant_toys(pushed[0], parse_goal("agentInRoom(agent0, room1)"), [pushed]) == (0,)


def test_the_method_is_exact_where_it_fits_and_the_abstraction_otherwise(sixteen, caplog):
    small = read_state_file(FIXTURES / "two_toys.state", "sokoban")
    assert not isinstance(state_space_for(small, parse_goal("agentInRoom(agent0, room1)")), AbstractStateSpace)
    with caplog.at_level(logging.DEBUG, logger="groundlang.model.relevance"):
        space = state_space_for(sixteen, parse_goal("toyInRoom(block0, room2)"))
    assert isinstance(space, AbstractStateSpace) and space.relevant == (0,)
    assert "relevance abstraction, 41006 states (whole layout up to 1,714,870,920 > max_states=5,000,000" in caplog.text
    # two toys and the agent on 200 cells fit neither method under the default limit: one clear line
    with pytest.raises(StateSpaceError) as refused:
        state_space_for(sixteen, parse_goal("toyInRoom(block0, room2) toyInRoom(block1, room2)"))
    message = str(refused.value)
    assert "\n" not in message and "1,714,870,920" in message and "GROUNDLANG_MAX_STATES=" in message
    with pytest.raises(StateSpaceError, match="even the agent alone"):
        check_abstraction_possible(sixteen, max_states=100)


def test_scenery_in_the_way_is_let_move_when_the_goal_is_out_of_reach():
    # bag2yellow: the backpack blocks the only door; the agent cannot leave room0 without pushing it
    inst = next(i for i in read_corpus(FIXTURES / "sokoban2", "sokoban2").instances if i.name == "bag2yellow_0")
    goal = parse_goal("agentInRoom(agent0, room1)")
    tables = pf_tables(inst.initial_state.layout)
    walled = state_space_for(inst.initial_state, goal, method="abstraction")
    assert not goal_mask(walled, goal, tables).any()
    widened = state_space_for(inst.initial_state, goal, tables=tables, method="abstraction")
    assert widened.relevant == (0, 1) and goal_mask(widened, goal, tables).any()


def _likelihoods(inst, goals, tables, method):
    out = []
    for goal in goals:
        space = state_space_for(inst.initial_state, goal, [inst.states], tables=tables, method=method)
        solved = solve_task(space.next_state, goal_mask(space, goal, tables), TaskSettings())
        path = trajectory_indices(space, list(inst.states))
        out.append(float(demonstration_log_likelihood(solved.log_policy, path, [int(a) for a in inst.actions])))
    return np.array(out)


# Agreement stated for the shipped layouts (measured: top-goal values differ by at most 0.57 nats; goals
# that order differently all lie more than 140 nats below the top, where no posterior mass is).
TOP_TOLERANCE = 1.0  # nats, |exact - abstraction| for every candidate within NEAR of the exact top
NEAR = 20.0  # nats below the exact top: candidates that could matter to a posterior


@pytest.mark.parametrize("folder, palette, scenery", [
    (example_corpus_path(), "sokoban", True),
    pytest.param(FIXTURES / "sokoban2_corpus", "sokoban2", True, marks=pytest.mark.slow),
    (FIXTURES / "sokoban2", "sokoban2", True),
    (FIXTURES / "sokoban", "sokoban", False),  # its goals name every toy there is
])
def test_abstraction_likelihoods_rank_the_candidate_goals_as_the_exact_ones(folder, palette, scenery):
    library = TaskLibrary.load()
    demos = {}
    for inst in read_corpus(folder, palette).instances:
        demos.setdefault((inst.initial_state, tuple(inst.actions)), inst)
    abstracted = 0
    for inst in demos.values():
        goals = sorted({i.goal for i in interpretations(inst.initial_state, library)})
        tables = pf_tables(inst.initial_state.layout)
        exact = _likelihoods(inst, goals, tables, "exact")
        approx = _likelihoods(inst, goals, tables, "abstraction")
        assert (np.isfinite(exact) == np.isfinite(approx)).all(), inst.name
        assert np.argmax(approx) == np.argmax(exact), inst.name
        near = np.flatnonzero(exact >= exact.max() - NEAR)
        assert np.abs(exact[near] - approx[near]).max() <= TOP_TOLERANCE, inst.name
        assert list(near[np.argsort(-exact[near])]) == list(near[np.argsort(-approx[near])]), inst.name
        abstracted += any(len(relevant_toys(inst.initial_state, g, [inst.states])) < len(inst.initial_state.toys)
                          for g in goals)
    assert bool(abstracted) == scenery  # where expected, some goal left a toy as scenery: not vacuous


def test_behaviour_likelihoods_of_a_demonstration_in_a_layout_of_a_billion_states(sixteen, learner):
    goals = [parse_goal("toyInRoom(block0, room2)"), parse_goal("toyInRoom(block0, room1)"),
             parse_goal("agentInRoom(agent0, room2)")]
    # a demonstration of the first goal alone (following also ends where habits say: a step or two more)
    space = state_space_for(sixteen, goals[0], tables=pf_tables(sixteen.layout))
    states, actions, reached, _ = plan_for_goal(space, sixteen, goals[0], learner.library, learner.settings, 200)
    assert reached

    class Demo:
        initial_state = sixteen

    Demo.states, Demo.actions = tuple(states), tuple(actions)
    row, = behaviour_likelihood_table([Demo], [goals], cache_dir=False)
    assert np.isfinite(row[0]) and row[0] > -5 and row.argmax() == 0


def test_follow_reaches_the_goal_in_a_layout_of_more_than_a_billion_states(sixteen, learner, monkeypatch):
    result = learner.follow("take the star to the blue room", sixteen)
    assert [str(a) for a in result.goal] == ["toyInRoom(block0, room2)"]
    assert result.reached and result.reason == "goal"
    # replaying its actions in the real dynamics ends where it says: no step pushed scenery through a wall
    assert replay(sixteen, result.actions)[-1] == result.final_state
    assert learner.follow("go to the green room", sixteen).reached
    # Where only the goal's relevance abstraction can be planned in, following still ends where what was meant
    # most probably holds, habits weighed. None of the example corpus's demonstrators who pushed the star into
    # a room stood in another room at the end: following stops where the goal's own plan does, in the doorway.
    # With habits shrunk towards the agent's overall rate of changing rooms (habit_prior="overall"), being in
    # a room was worth a step: the star is pushed on into the room, and the agent stands in it.
    goal = result.goal
    alone, _, reached, _ = plan_for_goal(state_space_for(sixteen, goal, tables=pf_tables(sixteen.layout)), sixteen,
                                         goal, learner.library, learner.settings, 200)
    blue = sixteen.layout.rooms[2]

    def in_blue(state):
        (x, y) = state.positions[0]
        return blue.left < x < blue.right and blue.bottom < y < blue.top

    assert reached and not in_blue(alone[-1]) and not in_blue(result.final_state)
    assert result.final_state == alone[-1]
    monkeypatch.setattr(learner.lm, "habit_prior", "overall")
    pushed_on = learner.follow("take the star to the blue room", sixteen)
    assert pushed_on.reached and in_blue(pushed_on.final_state)
    # one move more than the goal's plan (its states are its moves and one): the star pushed on into the room
    assert len(pushed_on.actions) == len(alone)


def test_the_gym_env_plays_a_learned_policy_in_a_layout_of_a_billion_states(sixteen, learner):
    pytest.importorskip("gymnasium")
    from groundlang.gym_env import CleanupEnv, policy, run_episode

    env = CleanupEnv(sixteen, command="take the star to the blue room", goal="toyInRoom(block0, room2)")
    env.reset(seed=0)
    act = policy(learner, "take the star to the blue room", env)
    states, actions, total, info = run_episode(env, act, seed=0)
    assert total == 1.0 and info["goal_holds"]
    # the policy's moves are follow's; the episode ends where the env's goal first holds, and follow may go
    # on a step to end where demonstrators of such goals ended (in the room the star was pushed into)
    followed = learner.follow("take the star to the blue room", sixteen)
    assert [int(a) for a in actions] == [int(a) for a in followed.actions[:len(actions)]]
    assert len(followed.actions) - len(actions) <= 2


def test_the_gym_policy_ends_before_a_move_that_would_push_scenery(sixteen):
    """A policy planned in a relevance abstraction: where its best move would push a toy the abstraction holds
    still, the world would leave the planned space; it terminates there, as follow's plan stops ("scenery")."""
    pytest.importorskip("gymnasium")
    from groundlang.gym_env import CleanupAction
    from groundlang.gym_policy import CommandPolicy

    space = abstract_space(sixteen, (0,))
    states = np.arange(space.num_states)
    pushing = {a: pushes_scenery(space, states, np.full(space.num_states, int(a))) for a in Action}
    a = next(a for a in Action if pushing[a].any())
    s, free = int(np.flatnonzero(pushing[a])[0]), int(np.flatnonzero(~pushing[a])[0])
    log_policy = np.full((space.num_states, len(CleanupAction)), -5.0)
    log_policy[:, int(a)] = 0.0  # the same move everywhere: a push at s, an ordinary move at free
    act = CommandPolicy((), None, space, log_policy, np.zeros(space.num_states, dtype=bool))
    assert act(space.state_at(s)) == CleanupAction.TERMINATE
    assert act(space.state_at(free)) == CleanupAction(int(a))


@pytest.mark.slow
def test_follow_reaches_the_goal_in_a_32x32_layout_with_five_toys(learner):
    state = read_state_file(LARGE / "thirtytwo.state", "sokoban")
    result = learner.follow("take the star to the blue room", state)
    assert [str(a) for a in result.goal] == ["toyInRoom(block0, room2)"] and result.reached
    assert replay(state, result.actions)[-1] == result.final_state


def test_goals_are_compared_on_a_sample_of_placements(sixteen):
    from groundlang.confidence import group_goals

    sample = placement_sample(sixteen, count=4096)
    assert sample.positions.shape == (4096, 4, 2) and (sample.positions[0] == sixteen.positions).all()
    cells = sample.positions.astype(np.int64) @ np.array([1, 1000])
    assert all(len(set(row)) == 4 for row in cells)  # no two objects on one cell
    # a static atom changes nothing; another room does
    goals = [(parse_goal("agentInRoom(agent0, room2)"), 0.5),
             (parse_goal("agentInRoom(agent0, room2) roomIsBlue(room2)"), 0.3),
             (parse_goal("agentInRoom(agent0, room1)"), 0.2)]
    groups = group_goals(goals, sample)
    assert [len(g.goals) for g in groups] == [2, 1] and groups[0].probability == pytest.approx(0.8)


def test_a_williams_pair_in_a_16x16_layout_with_three_blocks_is_reached():
    from groundlang.bdm import read_bdm
    from groundlang.pair_tasks import reachable, shortest_actions

    pair = read_bdm(LARGE / "sixteen.bdm")[0].pairs[0]
    assert _bound(pair.start) > 10**9
    assert reachable(pair.start, pair.end) is True
    actions = shortest_actions(pair.start, pair.end)
    assert len(actions) == 26 and replay(pair.start, actions)[-1] == pair.end


@pytest.mark.slow
def test_the_williams_corpus_16x16_pairs_are_checked():
    if not SHARED_WILLIAMS.is_dir():
        pytest.skip(f"Williams et al. 2018 corpus not found at {SHARED_WILLIAMS} (it is not part of the repository)")
    from groundlang.bdm import read_bdm
    from groundlang.pair_tasks import shortest_actions

    pairs = [p for path in sorted(SHARED_WILLIAMS.glob("*.bdm")) for c in read_bdm(path) for p in c.pairs
             if p.start.layout.width == 17 and len(p.start.toys) == 3]
    assert pairs
    found = 0
    for pair in pairs:
        actions = shortest_actions(pair.start, pair.end)
        if actions is not None:
            assert replay(pair.start, actions)[-1] == pair.end
            found += 1
    assert found >= 0.9 * len(pairs)


@pytest.mark.parametrize("goal", ["toyInRoom(block0, room2)",
                                  "agentNextToToy(agent0, block2) agentInRoom(agent0, room1)"])
def test_williams_goals_are_planned_for_in_a_16x16_layout_with_three_blocks(goal):
    from importlib.resources import files

    from groundlang.bdm import read_bdm
    from groundlang.inference.acting import rollout, rollout_states
    from groundlang.labels import goal_holds

    library = TaskLibrary.load([str(files("groundlang.logic") / "domains" / "williams2018.lp")])
    start = read_bdm(LARGE / "sixteen.bdm")[0].pairs[0].start
    atoms = parse_goal(goal)
    tables = pf_tables(start.layout, library.tabulation_program)
    space = state_space_for(start, atoms, tables=tables)
    assert isinstance(space, AbstractStateSpace) and len(space.scenery) == 2
    mask = goal_mask(space, atoms, tables)
    path = rollout(space.next_state, solve_task(space.next_state, mask, TaskSettings()), 0, goal_mask=mask)
    states, actions = rollout_states(space, path)
    assert path.reason == "goal" and replay(start, actions)[-1] == states[-1]
    assert goal_holds(atoms, states[-1], library)


def test_a_log_line_names_the_pair_it_was_sized_for_and_only_while_reading(caplog):
    from groundlang.model.relevance import STATE_SOURCE, announce, reading_states

    with caplog.at_level(logging.DEBUG, logger="groundlang.model.relevance"):
        with reading_states():
            STATE_SOURCE.set("part2.bdm, line 262")
            announce("layout-a", 5, "state space: %d states", 41006)
            announce("layout-a", 5, "state space: %d states", 41006)  # again: at debug level, still named
        announce("layout-b", 5, "state space: %d states", 202)
    assert [r.getMessage() for r in caplog.records] == [
        "part2.bdm, line 262: state space: 41006 states", "part2.bdm, line 262: state space: 41006 states",
        "state space: 202 states"]
    assert [r.levelno for r in caplog.records] == [logging.INFO, logging.DEBUG, logging.INFO]
    assert STATE_SOURCE.get() is None


def test_check_names_the_pair_whose_layout_needed_the_abstraction():
    import subprocess
    import sys

    path = LARGE / "sixteen.bdm"
    run = subprocess.run([sys.executable, "-m", "groundlang.cli", "check", str(path)], capture_output=True,
                         text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    said = [t for t in run.stderr.splitlines() if "state space: relevance abstraction" in t]
    assert said and all(t.startswith(f"{path}, line 2: state space: relevance abstraction") for t in said), said


def test_reading_states_forgets_the_place_when_the_loop_fails():
    from groundlang.model.relevance import STATE_SOURCE, reading_states

    with pytest.raises(ValueError, match="bad pair"):
        with reading_states():
            STATE_SOURCE.set("part1.bdm, line 7")
            raise ValueError("bad pair")
    assert STATE_SOURCE.get() is None
