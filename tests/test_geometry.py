"""model.geometry: ASP facts of a layout/state and the per-cell tables clingo computes from them."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from groundlang.logic.program import AspError
from groundlang.model.geometry import CellTables, cell_tables, layout_facts, state_facts
from groundlang.model.world import Agent, Door, Layout, Room, State, Toy, get_palette

SOKOBAN = get_palette("sokoban")


def corpus_like_layout() -> Layout:
    # The commands-to-tasks layout: room0 green (north-west), room1 red (north-east), room2 blue (south).
    return Layout(
        (Room("green", 0, 10, 6, 4), Room("red", 6, 10, 10, 4), Room("blue", 0, 4, 10, 0)),
        (Door(3, 4, 3, 3), Door(8, 4, 8, 3), Door(6, 6, 6, 6)),
        (("yellow", "star"),),
        SOKOBAN,
    )


def reference_tables(layout: Layout) -> tuple[np.ndarray, np.ndarray]:
    """The same tables straight from model.world's geometry (Room.contains, Door.contains, walkable)."""
    w, h = layout.width, layout.height
    room_of = np.full((w, h), -1)
    door_of = np.full((w, h), -1)
    walk = layout.walkable
    for x in range(w):
        for y in range(h):
            rooms = [i for i, r in enumerate(layout.rooms) if r.contains(x, y)]
            doors = [i for i, d in enumerate(layout.doors) if d.contains(x, y) and walk[x, y]]
            room_of[x, y] = rooms[0] if rooms else -1
            door_of[x, y] = doors[0] if doors else -1
    return room_of, door_of


def check_against_world(layout: Layout) -> CellTables:
    tables = cell_tables(layout)
    assert tables.room_of.shape == tables.door_of.shape == (layout.width, layout.height)
    assert tables.room_of.dtype == tables.door_of.dtype == np.int16
    np.testing.assert_array_equal((tables.room_of >= 0) | (tables.door_of >= 0), layout.walkable)
    room_of, door_of = reference_tables(layout)
    np.testing.assert_array_equal(tables.room_of, room_of)
    np.testing.assert_array_equal(tables.door_of, door_of)
    return tables


def test_corpus_layout_tables():
    tables = check_against_world(corpus_like_layout())
    assert (tables.room_of == 0).sum() == 5 * 5  # x 1..5, y 5..9
    assert (tables.room_of == 1).sum() == 3 * 5
    assert (tables.room_of == 2).sum() == 9 * 3
    assert sorted(zip(*np.nonzero(tables.door_of == 0))) == [(3, 3), (3, 4)]
    assert sorted(zip(*np.nonzero(tables.door_of == 2))) == [(6, 6)]
    assert tables.room_of[3, 4] == -1 and tables.room_of[3, 3] == 2  # a door cell inside a room is both


def test_tables_are_cached_per_layout_and_read_only():
    a = cell_tables(corpus_like_layout())
    assert cell_tables(corpus_like_layout()) is a  # equal layouts share one clingo run
    with pytest.raises(ValueError):
        a.room_of[1, 1] = 7


def test_door_outside_every_room_and_overlapping_doors():
    layout = Layout((Room("red", 0, 4, 4, 0), Room("blue", 4, 4, 8, 0)),
                    (Door(4, 3, 4, 1), Door(4, 2, 4, 2), Door(20, 2, 20, 2), Door(-3, 2, -1, 2)),
                    (), SOKOBAN)
    tables = check_against_world(layout)
    assert list(tables.door_of[4, 1:4]) == [0, 0, 0]  # the lower index wins where doors overlap
    assert not (tables.door_of >= 2).any()


def test_example_files(fixtures):
    from groundlang.corpus import example_corpus_path, read_state_file

    paths = sorted(example_corpus_path().glob("*.state"))
    assert paths, "the example corpus ships .state files"
    for path in paths:
        check_against_world(read_state_file(path, "sokoban").layout)


def test_shared_corpus_layouts(shared_corpus):
    from groundlang.corpus import read_instance

    layouts = {read_instance(p, "sokoban").initial_state.layout
               for p in sorted((shared_corpus / "allTurkTrain").glob("*.txt"))[:12]}
    for layout in layouts:
        check_against_world(layout)


@st.composite
def layouts(draw):
    """Rooms tiled on a coarse grid (no interior overlap), doors anywhere near them."""
    cols, rows = draw(st.integers(1, 3)), draw(st.integers(1, 3))
    rooms = []
    for c in range(cols):
        for r in range(rows):
            if draw(st.booleans()) or not rooms:
                w, h = draw(st.integers(2, 5)), draw(st.integers(2, 5))
                left, bottom = 5 * c, 5 * r
                rooms.append(Room(draw(st.sampled_from(SOKOBAN.colours)), left, bottom + h, left + w, bottom))
    doors = []
    for _ in range(draw(st.integers(0, 4))):
        x, y = draw(st.integers(-1, 16)), draw(st.integers(-1, 16))
        doors.append(Door(x, y + draw(st.integers(0, 2)), x + draw(st.integers(0, 2)), y))
    return Layout(tuple(rooms), tuple(doors), (), SOKOBAN)


@settings(max_examples=40, deadline=None)
@given(layouts())
def test_random_layouts_agree_with_walkable(layout):
    check_against_world(layout)


def test_facts_name_objects_in_file_order():
    layout = corpus_like_layout()
    state = State(layout, Agent(8, 6), (Toy("yellow", "star", 4, 8),))
    facts = state_facts(state)
    assert "room(room2). rect(room2,0,4,10,0). colour(room2,blue)." in facts
    assert "door(door1). rect(door1,8,4,8,3)." in facts
    assert "toy(block0). colour(block0,yellow). shape(block0,star)." in facts
    assert "agent(agent0)." in facts and "at(agent0,8,6)." in facts and "at(block0,4,8)." in facts
    assert "palette_colour(darkGray)." in layout_facts(layout) and "agent(" not in layout_facts(layout)


def test_attribute_that_is_not_an_asp_constant_is_refused():
    from groundlang.model.world import Palette

    odd = Palette("odd", ("Dark Gray",), ("star",))
    layout = Layout((Room("Dark Gray", 0, 4, 4, 0),), (), (), odd)
    with pytest.raises(AspError, match="'Dark Gray' cannot be an ASP constant"):
        layout_facts(layout)


def test_door_left_of_the_grid_opens_nothing_in_asp():
    layout = Layout((Room("red", 0, 4, 4, 0),), (Door(-5, 2, -3, 2),), (), SOKOBAN)
    tables = cell_tables(layout)
    assert (tables.door_of == -1).all() and tables.room_of[0, 2] == -1


def test_door_left_of_the_grid_agrees_with_walkable():
    check_against_world(Layout((Room("red", 0, 4, 4, 0),), (Door(-5, 2, -3, 2),), (), SOKOBAN))
