"""The gymnasium environment: checker, spaces, dynamics, rewards, determinism, and a learned policy."""

from __future__ import annotations

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="gymnasium is not installed (pip install groundlang[gym])")

from gymnasium.utils.env_checker import check_env  # noqa: E402

from groundlang.corpus import example_corpus_path, parse_state, read_state_file  # noqa: E402
from groundlang.gym_env import (  # noqa: E402
    CHANNELS,
    ENV_ID,
    CleanupAction,
    CleanupEnv,
    command_text,
    observation_positions,
    policy,
    run_episode,
)
from groundlang.model.world import Action, step  # noqa: E402

# Green room west, red north-east, blue south-east (the example corpus's layout); star at (8,2), agent at (9,7).
STATE = ("room,5,0,9,5,0 room,10,5,9,12,4 room,1,5,4,12,0 door,5,7,5,7 door,5,2,5,2 door,9,4,9,4 "
         "block,12,0,8,2 agent,9,7")


@pytest.fixture
def state():
    return parse_state(STATE, "sokoban")


def test_registered_and_check_env_passes():
    assert ENV_ID in gymnasium.registry
    env = gymnasium.make(ENV_ID, render_mode="rgb_array")
    check_env(env.unwrapped, skip_render_check=False)
    env.close()


def test_observation_channels(state):
    env = CleanupEnv(state, command="go to the green room")
    obs, info = env.reset(seed=0)
    grid = obs["grid"]
    assert grid.shape == (10, 13, 6) and grid.dtype == np.uint8
    assert obs["command"] == "go to the green room"
    assert obs in env.observation_space
    # Row 0 is north (y = 9): the agent at (9, 7) is on row 2, column 9; the star at (8, 2) on row 7.
    assert list(zip(*np.nonzero(grid[:, :, 3]))) == [(2, 9)]
    assert (grid[7, 8, 4], grid[7, 8, 5]) == (13, 1)  # yellow = 12 + 1, star = 0 + 1
    # Room colour indices + 1: green 6 (west), red 11 (north-east), blue 2 (south-east).
    assert (grid[4, 2, 2], grid[2, 8, 2], grid[7, 8, 2]) == (6, 11, 2)
    # Doors at (5,7), (5,2), (9,4): door channel set, wall channel clear.
    assert {(int(c), 9 - int(r)) for r, c in zip(*np.nonzero(grid[:, :, 1]))} == {(5, 7), (5, 2), (9, 4)}
    assert grid[2, 5, 0] == 0 and grid[0, 0, 0] == 1
    assert (observation_positions(grid, state.layout) == state.positions).all()
    assert info["goal_holds"] is False and info["state"] == state


def test_step_follows_the_world_dynamics_and_rewards_the_goal(state):
    env = CleanupEnv(state, command="go to the blue room", goal="agentInRoom(agent0, room2)", max_steps=50)
    env.reset(seed=0)
    # (9,7) -> south twice -> (9,5); south: door (9,4); south: (9,3) inside the blue room.
    rewards, expected = [], state
    for k in range(4):
        obs, reward, terminated, truncated, info = env.step(CleanupAction.SOUTH)
        expected = step(expected, Action.SOUTH)
        assert info["state"] == expected
        rewards.append(reward)
    assert rewards == [0.0, 0.0, 0.0, 1.0]
    assert terminated and not truncated and info["goal_holds"]


def test_terminate_ends_the_episode_without_reward_when_the_goal_fails(state):
    env = CleanupEnv(state, goal="agentInRoom(agent0, room0)")
    env.reset()
    _, reward, terminated, truncated, info = env.step(CleanupAction.TERMINATE)
    assert (reward, terminated, truncated, info["goal_holds"]) == (0.0, True, False, False)


def test_truncated_at_max_steps(state):
    env = CleanupEnv(state, max_steps=3)
    env.reset()
    outcomes = [env.step(CleanupAction.NORTH)[2:4] for _ in range(3)]
    assert outcomes == [(False, False), (False, False), (False, True)]


