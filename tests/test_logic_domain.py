"""Named ASP cases for domain.lp (walls, doors, inside cells) and pfs.lp (every PF)."""

from __future__ import annotations

from functools import lru_cache

import pytest

from groundlang.logic.program import Program, package_source
from groundlang.logic.tasks import pf_name

# Two rooms sharing the wall x=4, a door at (4,2) in it, a door outside every room.
#   room0: x 0..4, y 0..4 (interior x 1..3, y 1..3), green
#   room1: x 4..8, y 0..4 (interior x 5..7, y 1..3), darkGray
TWO_ROOMS = """
palette_colour(green; darkGray; yellow; red). palette_shape(star; moon).
room(room0). rect(room0, 0, 4, 4, 0). colour(room0, green).
room(room1). rect(room1, 4, 4, 8, 0). colour(room1, darkGray).
door(door0). rect(door0, 4, 2, 4, 2).
door(door1). rect(door1, 10, 2, 10, 2).
"""
TOYS = """
toy(block0). colour(block0, yellow). shape(block0, star). at(block0, 6, 2).
toy(block1). colour(block1, red). shape(block1, moon). at(block1, 4, 2).
agent(agent0). at(agent0, 3, 2).
"""
AGENT_IN_DOOR = "agent(agent0). at(agent0, 4, 2). toy(block0). colour(block0, red). shape(block0, moon). at(block0, 1, 1)."


# The Williams domain's three rooms (tests/fixtures/williams2018/one.state), room0's colour given.
WILLIAMS = ("domain.lp", "pfs.lp", "domains/williams2018.lp")
THREE_ROOMS = """
palette_colour(red; green; blue; yellow). palette_shape(chair; box).
room(room0). rect(room0, 0, 4, 4, 0). colour(room0, {room0}).
room(room1). rect(room1, 4, 4, 8, 0). colour(room1, red).
room(room2). rect(room2, 0, 8, 8, 4). colour(room2, green).
door(door0). rect(door0, 2, 4, 2, 4). door(door1). rect(door1, 6, 4, 6, 4).
agent(agent0). at(agent0, 2, 2). toy(block0). colour(block0, red). shape(block0, chair). at(block0, 2, 6).
"""


@lru_cache(maxsize=None)
def program(*names: str) -> Program:
    return Program(tuple(package_source(n) for n in names))


