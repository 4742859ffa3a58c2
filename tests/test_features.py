"""model.features: grounded PF values over a state space, from per-cell tables."""

from __future__ import annotations

import csv

import numpy as np
import pytest
import torch

from groundlang.logic.atoms import Atom, parse_atom, parse_goal
from groundlang.model.features import FeatureError, feature_matrix, goal_mask, position_atoms
from groundlang.model.geometry import CellTables, cell_tables
from groundlang.model.pf_tables import pf_tables
from groundlang.model.statespace import enumerate_states
from groundlang.model.world import Agent, Door, Layout, Room, State, Toy, get_palette

SOKOBAN = get_palette("sokoban")


def local_tables(layout: Layout) -> CellTables:
    """The tables straight from Layout.walkable, rooms and doors (no clingo)."""
    w, h = layout.width, layout.height
    room_of = np.full((w, h), -1, dtype=np.int16)
    door_of = np.full((w, h), -1, dtype=np.int16)
    for i in reversed(range(len(layout.rooms))):
        r = layout.rooms[i]
        room_of[r.left + 1 : r.right, r.bottom + 1 : r.top] = i
    for i in reversed(range(len(layout.doors))):
        d = layout.doors[i]
        door_of[max(d.left, 0) : d.right + 1, max(d.bottom, 0) : d.top + 1] = i
    door_of[~layout.walkable] = -1
    return CellTables(room_of, door_of)


def corpus_state(agent=(8, 6), toys=((4, 8),), palette=SOKOBAN, kinds=(("yellow", "star"),)) -> State:
    layout = Layout(
        (Room("green", 0, 10, 6, 4), Room("red", 6, 10, 10, 4), Room("blue", 0, 4, 10, 0)),
        (Door(3, 4, 3, 3), Door(8, 4, 8, 3), Door(5, 6, 6, 6)),
        tuple(kinds[: len(toys)]),
        palette,
    )
    return State(layout, Agent(*agent), tuple(Toy(*k, x, y) for k, (x, y) in zip(kinds, toys)))


@pytest.fixture(scope="module")
def one_toy():
    state = corpus_state()
    return enumerate_states(state), pf_tables(state.layout)


@pytest.fixture(scope="module")
def two_toys():
    state = corpus_state(toys=((4, 8), (7, 2)), kinds=(("yellow", "star"), ("red", "moon")))
    return enumerate_states(state), pf_tables(state.layout)


def test_local_tables_match_clingo():
    layout = corpus_state().layout
    mine, theirs = local_tables(layout), cell_tables(layout)
    np.testing.assert_array_equal(mine.room_of, theirs.room_of)
    np.testing.assert_array_equal(mine.door_of, theirs.door_of)


def reference_column(space, atom: Atom, tables: CellTables) -> np.ndarray:
    """The paper's position PFs computed straight from the cell tables with numpy: what the PF tables
    clingo tabulates from pfs.lp must agree with."""
    pos = space.positions
    index = {"agent0": 0, **{n: 1 + i for i, n in enumerate(space.layout.toy_names)}}
    mover = pos[:, index[atom.args[0]]]
    if atom.predicate == "agentTouchingToy":
        toy = pos[:, index[atom.args[1]]]
        return np.abs(mover - toy).sum(-1) == 1
    grid = tables.room_of if atom.predicate.endswith("InRoom") else tables.door_of
    return grid[mover[:, 0], mover[:, 1]] == int(atom.args[1][4:])


@pytest.mark.parametrize("fixture", ["one_toy", "two_toys"])
def test_tabulated_pfs_agree_with_the_cell_tables_in_every_state(fixture, request):
    space, tables = request.getfixturevalue(fixture)
    reference = local_tables(space.layout)
    atoms = position_atoms(space.layout)
    assert {a.predicate for a in atoms} == {"agentInRoom", "toyInRoom", "agentInDoor", "toyInDoor", "agentTouchingToy"}
    values = feature_matrix(space, atoms, tables).numpy().astype(bool)
    for f, atom in enumerate(atoms):
        np.testing.assert_array_equal(values[:, f], reference_column(space, atom, reference), err_msg=str(atom))
    assert values.any(0).sum() >= len(atoms) - 2  # nearly every atom holds somewhere: not all False


def test_position_atoms():
    layout = corpus_state(toys=((4, 8), (7, 2)), kinds=(("yellow", "star"), ("red", "moon"))).layout
    atoms = [str(a) for a in position_atoms(layout)]
    assert len(atoms) == 3 + 2 * 3 + 3 + 2 * 3 + 2
    assert atoms[:4] == ["agentInRoom(agent0, room0)", "agentInRoom(agent0, room1)",
                         "agentInRoom(agent0, room2)", "toyInRoom(block0, room0)"]
    assert atoms[-2:] == ["agentTouchingToy(agent0, block0)", "agentTouchingToy(agent0, block1)"]
    assert "toyInDoor(block1, door2)" in atoms
    assert [str(a) for a in position_atoms(corpus_state(toys=()).layout)] == [
        "agentInRoom(agent0, room0)", "agentInRoom(agent0, room1)", "agentInRoom(agent0, room2)",
        "agentInDoor(agent0, door0)", "agentInDoor(agent0, door1)", "agentInDoor(agent0, door2)",
    ]


