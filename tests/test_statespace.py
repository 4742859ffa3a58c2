"""model.statespace: vectorised breadth-first enumeration against world.step."""

from __future__ import annotations

import importlib.util
from collections import deque
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from groundlang.model import statespace
from groundlang.model.statespace import StateSpaceError, enumerate_states, trajectory_indices
from groundlang.model.world import Action, Agent, Door, Layout, Room, State, Toy, get_palette, step

SOKOBAN = get_palette("sokoban")
BENCHMARK = Path(__file__).parent.parent / "benchmarks" / "bench_statespace.py"

CORPUS_ROOMS = (Room("green", 0, 10, 6, 4), Room("red", 6, 10, 10, 4), Room("blue", 0, 4, 10, 0))
CORPUS_DOORS = (Door(3, 4, 3, 3), Door(8, 4, 8, 3), Door(5, 6, 6, 6))
TOY_KINDS = [("yellow", "star"), ("magenta", "moon"), ("cyan", "circle")]


def make_state(rooms, doors, agent, toys) -> State:
    """A state whose toys take TOY_KINDS' attributes in order."""
    objects = tuple(Toy(*TOY_KINDS[i], x, y) for i, (x, y) in enumerate(toys))
    layout = Layout(tuple(rooms), tuple(doors), tuple((t.colour, t.shape) for t in objects), SOKOBAN)
    return State(layout, Agent(*agent), objects)


def corpus_state(agent=(8, 6), toys=((4, 8),)) -> State:
    return make_state(CORPUS_ROOMS, CORPUS_DOORS, agent, toys)


# Small worlds that exercise walls, doors, corridors, corners and toy-toy blocking.
SMALL_WORLDS = {
    "no toy": corpus_state((4, 2), ()),
    "corpus, one toy": corpus_state(),
    "one room, two toys": make_state([Room("red", 0, 5, 5, 0)], [], (1, 1), [(2, 2), (3, 3)]),
    "corridor, toy stuck against the far wall": make_state(
        [Room("red", 0, 2, 6, 0)], [], (1, 1), [(5, 1)]
    ),
    "two rooms, door, three toys": make_state(
        [Room("green", 0, 4, 4, 0), Room("blue", 4, 4, 8, 0)], [Door(4, 2, 4, 2)],
        (1, 1), [(2, 2), (5, 2), (6, 3)],
    ),
    "corpus, two toys": corpus_state((8, 6), ((4, 8), (7, 2))),
}


def reference_enumeration(state: State) -> dict[tuple, dict[int, tuple]]:
    """Breadth-first search calling world.step: positions -> {action: successor positions}."""
    def key(s):
        return tuple(map(tuple, s.positions.tolist()))

    graph: dict[tuple, dict[int, tuple]] = {}
    queue = deque([state])
    graph[key(state)] = {}
    while queue:
        current = queue.popleft()
        row = graph[key(current)]
        for action in Action:
            successor = step(current, action)
            k = key(successor)
            row[int(action)] = k
            if k not in graph:
                graph[k] = {}
                queue.append(successor)
    return graph


# The two-toy corpus world (328,410 states) is checked on a sample instead.
@pytest.mark.parametrize("name", [n for n in SMALL_WORLDS if n != "corpus, two toys"])
def test_enumeration_equals_step_bfs(name):
    state = SMALL_WORLDS[name]
    space = enumerate_states(state)
    graph = reference_enumeration(state)
    assert space.num_states == len(graph)
    keys = [tuple(map(tuple, p)) for p in space.positions.tolist()]
    assert set(keys) == set(graph)
    assert keys[0] == tuple(map(tuple, state.positions.tolist()))
    for s, k in enumerate(keys):
        for a in range(4):
            assert keys[space.next_state[s, a]] == graph[k][a], (name, k, Action(a))


def test_known_sizes():
    sizes = {name: enumerate_states(s).num_states for name, s in SMALL_WORLDS.items()}
    # 70 walkable cells in the corpus layout (67 inside rooms, 3 door cells in walls); every
    # placement of one toy is reachable; a toy against the corridor's end wall never moves.
    assert sizes["no toy"] == 70
    assert sizes["corpus, one toy"] == 4830
    assert sizes["corridor, toy stuck against the far wall"] == 4
    assert sizes["corpus, two toys"] == 328_410


def test_two_toy_world_agrees_with_step():
    space = enumerate_states(SMALL_WORLDS["corpus, two toys"])
    rng = np.random.default_rng(7)
    for s in rng.integers(0, space.num_states, 300):
        state = space.state_at(int(s))
        for action in Action:
            expected = step(state, action).positions
            np.testing.assert_array_equal(space.positions[space.next_state[s, action]], expected)
    # Pushing a toy onto the other toy is blocked: the agent at (7,6), toys at (6,6)/(5,6) going west.
    i = space.index_of(np.array([[7, 6], [6, 6], [5, 6]]))
    assert space.next_state[i, Action.WEST] == i