def test_seeded_resets_are_deterministic():
    a, b = CleanupEnv(), CleanupEnv()
    picks = []
    for seed in range(6):
        oa, ia = a.reset(seed=seed)
        ob, ib = b.reset(seed=seed)
        assert oa["command"] == ob["command"] and (oa["grid"] == ob["grid"]).all()
        assert ia["goal"] == ib["goal"]
        picks.append(oa["command"])
    assert len(set(picks)) > 1  # the seed does choose among the example instances
    # The same seed and actions give the same trajectory.
    rng = np.random.default_rng(7)
    actions = rng.integers(0, 4, size=20)
    runs = []
    for env in (a, b):
        env.reset(seed=11)
        runs.append([env.step(int(x))[0]["grid"].copy() for x in actions])
    assert all((x == y).all() for x, y in zip(*runs))


def test_reset_options_and_rendering(state):
    env = CleanupEnv(render_mode="rgb_array")
    obs, info = env.reset(seed=0, options={"state": state, "command": "Go to the \u2018green\u2019 room\n",
                                            "goal": "agentInRoom(agent0, room0)"})
    assert obs["command"] == "Go to the 'green' room"
    assert info["state"] == state
    image = env.render()
    assert image.ndim == 3 and image.shape[2] == 3 and image.dtype == np.uint8
    assert image.std() > 10  # a picture, not a blank canvas
    text_env = CleanupEnv(state, render_mode="ansi")
    text_env.reset()
    assert "legend" in text_env.render()


def test_bad_arguments_are_value_errors(state):
    with pytest.raises(ValueError, match="render_mode"):
        CleanupEnv(state, render_mode="human")
    with pytest.raises(ValueError, match="max_steps"):
        CleanupEnv(state, max_steps=0)
    with pytest.raises(ValueError, match="at most"):
        command_text("x" * 2000)
    for steps in (1.5, "10", None, float("nan"), True):  # of the wrong type: TypeError, as Python's own
        with pytest.raises(TypeError, match="max_steps must be a positive integer"):
            CleanupEnv(state, max_steps=steps)
    with pytest.raises(TypeError, match="state must be a State"):
        CleanupEnv(state="x")
    with pytest.raises(TypeError, match="command must be a str"):
        CleanupEnv(state, command=5)
    with pytest.raises(TypeError, match="goal must be a goal string"):
        CleanupEnv(state, goal=5)


def test_an_action_must_be_one_of_the_spaces_and_the_episode_ends_for_good(state):
    """``step(1.5)`` moved as 1 and ``step(4.9)`` terminated; after TERMINATE, a step still moved and paid."""
    env = CleanupEnv(state, goal="agentInRoom(agent0, room0)")
    env.reset(seed=0)
    for action in (1.5, 4.9, "3", True, None, -1, 5, "up"):
        with pytest.raises(ValueError, match=r"action must be an integer from 0 to 4 \(CleanupAction\)"):
            env.step(action)
    assert env.steps == 0  # nothing was taken
    env.step(np.int64(int(CleanupAction.TERMINATE)))
    with pytest.raises(RuntimeError, match="the episode is over"):
        env.step(0)
    env.reset(seed=0)
    env.step(0)  # a new episode steps again
    truncated = CleanupEnv(state, max_steps=1)
    truncated.reset(seed=0)
    assert truncated.step(0)[3] is True
    with pytest.raises(RuntimeError, match="the episode is over"):
        truncated.step(0)


def test_reset_options_are_checked(state):
    env = CleanupEnv(state)
    for options, error, message in [("x", TypeError, "options must be a dict"),
                                    ({"sate": state}, ValueError, "options 'sate': expected state, command or goal"),
                                    ({"state": None}, TypeError, r"options\['state'\] must be a State"),
                                    ({"command": None}, TypeError, r"options\['command'\] must be a str")]:
        with pytest.raises(error, match=message):
            env.reset(options=options)


def test_a_state_of_another_palette_is_refused(state):
    """A grid numbers the env's palette's values: a state of another palette (more colours, or as many as the
    env's in another order) had been taken when its channels fitted, its colours read as the env's."""
    from groundlang.model.palette import Palette

    env = CleanupEnv(state)
    for other in (Palette("wide", tuple(f"c{i}" for i in range(25)), state.layout.palette.shapes),
                  Palette("shuffled", state.layout.palette.colours[::-1], state.layout.palette.shapes)):
        with pytest.raises(ValueError, match=f"state of palette {other.name}: this env's grids number the values "
                                             "of palette sokoban"):
            env.reset(options={"state": parse_state(STATE, other)})
    same = Palette("copy", state.layout.palette.colours, state.layout.palette.shapes)  # its values, another name
    env.reset(options={"state": parse_state(STATE, same)})