@pytest.mark.parametrize(
    "agent, toy, true_atoms",
    [
        ((8, 6), (4, 8), {"agentInRoom(agent0, room1)", "toyInRoom(block0, room0)"}),
        ((3, 4), (3, 3), {"agentInDoor(agent0, door0)", "toyInDoor(block0, door0)",
                          "toyInRoom(block0, room2)", "agentTouchingToy(agent0, block0)"}),
        ((6, 6), (5, 6), {"agentInDoor(agent0, door2)", "toyInDoor(block0, door2)",
                          "toyInRoom(block0, room0)", "agentTouchingToy(agent0, block0)"}),
        ((5, 5), (4, 6), {"agentInRoom(agent0, room0)", "toyInRoom(block0, room0)"}),  # diagonal
        ((9, 1), (9, 2), {"agentInRoom(agent0, room2)", "toyInRoom(block0, room2)",
                          "agentTouchingToy(agent0, block0)"}),
    ],
)
def test_hand_picked_states(one_toy, agent, toy, true_atoms):
    space, tables = one_toy
    atoms = position_atoms(space.layout)
    row = feature_matrix(space, atoms, tables)[space.index_of(np.array([agent, toy]))]
    assert {str(a) for a, v in zip(atoms, row.tolist()) if v == 1.0} == true_atoms


def test_every_atom_every_state_matches_goal_holds(two_toys):
    """Against groundlang.labels.goal_holds, a per-state Python reference, on a sample of states."""
    from groundlang.labels import goal_holds

    space, tables = two_toys
    atoms = position_atoms(space.layout) + [parse_atom(a) for a in (
        "roomIsGreen(room0)", "roomIsBlue(room0)", "toyIsRed(block1)", "toyIsMoon(block1)", "toyIsStar(block1)")]
    features = feature_matrix(space, atoms, tables)
    assert features.dtype == torch.float32 and features.shape == (space.num_states, len(atoms))
    rng = np.random.default_rng(0)
    for s in rng.choice(space.num_states, 400, replace=False):
        state = space.state_at(int(s))
        expected = [float(goal_holds([a], state)) for a in atoms]
        assert features[s].tolist() == expected, space.state_at(int(s))


def test_column_counts(one_toy):
    space, tables = one_toy
    counts = feature_matrix(space, position_atoms(space.layout), tables).sum(0).tolist()
    # 70 cells; toy elsewhere: 69 placements per agent cell. Rooms hold 25, 15, 27 cells.
    assert counts[:3] == [25 * 69, 15 * 69, 27 * 69]
    assert counts[3:6] == [25 * 69, 15 * 69, 27 * 69]
    assert counts[6:9] == [2 * 69, 2 * 69, 2 * 69]  # door cells (3,3),(3,4) / (8,3),(8,4) / (5,6),(6,6)
    # Ordered pairs of 4-neighbouring walkable cells.
    walk = space.layout.walkable
    pairs = 2 * ((walk[1:, :] & walk[:-1, :]).sum() + (walk[:, 1:] & walk[:, :-1]).sum())
    assert counts[-1] == pairs


def test_constant_colour_and_shape_columns(one_toy):
    space, tables = one_toy
    atoms = ["roomIsGreen(room0)", "roomIsRed(room0)", "roomIsRed(room1)", "roomIsDarkGray(room2)",
             "toyIsYellow(block0)", "toyIsStar(block0)", "toyIsMoon(block0)"]
    values = feature_matrix(space, [parse_atom(a) for a in atoms], tables)
    assert values[0].tolist() == [1, 0, 1, 0, 1, 1, 0]
    assert bool((values == values[0]).all())

    second = corpus_state(palette=get_palette("sokoban2"), kinds=(("magenta", "chair"),))
    space2 = enumerate_states(second)
    values2 = feature_matrix(space2, ["toyIsChair(block0)", "toyIsMagenta(block0)", "toyIsBag(block0)"],
                             pf_tables(second.layout))
    assert values2[123].tolist() == [1, 1, 0]
    with pytest.raises(FeatureError, match="toyIsStar"):  # a shape of the other palette
        feature_matrix(space2, ["toyIsStar(block0)"], pf_tables(second.layout))