def test_arrays_and_accessors():
    state = SMALL_WORLDS["corpus, one toy"]
    space = enumerate_states(state)
    assert space.next_state.dtype == np.int32 and space.next_state.shape == (4830, 4)
    assert space.positions.shape == (4830, 2, 2) and space.positions.dtype == np.int16
    assert space.next_state.min() >= 0 and space.next_state.max() < space.num_states
    assert space.index_of(state) == 0
    assert space.state_at(0) == state
    assert space.object_names == ["agent0", "block0"]
    assert space.num_toys == 1 and len(space) == 4830
    for i in (0, 17, 4829):
        assert space.index_of(space.state_at(i)) == i
        assert space.index_of(space.positions[i]) == i
    np.testing.assert_array_equal(space.indices_of(space.positions[::-1]), np.arange(4830)[::-1])
    # Breadth-first numbering: distance from the initial state never decreases with the index.
    distance = np.full(space.num_states, -1)
    frontier, d = np.array([0]), 0
    while len(frontier):
        distance[frontier] = d
        successors = np.unique(space.next_state[frontier])
        frontier, d = successors[distance[successors] < 0], d + 1
    assert (distance >= 0).all() and (np.diff(distance) >= 0).all() and distance.max() > 20


def test_unreachable_and_invalid_lookups_are_named():
    space = enumerate_states(SMALL_WORLDS["corridor, toy stuck against the far wall"])
    with pytest.raises(StateSpaceError, match=r"agent0@\(2,1\) block0@\(4,1\) is not reachable"):
        space.index_of(np.array([[2, 1], [4, 1]]))
    with pytest.raises(ValueError, match=r"agent0@\(0,0\)"):  # a wall cell
        space.index_of(np.array([[0, 0], [5, 1]]))
    with pytest.raises(ValueError, match="outside 0..3"):
        space.state_at(4)
    other = corpus_state()
    with pytest.raises(ValueError, match="different layout"):
        space.index_of(other)
    assert space.indices_of(np.array([[[2, 1], [4, 1]], [[99, -3], [5, 1]]])).tolist() == [-1, -1]


def test_dense_and_sorted_key_maps_agree():
    for name in ("corpus, one toy", "two rooms, door, three toys", "no toy"):
        state = SMALL_WORLDS[name]
        dense = statespace._enumerate(state, 10**7, dense=True)
        sparse = statespace._enumerate(state, 10**7, dense=False)
        np.testing.assert_array_equal(dense.next_state, sparse.next_state)
        np.testing.assert_array_equal(dense.positions, sparse.positions)


def test_max_states_refusal_names_estimate_and_setting():
    state = SMALL_WORLDS["corpus, two toys"]
    # 70 walkable cells: 70 * 69 * 68 = 328,440 placements of the agent and two named toys.
    with pytest.raises(StateSpaceError) as err:
        enumerate_states(state, max_states=100_000)
    message = str(err.value)
    assert "328,440" in message and "70 walkable cells" in message
    assert "max_states=100,000" in message and "pass max_states=328,440" in message
    assert enumerate_states(SMALL_WORLDS["corpus, one toy"], max_states=4830).num_states == 4830
    with pytest.raises(StateSpaceError, match="up to 4,830 states"):
        enumerate_states(SMALL_WORLDS["corpus, one toy"], max_states=4829)


@pytest.mark.parametrize(
    "agent, toys, message",
    [((0, 0), [(4, 8)], r"agent0 at \(0,0\) is inside a wall"),
     ((8, 6), [(6, 8)], r"block0 at \(6,8\) is inside a wall"),
     ((8, 6), [(8, 6)], "two objects share a cell")],
)
def test_invalid_initial_state(agent, toys, message):
    with pytest.raises(StateSpaceError, match=message):
        enumerate_states(corpus_state(agent, toys))


def test_trajectory_indices():
    state = SMALL_WORLDS["corpus, one toy"]
    space = enumerate_states(state)
    rng = np.random.default_rng(3)
    states, expected = [state], [0]
    for a in rng.integers(0, 4, 40):
        expected.append(int(space.next_state[expected[-1], a]))
        states.append(step(states[-1], Action(int(a))))
    np.testing.assert_array_equal(trajectory_indices(space, states), expected)
    assert trajectory_indices(space, []).shape == (0,)
    corridor = SMALL_WORLDS["corridor, toy stuck against the far wall"]
    space = enumerate_states(corridor)
    moved = step(corridor, Action.EAST)
    unreachable = corridor.with_positions(np.array([[2, 1], [4, 1]]))
    np.testing.assert_array_equal(trajectory_indices(space, [corridor, moved]), [0, space.index_of(moved)])
    with pytest.raises(StateSpaceError, match=r"step 2: state agent0@\(2,1\) block0@\(4,1\) is not reachable"):
        trajectory_indices(space, [corridor, moved, unreachable])