def test_a_policy_ends_in_a_layout_it_did_not_plan_in(state):
    """Rooms recoloured: the agent's and toys' positions are in the planned space, but the red room is elsewhere;
    the policy had gone on to where the red room had been."""
    import dataclasses

    from groundlang.corpus import read_corpus
    from groundlang.learner import Learner

    learner = Learner(steps=20, cache_dir=False).fit(read_corpus(example_corpus_path(), "sokoban").instances[:6])
    act = policy(learner, "go to the red room", state)
    colours = [r.colour for r in state.layout.rooms]
    rooms = tuple(dataclasses.replace(r, colour=c) for r, c in zip(state.layout.rooms, colours[1:] + colours[:1]))
    moved = dataclasses.replace(state, layout=dataclasses.replace(state.layout, rooms=rooms))
    assert act(state) != CleanupAction.TERMINATE
    env = CleanupEnv(moved)
    observation, _ = env.reset()
    assert act(moved) == CleanupAction.TERMINATE and act(observation) == CleanupAction.TERMINATE
    observation, _ = CleanupEnv(state).reset()
    assert act(observation) == act(state)


def test_a_picture_of_a_large_layout_stays_bounded():
    """rgb_array pictures had half an inch a cell however large the layout (a 300-cell room: 9120 pixels a side,
    7 GB); they are bounded as show's are."""
    from groundlang.bdm import parse_bdm_state
    from groundlang.gym_env import render_rgb

    big, _ = parse_bdm_state("{agent0 (agent): [x: {2} y: {2} ] , block0 (block): [x: {5} y: {5} shape: {chair} "
                             "colour: {red} ] , room0 (room): [top: {300} left: {0} bottom: {0} right: {300} "
                             "colour: {red} ] , }")
    picture = render_rgb(big)
    assert picture.shape[2] == 3 and max(picture.shape[:2]) <= 60 * (16 + 1.5)


def test_a_policy_refuses_what_is_not_an_observation(state):
    from groundlang.corpus import read_corpus
    from groundlang.learner import Learner

    learner = Learner(steps=20, cache_dir=False).fit(read_corpus(example_corpus_path(), "sokoban").instances[:6])
    act = policy(learner, "go to the red room", state)
    for observation in (None, 5, {"grid": np.zeros((2, 2, 2), dtype=np.uint8)}, {"command": "x"}):
        with pytest.raises(ValueError, match="observation must be an env's"):
            act(observation)
    with pytest.raises(TypeError, match="policy: learner must be a trained Learner"):
        policy(None, "go to the red room", state)


@pytest.mark.slow
def test_a_learned_policy_carries_out_a_command_in_a_novel_layout():
    from groundlang.corpus import read_corpus
    from groundlang.learner import Learner

    corpus = read_corpus(example_corpus_path(), "sokoban")
    learner = Learner(cache_dir=False).fit(corpus.instances)
    novel = read_state_file(example_corpus_path() / "novel_b.state", "sokoban")
    # novel_b: room0 red, room1 blue, room2 green.
    env = CleanupEnv(novel, command="take the star to the red room", goal="toyInRoom(block0, room0)")
    env.reset(seed=0)
    act = policy(learner, "take the star to the red room", env)
    assert [str(a) for a in act.goal] == ["toyInRoom(block0, room0)"]
    states, actions, total, info = run_episode(env, act, seed=0)
    assert total == 1.0 and info["goal_holds"]
    followed = learner.follow("take the star to the red room", novel)
    # The environment ends the episode where its goal first holds; following ends there too: none of the example
    # corpus's demonstrators went on after pushing the star in (habit_prior; with "overall" it took a step more).
    assert states == followed.states
    # Without a goal the environment ends when the policy terminates: where following ends.
    free = CleanupEnv(novel, command="take the star to the red room")
    free.reset(seed=0)
    states, actions, _, _ = run_episode(free, policy(learner, "take the star to the red room", free), seed=0)
    assert states == followed.states and [int(a) for a in actions[:-1]] == [int(a) for a in followed.actions]
    assert actions[-1] == CleanupAction.TERMINATE