CASES = [
    # (name, programs, facts, must appear, must not appear)
    ("inside cells strictly within the walls", ("domain.lp",), TWO_ROOMS,
     ["inside(room0,1,1)", "inside(room0,3,3)", "inside(room1,5,1)", "inside(room1,7,3)"],
     ["inside(room0,0,0)", "inside(room0,4,2)", "inside(room1,4,2)", "inside(room0,2,4)", "inside(room1,8,3)"]),
    ("borders are every rectangle edge", ("domain.lp",), TWO_ROOMS,
     ["border(0,0)", "border(4,2)", "border(8,4)", "border(2,4)", "border(6,0)"],
     ["border(2,2)", "border(6,3)"]),
    ("a door clears a shared wall cell", ("domain.lp",), TWO_ROOMS,
     ["door_cell(door0,4,2)", "walkable(4,2)", "wall(4,1)", "wall(4,3)", "wall(0,0)"],
     ["wall(4,2)", "wall(2,2)", "door_cell(door0,4,1)"]),
    ("a door outside every room opens nothing", ("domain.lp",), TWO_ROOMS,
     [], ["door_cell(door1,10,2)", "walkable(10,2)", "covered(10,2)"]),
    ("objects by class", ("domain.lp",), TWO_ROOMS + TOYS,
     ["object(room,room0)", "object(door,door1)", "object(toy,block1)", "object(agent,agent0)", "class(door)"],
     ["object(room,block0)"]),
    ("agentInRoom", ("domain.lp", "pfs.lp"), TWO_ROOMS + TOYS,
     ["holds(agentInRoom,(agent0,room0))"], ["holds(agentInRoom,(agent0,room1))"]),
    ("toyInRoom, not in a door cell", ("domain.lp", "pfs.lp"), TWO_ROOMS + TOYS,
     ["holds(toyInRoom,(block0,room1))"],
     ["holds(toyInRoom,(block0,room0))", "holds(toyInRoom,(block1,room0))", "holds(toyInRoom,(block1,room1))"]),
    ("toyInDoor", ("domain.lp", "pfs.lp"), TWO_ROOMS + TOYS,
     ["holds(toyInDoor,(block1,door0))"], ["holds(toyInDoor,(block0,door0))", "holds(agentInDoor,(agent0,door0))"]),
    ("agentInDoor", ("domain.lp", "pfs.lp"), TWO_ROOMS + AGENT_IN_DOOR,
     ["holds(agentInDoor,(agent0,door0))"],
     ["holds(agentInRoom,(agent0,room0))", "holds(agentInRoom,(agent0,room1))", "holds(agentInDoor,(agent0,door1))"]),
    ("agentTouchingToy: next cell only", ("domain.lp", "pfs.lp"), TWO_ROOMS + TOYS,
     ["holds(agentTouchingToy,(agent0,block1))"], ["holds(agentTouchingToy,(agent0,block0))"]),
    ("agentTouchingToy: not diagonally", ("domain.lp", "pfs.lp"),
     TWO_ROOMS + "agent(agent0). at(agent0, 2, 2). toy(block0). at(block0, 3, 3).",
     [], ["holds(agentTouchingToy,(agent0,block0))"]),
    ("room colour", ("domain.lp", "pfs.lp"), TWO_ROOMS + TOYS,
     ["holds(roomIs(green),(room0,))", "holds(roomIs(darkGray),(room1,))"],
     ["holds(roomIs(green),(room1,))", "holds(roomIs(red),(room0,))"]),
    ("toy colour and shape", ("domain.lp", "pfs.lp"), TWO_ROOMS + TOYS,
     ["holds(toyIs(yellow),(block0,))", "holds(toyIs(star),(block0,))", "holds(toyIs(moon),(block1,))"],
     ["holds(toyIs(star),(block1,))", "holds(toyIs(red),(block0,))", "holds(roomIs(yellow),(block0,))"]),
    ("spatial PFs: a door level with the agent is on one side only", ("domain.lp", "pfs.lp"), TWO_ROOMS + TOYS,
     ["holds(doorEastOfAgent,(door0,))", "holds(doorEastOfAgent,(door1,))"],
     ["holds(doorWestOfAgent,(door0,))", "holds(doorNorthOfAgent,(door0,))", "holds(doorSouthOfAgent,(door0,))"]),
    ("spatial PFs: diagonal sides, doors only", ("domain.lp", "pfs.lp"), TWO_ROOMS + "agent(agent0). at(agent0, 6, 3).",
     ["holds(doorWestOfAgent,(door0,))", "holds(doorSouthOfAgent,(door0,))",
      "holds(doorEastOfAgent,(door1,))", "holds(doorSouthOfAgent,(door1,))"],
     ["holds(doorEastOfAgent,(door0,))", "holds(doorNorthOfAgent,(door1,))",
      "holds(doorWestOfAgent,(room0,))", "holds(doorWestOfAgent,(agent0,))"]),
    ("PF classes and signatures", ("domain.lp", "pfs.lp"), TWO_ROOMS,
     ["pf(position,agentInRoom,(agent,room))", "pf(position,toyInRoom,(toy,room))",
      "pf(position,agentInDoor,(agent,door))", "pf(position,toyInDoor,(toy,door))",
      "pf(position,agentTouchingToy,(agent,toy))", "pf(colour,roomIs(darkGray),(room,))",
      "pf(colour,toyIs(red),(toy,))", "pf(shape,toyIs(moon),(toy,))", "pf(spatial,doorWestOfAgent,(door,))"],
     ["pf(shape,toyIs(red),(toy,))", "pf(colour,toyIs(star),(toy,))", "pf(position,roomIs(green),(room,))"]),
    # a superlative among the rooms of one colour holds only where another room has that colour: room2 and room0
    # are green (areas 21 and 9), room1 alone red; a red chair is no room of red's
    # and a superlative picks out one: room0 and room1 tie for smallest (area 9), so neither is "the smallest room"
    ("superlatives of a colour compare rooms of that colour", WILLIAMS, THREE_ROOMS.format(room0="green"),
     ["holds(roomIsLargestOfItsColour,(room2,))", "holds(roomIsSmallestOfItsColour,(room0,))",
      "holds(roomIsLargest,(room2,))"],
     ["holds(roomIsLargestOfItsColour,(room0,))", "holds(roomIsSmallestOfItsColour,(room2,))",
      "holds(roomIsLargestOfItsColour,(room1,))", "holds(roomIsSmallestOfItsColour,(room1,))",
      "holds(roomIsSmallest,(room0,))", "holds(roomIsSmallest,(room1,))"]),
    ("a tie among the rooms of one colour names none of them", WILLIAMS, THREE_ROOMS.format(room0="red"),
     ["holds(roomIs(red),(room0,))", "holds(roomIs(red),(room1,))", "holds(roomIsLargest,(room2,))"],
     [f"holds(roomIs{size}OfItsColour,({room},))" for size in ("Largest", "Smallest")
      for room in ("room0", "room1", "room2")] + ["holds(roomIsSmallest,(room0,))", "holds(roomIsSmallest,(room1,))"]),
    # areas 6 (room0), 12 (room1) and 12 (room2, narrowed): two rooms tie for the largest, one is the smallest
    ("a tie for the largest names no room", WILLIAMS,
     THREE_ROOMS.format(room0="blue").replace("rect(room0, 0, 4, 4, 0)", "rect(room0, 0, 4, 3, 0)")
                                      .replace("rect(room1, 4, 4, 8, 0)", "rect(room1, 3, 4, 8, 0)")
                                      .replace("rect(room2, 0, 8, 8, 4)", "rect(room2, 0, 8, 5, 4)"),
     ["holds(roomIsSmallest,(room0,))"],
     ["holds(roomIsLargest,(room1,))", "holds(roomIsLargest,(room2,))", "holds(roomIsLargest,(room0,))"]),
    ("the smallest room where one is smaller than the others", WILLIAMS,
     THREE_ROOMS.format(room0="blue").replace("rect(room0, 0, 4, 4, 0)", "rect(room0, 0, 4, 3, 0)")
                                      .replace("rect(room1, 4, 4, 8, 0)", "rect(room1, 3, 4, 8, 0)"),
     ["holds(roomIsSmallest,(room0,))", "holds(roomIsLargest,(room2,))"],
     ["holds(roomIsSmallest,(room1,))", "holds(roomIsLargest,(room1,))", "holds(roomIsSmallest,(room2,))"]),
    ("no superlative of a colour no other room has", WILLIAMS, THREE_ROOMS.format(room0="blue"),
     ["holds(roomIs(blue),(room0,))", "holds(roomIsLargest,(room2,))"],
     [f"holds(roomIs{size}OfItsColour,({room},))" for size in ("Largest", "Smallest")
      for room in ("room0", "room1", "room2")]),
]