@settings(max_examples=25, deadline=None)
@given(
    cells=st.lists(st.tuples(st.integers(1, 9), st.integers(1, 3)), min_size=2, max_size=3, unique=True),
    actions=st.lists(st.integers(0, 3), max_size=60),
)
def test_random_walks_follow_next_state(cells, actions):
    """From random placements in the corpus layout's south room, a random walk stays on next_state."""
    state = corpus_state(cells[0], cells[1:])
    space = enumerate_states(state)
    index = 0
    for a in actions:
        state = step(state, Action(a))
        index = int(space.next_state[index, a])
        np.testing.assert_array_equal(space.positions[index], state.positions)
        assert space.index_of(state) == index


def _benchmark_module():
    spec = importlib.util.spec_from_file_location("bench_statespace", BENCHMARK)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_benchmark_worlds_and_python_baseline():
    bench = _benchmark_module()
    worlds = bench.benchmark_layouts()
    assert len(worlds) == 3
    small = worlds[0][1]
    space = enumerate_states(small)
    assert space.num_states == 9312
    order, next_state = bench.python_bfs(small)
    # Same states and the same transitions, whatever the order.
    mine = {tuple(map(tuple, p)): i for i, p in enumerate(space.positions.tolist())}
    assert set(order) == set(mine)
    translate = np.array([mine[s] for s in order])
    np.testing.assert_array_equal(space.next_state[translate], translate[np.array(next_state)])
    assert enumerate_states(worlds[1][1]).num_states == 103_746


def test_corpus_demonstrations_are_enumerated(shared_corpus):
    """Every state of every demonstration of both folders lies in its initial state's enumeration."""
    from groundlang.corpus import read_instance

    spaces: dict[tuple, statespace.StateSpace] = {}
    files = 0
    for folder in ("allTurkTrain", "allTurkTrainLimitedCommand"):
        for path in sorted((shared_corpus / folder).glob("*.txt")):
            instance = read_instance(path, "sokoban")
            first = instance.initial_state
            key = (first.layout, first.positions.tobytes())
            if key not in spaces:
                spaces[key] = enumerate_states(first)
            space = spaces[key]
            indices = trajectory_indices(space, instance.states)
            assert indices[0] == 0
            # Consecutive demonstration states are linked by next_state under the recorded action.
            np.testing.assert_array_equal(
                space.next_state[indices[:-1], [int(a) for a in instance.actions]], indices[1:]
            )
            files += 1
    assert files == 480
    assert len(spaces) == 6


@pytest.mark.parametrize("given, expected", [("", 5_000_000), ("  ", 5_000_000), ("1_000", 1000), ("2,500", 2500),
                                             ("_", None), (",", None), ("0", None), ("abc", None),
                                             ("1,000,000", 1_000_000), ("²", None), ("1,2,3", None), ("1__0", None)])
def test_the_state_limit_from_the_environment(monkeypatch, given, expected):
    from groundlang.model.state_search import default_max_states

    monkeypatch.setenv("GROUNDLANG_MAX_STATES", given)
    if expected is None:  # digit separators alone are not a number: refused, not read as unset
        with pytest.raises(StateSpaceError, match=f"GROUNDLANG_MAX_STATES='{given}': expected a positive integer"):
            default_max_states()
    else:
        assert default_max_states() == expected


def test_a_state_limit_no_memory_could_hold_is_refused(monkeypatch):
    """2,000,000,000 had been taken as a limit: a run grew past 6 GB before anything was refused. A bound whose
    tables alone (36 bytes a state, measured) would pass the machine's memory is refused, in the variable and
    as an argument; one that fits is a limit as before."""
    import os

    from groundlang.model.state_search import SPACE_BYTES_PER_STATE, default_max_states, max_states_given

    memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    too_many = memory // SPACE_BYTES_PER_STATE + 1
    monkeypatch.setenv("GROUNDLANG_MAX_STATES", str(too_many))
    with pytest.raises(StateSpaceError, match=rf"GROUNDLANG_MAX_STATES='{too_many}': a space that large needs at least "
                                              rf"36 bytes a state .* at most {too_many - 1:,}$"):
        default_max_states()
    with pytest.raises(StateSpaceError, match=f"max_states={too_many}: a space that large"):
        max_states_given(too_many)
    with pytest.raises(StateSpaceError, match="max_states=inf: a space that large"):
        max_states_given(float("inf"))
    monkeypatch.setenv("GROUNDLANG_MAX_STATES", str(too_many - 1))
    assert default_max_states() == too_many - 1 == max_states_given(too_many - 1)