@pytest.mark.parametrize(
    "atom, message",
    [
        ("agentNearRoom(agent0, room0)", r"agentNearRoom\(agent0, room0\): unknown predicate"),
        ("toyInRoom(block0, room7)", r"toyInRoom\(block0, room7\) names room7, which does not exist"),
        ("toyInRoom(block3, room0)", r"toyInRoom\(block3, room0\) names block3, which does not exist"),
        ("agentInRoom(block0, room0)", "block0 is a toy; expected an agent there"),
        ("agentInRoom(agent0)", r"has 1 arguments; agentInRoom takes 2 \(agent, room\)"),
        ("roomIsGreen(room0, room1)", r"has 2 arguments; roomIsGreen takes 1 \(room\)"),
        ("roomIsStar(room0)", "unknown predicate 'roomIsStar'"),
        ("roomIsPurple(room0)", "unknown predicate"),
        ("toyIsGreen(room0)", "room0 is a room; expected a toy there"),
    ],
)
def test_bad_atoms_are_named(one_toy, atom, message):
    space, tables = one_toy
    with pytest.raises(FeatureError, match=message):
        feature_matrix(space, [parse_atom(atom)], tables)
    with pytest.raises(ValueError):
        goal_mask(space, [atom], tables)


def test_tables_of_another_layout_are_refused(one_toy, two_toys):
    space, _ = one_toy
    _, other = two_toys
    with pytest.raises(FeatureError, match="layout other than"):
        feature_matrix(space, position_atoms(space.layout), other)


def test_goal_mask(two_toys):
    space, tables = two_toys
    goal = parse_goal("agentInRoom(agent0, room1) blockInRoom(block1, room0)")  # corpus alias
    mask = goal_mask(space, goal, tables)
    assert mask.dtype == bool and mask.shape == (space.num_states,)
    features = feature_matrix(space, [Atom("agentInRoom", ("agent0", "room1")),
                                      Atom("toyInRoom", ("block1", "room0"))], tables)
    np.testing.assert_array_equal(mask, features.numpy().all(1))
    # Agent in room1 (15 cells), block1 in room0 (25 cells), block0 anywhere else (68 cells).
    assert mask.sum() == 15 * 25 * 68
    assert not mask[0]
    np.testing.assert_array_equal(goal_mask(space, ["agentInRoom(agent0, room1)"], tables),
                                  features[:, 0].numpy() == 1)
    with pytest.raises(FeatureError, match="empty goal"):
        goal_mask(space, [], tables)


def test_corpus_goals_hold_only_at_the_end(shared_corpus):
    """Each of the 6 demonstrations: the label's goal holds in the final state, not the first."""
    from groundlang.corpus import read_instance

    labels = {row["prefix"]: parse_goal(row["goal"])
              for row in csv.DictReader(open(shared_corpus / "labels.csv", encoding="utf-8"))}
    assert len(labels) == 6
    for prefix, goal in labels.items():
        instance = read_instance(shared_corpus / "allTurkTrain" / f"{prefix}0.txt", "sokoban")
        space = enumerate_states(instance.initial_state)
        mask = goal_mask(space, goal, pf_tables(space.layout))
        assert mask[space.index_of(instance.final_state)], prefix
        assert not mask[0], prefix


def test_a_layout_too_large_to_tabulate_is_refused_before_grounding(fixtures):
    from groundlang.corpus import read_state_file
    from groundlang.model.pf_tables import MAX_TABULATED_CELLS, TabulationError

    state = read_state_file(fixtures / "bad_input" / "huge_grid.state", "sokoban")
    assert state.layout.walkable.sum() > MAX_TABULATED_CELLS
    # Refused by its size, not after grounding (which took minutes and gigabytes).
    with pytest.raises(TabulationError, match="162,793 walkable cells; PFs are tabulated for at most 4,096"):
        pf_tables(state.layout)


def test_a_layout_of_too_many_movable_objects_is_refused_before_its_facts_are_written(monkeypatch):
    """850 blocks in a 40x40 room (a 115 kB .bdm line) took 159 s and 1.2 GB writing and parsing the copies
    of every block on every cell, before the grounding's time limit could act."""
    import groundlang.model.pf_tables as tables
    from groundlang.bdm import parse_bdm_state
    from groundlang.model.pf_tables import MAX_TABULATED_COPIES, TabulationError

    blocks = [f"block{k} (block): [x: {{{1 + k // 38}}} y: {{{2 + k % 38}}} shape: {{chair}} colour: {{red}} ]"
              for k in range(850)]
    line = ("{agent0 (agent): [x: {1} y: {1} ] , " + " , ".join(blocks)
            + " , room0 (room): [top: {40} left: {0} bottom: {0} right: {40} colour: {red} ] , }")
    state, _ = parse_bdm_state(line)
    monkeypatch.setattr(tables, "_copies", lambda layout: pytest.fail("wrote the copies"))
    with pytest.raises(TabulationError, match=f"851 movable objects on 1,521 walkable cells; PFs are tabulated "
                                              f"for at most {MAX_TABULATED_COPIES:,} objects x cells"):
        pf_tables(state.layout)