def test_actions_are_the_worlds_moves_then_the_planners_terminate():
    from groundlang.inference.planning import TERMINATE

    assert [(a.name, int(a)) for a in CleanupAction][:-1] == [(a.name, int(a)) for a in Action]
    assert CleanupAction.TERMINATE == TERMINATE == len(Action)


def test_toys_alike_are_told_apart_by_where_they_were(state):
    """Eight yellow stars: matching them to the layout's toys in every order took 8! = 40320 arrays per
    observation (10 stars hung); each keeps the cell it had a step before, so one candidate is read."""
    stars = " ".join(f"block,12,0,{x},{y}" for x, y in [(1, 1), (2, 1), (3, 1), (1, 2), (2, 2), (3, 2), (1, 3),
                                                          (2, 3)])
    many = parse_state(STATE.replace("block,12,0,8,2", stars), "sokoban")
    env = CleanupEnv(many, command="go to the green room")
    grid = env.reset(seed=0)[0]["grid"]
    with pytest.raises(ValueError, match="cannot be told apart in 40,320 ways"):
        observation_positions(grid, many.layout)
    assert (observation_positions(grid, many.layout, previous=many.positions) == many.positions).all()
    # One star pushed a cell east (as a step moves at most one): the others keep their cells, it takes the free one.
    moved = many.positions.copy()
    moved[3] = (4, 1)
    grid = CleanupEnv(many.with_positions(moved)).reset(seed=0)[0]["grid"]
    assert (observation_positions(grid, many.layout, previous=many.positions) == moved).all()


def test_an_attribute_the_palette_adds_has_a_channel_and_tells_toys_apart():
    """Two red chairs, one wooden and one metal (an attribute the palette adds): the grid has a channel of
    materials, so the chairs are matched to the layout's by it, with no previous positions to go by, and a
    state of a palette without it is refused by the env."""
    from pathlib import Path

    from groundlang.bdm import parse_bdm_state
    from groundlang.gym_env import channels

    palette = str(Path(__file__).parent / "fixtures" / "materials" / "materials.lp")
    line = ("{agent0 (agent): [x: {2} y: {2} ] , door0 (door): [top: {3} left: {4} bottom: {3} right: {4} ] , "
            "block0 (block): [x: {6} y: {2} shape: {chair} colour: {red} material: {wood} ] , "
            "block1 (block): [x: {2} y: {5} shape: {chair} colour: {red} material: {metal} ] , "
            "room0 (room): [top: {7} left: {0} bottom: {0} right: {4} colour: {red} ] , "
            "room1 (room): [top: {7} left: {4} bottom: {0} right: {8} colour: {green} ] , }")
    chairs, _ = parse_bdm_state(line, palette)
    env = CleanupEnv(chairs, command="go next to the metal chair")
    assert env.channels == channels(chairs.layout.palette) == CHANNELS + ("toy_material",)
    grid = env.reset(seed=0)[0]["grid"]
    assert grid.shape == (8, 9, 7) and env.observation_space["grid"].contains(grid)
    # wood is value 0, metal 1: each chair's cell holds its index + 1, every other cell 0
    assert {(int(c), 7 - int(r)): int(grid[r, c, 6]) for r, c in zip(*np.nonzero(grid[:, :, 6]))} == \
        {(6, 2): 1, (2, 5): 2}
    assert (observation_positions(grid, chairs.layout) == chairs.positions).all()
    swapped = chairs.with_positions(chairs.positions[[0, 2, 1]])  # the metal chair where the wooden one was
    assert (observation_positions(CleanupEnv(swapped).reset(seed=0)[0]["grid"], chairs.layout,
                                  previous=chairs.positions) == swapped.positions).all()
    for _ in range(3):  # north twice, then push the metal chair from (2, 5) to (2, 6)
        after = env.step(int(CleanupAction.NORTH))[0]["grid"]
    assert (int(after[7 - 6, 2, 6]), int(after[7 - 5, 2, 6]), int(after[7 - 5, 2, 3])) == (2, 0, 1)
    plain, _ = parse_bdm_state(line.replace(" material: {wood}", "").replace(" material: {metal}", ""),
                               "williams2018")
    with pytest.raises(ValueError, match="state of palette williams2018: this env's grids number the values of "
                                         "palette materials"):
        env.reset(options={"state": plain})