@pytest.mark.parametrize("name, programs, facts, must, must_not", CASES, ids=[c[0] for c in CASES])
def test_asp_case(name, programs, facts, must, must_not):
    (model,) = program(*programs).solve(facts, models=1)
    atoms = {str(s).replace(" ", "") for s in model}
    assert set(must) <= atoms, sorted(set(must) - atoms)
    assert not set(must_not) & atoms, sorted(set(must_not) & atoms)


def test_every_position_pf_is_declared_once():
    (model,) = program("domain.lp", "pfs.lp").solve(TWO_ROOMS, models=1)
    position = sorted(str(s.arguments[1]) for s in model if s.name == "pf" and s.arguments[0].name == "position")
    assert position == ["agentInDoor", "agentInRoom", "agentTouchingToy", "toyInDoor", "toyInRoom"]


def test_pf_names_capitalise_the_value():
    (model,) = program("domain.lp", "pfs.lp").solve(TWO_ROOMS + TOYS, models=1)
    names = {pf_name(s.arguments[0]) for s in model if s.name == "holds"}
    assert names == {"agentInRoom", "toyInRoom", "toyInDoor", "agentTouchingToy", "roomIsGreen",
                     "roomIsDarkGray", "toyIsYellow", "toyIsStar", "toyIsRed", "toyIsMoon", "doorEastOfAgent"}