def test_a_room_and_a_door_attribute_fill_the_room_cells_and_the_door_cell(tmp_path):
    from groundlang.bdm import parse_bdm_state

    palette = tmp_path / "floors.lp"
    palette.write_text("value(colour, 0, red). value(colour, 1, green). value(shape, 0, chair).\n"
                       "value(floor, 0, wood). value(floor, 1, tile). value(lock, 0, open). value(lock, 1, shut).\n"
                       "attribute(room, floor). attribute(door, lock).\n", encoding="utf-8")
    state, _ = parse_bdm_state(
        "{agent0 (agent): [x: {2} y: {2} ] , door0 (door): [top: {3} left: {4} bottom: {3} right: {4} lock: {shut} ] , "
        "room0 (room): [top: {7} left: {0} bottom: {0} right: {4} colour: {red} floor: {tile} ] , "
        "room1 (room): [top: {7} left: {4} bottom: {0} right: {8} colour: {green} floor: {wood} ] , }", str(palette))
    env = CleanupEnv(state)
    grid = env.reset(seed=0)[0]["grid"]
    assert env.channels[6:] == ("door_lock", "room_floor")
    lock, floor = grid[:, :, 6], grid[:, :, 7]
    assert list(zip(*np.nonzero(lock))) == [(7 - 3, 4)] and lock[7 - 3, 4] == 2
    assert (floor[1:7, 1:4] == 2).all() and (floor[1:7, 5:8] == 1).all()
    assert (floor[[0, 7], :] == 0).all() and (floor[:, [0, 4, 8]] == 0).all()


def test_a_goal_over_objects_the_state_lacks_is_refused_before_the_episode_changes(state):
    from groundlang.labels import LabelError
    from groundlang.logic.atoms import format_goal

    # it had been accepted at construction, and a reset with it left the env half reset
    with pytest.raises(LabelError, match="names room9, which does not exist"):
        CleanupEnv(state, "go", goal="agentInRoom(agent0, room9)")
    env = CleanupEnv(state, "go to the green room", goal="agentInRoom(agent0, room1)")
    env.reset(seed=0)
    with pytest.raises(LabelError, match="names room9"):
        env.reset(options={"goal": "agentInRoom(agent0, room9)"})
    assert format_goal(env.goal) == "agentInRoom(agent0, room1)" and env.command == "go to the green room"


def test_a_goal_may_use_a_pf_of_the_library_given(state):
    """A PF a user authored in ASP (the example ``next_to.lp``) is a goal of the env given its library:
    the domain's own PFs alone refuse it."""
    from groundlang.labels import LabelError

    library = example_corpus_path() / "next_to.lp"
    with pytest.raises(LabelError, match="unknown predicate 'agentNextToToy'"):
        CleanupEnv(state=state, goal="agentNextToToy(agent0, block0)")
    env = gymnasium.make(ENV_ID, state=state, goal="agentNextToToy(agent0, block0)", library=str(library))
    _, info = env.reset(seed=0)
    assert not info["goal_holds"]
    # the star at (8,2), the agent at (9,7): four steps south end beside it (diagonally), where the goal holds
    for _ in range(3):
        _, reward, terminated, _, info = env.step(int(CleanupAction.SOUTH))
        assert not terminated and reward == 0.0
    _, reward, terminated, _, info = env.step(int(CleanupAction.SOUTH))
    assert terminated and reward == 1.0 and info["goal_holds"]
    with pytest.raises(TypeError, match="library must be a TaskLibrary"):
        CleanupEnv(state=state, library=5)
    for bad, said in (("", "empty"), ([], "empty"), (str(example_corpus_path()), "expected the path of a .lp file"),
                      ("no-such.lp", "expected the path of a .lp file")):
        with pytest.raises(ValueError, match=said):
            CleanupEnv(state=state, library=bad)
