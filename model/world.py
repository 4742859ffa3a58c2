"""Cleanup World as an OO-MDP: objects, layouts, states and push dynamics (palettes: :mod:`.palette`).

Coordinates follow the commands-to-tasks corpus: x grows east, y grows north,
a room is the rectangle LEFT..RIGHT x BOTTOM..TOP whose border cells are walls,
and a door rectangle clears the wall cells it covers. A cell is *inside* a room
when LEFT < x < RIGHT and BOTTOM < y < TOP. Cells that are neither inside a
room nor door cells cannot be entered.

Objects keep the corpus's names in file order (``room0``, ``door0``,
``block0``, ``agent0``) so that atoms printed here compare with gold labels.
groundlang calls the movable objects *toys*, as the paper does; the corpus
calls them blocks, hence their names.
"""

from __future__ import annotations

import enum
from collections import Counter
from dataclasses import dataclass, field, replace
from functools import cached_property, lru_cache

import numpy as np

from groundlang.model.palette import Palette, WorldError, get_palette

__all__ = ["Action", "ACTION_DELTAS", "Palette", "get_palette", "Room", "Door", "Toy", "Agent", "Layout", "State",
           "step", "replay", "WorldError", "MAX_LAYOUT_OBJECTS", "MAX_LAYOUT_ROOMS"]

# Rooms, doors and toys a layout may have: checking a layout costs about 0.2 ms a door and grows with the
# square of its rooms, and a 16 MB state line could hold a million doors. Chosen on no figure: the corpora's
# layouts have at most a dozen, and 4,000 doors are checked in about a second.
MAX_LAYOUT_OBJECTS = 4096
# Rooms a layout may have: a task library's groundings and the roles of their bystanders grow with a power of the
# rooms (1,600 rooms of one cell each took 75 s and 2.5 GB to follow one command; 256, 3.7 s and 320 MB).
# Chosen on no figure: the corpora's layouts have three rooms.
MAX_LAYOUT_ROOMS = 256


# The world's kinds of object, as the classes of logic/domain.lp (class/1) call them, and the prefix of
# their names (the corpora's: a toy is a "block"). The one place Python names them: the Cleanup World's
# dynamics (walls, doors, pushing) are code; a test checks that domain.lp declares the same classes.
AGENT_CLASS, ROOM_CLASS, DOOR_CLASS, TOY_CLASS = "agent", "room", "door", "toy"
NAME_PREFIXES = (("agent", AGENT_CLASS), ("room", ROOM_CLASS), ("door", DOOR_CLASS), ("block", TOY_CLASS))
WORLD_CLASSES = tuple(cls for _, cls in NAME_PREFIXES)


def object_class(name: str) -> str:
    """The class of an object of the world by its name (``block0`` is a toy); ValueError otherwise."""
    for prefix, cls in NAME_PREFIXES:
        if name.startswith(prefix) and name[len(prefix):].isdigit():
            return cls
    raise ValueError(f"cannot tell the class of object {name!r}")


class Action(enum.IntEnum):
    """Movement actions, with the corpus's spelling as ``name.lower()``."""

    NORTH = 0
    SOUTH = 1
    EAST = 2
    WEST = 3

    @classmethod
    def parse(cls, word: str) -> "Action":
        """Parse a corpus action word (case and surrounding spaces ignored)."""
        try:
            return cls[word.strip().upper()]
        except KeyError:
            raise WorldError(
                f"unknown action {word.strip()!r}; expected one of north, south, east, west"
            ) from None

    @property
    def word(self) -> str:
        return self.name.lower()


# (dx, dy) per action, indexed by Action value.
ACTION_DELTAS = np.array([[0, 1], [0, -1], [1, 0], [-1, 0]], dtype=np.int64)


@dataclass(frozen=True)
class Room:
    colour: str
    left: int
    top: int
    right: int
    bottom: int

    def contains(self, x: int, y: int) -> bool:
        """True when (x, y) lies strictly inside the room's walls."""
        return self.left < x < self.right and self.bottom < y < self.top


@dataclass(frozen=True)
class Door:
    left: int
    top: int
    right: int
    bottom: int

    def contains(self, x: int, y: int) -> bool:
        return self.left <= x <= self.right and self.bottom <= y <= self.top


@dataclass(frozen=True)
class Toy:
    colour: str
    shape: str
    x: int
    y: int


@dataclass(frozen=True)
class Agent:
    x: int
    y: int


@dataclass(frozen=True)
class Layout:
    """The static part of a state: rooms, doors and the toys' fixed attributes."""

    rooms: tuple[Room, ...]
    doors: tuple[Door, ...]
    toy_attributes: tuple[tuple[str, str], ...]  # (colour, shape) per toy
    palette: Palette = field(compare=True)
    # The values of the attributes the palette adds (Palette.added): (object name, attribute, value), one
    # per object of a class the palette gives the attribute, in the order of the objects' names.
    added_attributes: tuple[tuple[str, str, str], ...] = ()

    @cached_property
    def width(self) -> int:
        return max(r.right for r in self.rooms) + 1

    @cached_property
    def height(self) -> int:
        return max(r.top for r in self.rooms) + 1

    @cached_property
    def walkable(self) -> np.ndarray:
        """Boolean grid ``[width, height]``: cells an object may occupy.

        Room interiors, plus door cells; a door only clears cells that belong
        to some room's rectangle, it never opens the space outside all rooms.
        """
        interior = np.zeros((self.width, self.height), dtype=bool)
        covered = np.zeros_like(interior)
        for r in self.rooms:
            interior[r.left + 1 : r.right, r.bottom + 1 : r.top] = True
            covered[r.left : r.right + 1, r.bottom : r.top + 1] = True
        door = np.zeros_like(interior)
        for d in self.doors:
            door[max(d.left, 0) : max(d.right + 1, 0), max(d.bottom, 0) : max(d.top + 1, 0)] = True
        return interior | (door & covered)

    @cached_property
    def wall(self) -> np.ndarray:
        """Boolean grid ``[width, height]``: border cells of any room (before doors)."""
        grid = np.zeros((self.width, self.height), dtype=bool)
        for r in self.rooms:
            grid[r.left : r.right + 1, r.bottom] = True
            grid[r.left : r.right + 1, r.top] = True
            grid[r.left, r.bottom : r.top + 1] = True
            grid[r.right, r.bottom : r.top + 1] = True
        return grid

    @property
    def room_names(self) -> list[str]:
        return [f"room{i}" for i in range(len(self.rooms))]

    @property
    def door_names(self) -> list[str]:
        return [f"door{i}" for i in range(len(self.doors))]

    @property
    def toy_names(self) -> list[str]:
        return [f"block{i}" for i in range(len(self.toy_attributes))]

    @cached_property
    def objects(self) -> tuple[tuple[str, str, tuple[tuple[str, tuple], ...]], ...]:
        """Every object as ``(class, name, facts)``, the agent first: the one place where the world's
        kinds of object meet the schema's classes (``class/1`` of ``logic/domain.lp``; a test checks
        they agree). ``facts`` are ``(predicate, arguments)`` pairs, ``("colour", ("green",))``."""
        out = [(AGENT_CLASS, "agent0", ())]
        out += [(ROOM_CLASS, n, (("rect", (r.left, r.top, r.right, r.bottom)), ("colour", (r.colour,))))
                for n, r in zip(self.room_names, self.rooms)]
        out += [(DOOR_CLASS, n, (("rect", (d.left, d.top, d.right, d.bottom)),))
                for n, d in zip(self.door_names, self.doors)]
        out += [(TOY_CLASS, n, (("colour", (c,)), ("shape", (s,))))
                for n, (c, s) in zip(self.toy_names, self.toy_attributes)]
        if self.added_attributes:
            out = [(cls, name, facts + tuple((a, (v,)) for a, v in self.added_values(name).items()))
                   for cls, name, facts in out]
        return tuple(out)

    def added_values(self, name: str) -> dict[str, str]:
        """The added attributes' values of object ``name`` (``{"material": "wood"}``; empty: none)."""
        return dict(self._added_by_name.get(name, ()))

    @cached_property
    def _added_by_name(self) -> dict[str, tuple[tuple[str, str], ...]]:
        # Indexed once: an object at a time, a scan per object was quadratic in a large layout's objects.
        by_name: dict[str, list[tuple[str, str]]] = {}
        for name, attribute, value in self.added_attributes:
            by_name.setdefault(name, []).append((attribute, value))
        return {name: tuple(pairs) for name, pairs in by_name.items()}

    @property
    def movable_names(self) -> list[str]:
        """The objects whose positions make up a state, in the order of ``State.positions``."""
        return ["agent0"] + self.toy_names

    def validate(self) -> None:
        """Raise WorldError when rooms are degenerate or overlap, or a door opens no wall between two rooms.
        Once per distinct layout (a demonstration's states share theirs): the answer is remembered."""
        _validate_layout(self)

    def _validate(self) -> None:
        if not self.rooms:
            raise WorldError("a layout needs at least one room")
        count = len(self.rooms) + len(self.doors) + len(self.toy_attributes)
        if count > MAX_LAYOUT_OBJECTS:  # checking them costs time in their number (rooms: its square)
            raise WorldError(f"the layout has {count:,} rooms, doors and toys ({len(self.rooms):,}, {len(self.doors):,}, "
                             f"{len(self.toy_attributes):,}); at most {MAX_LAYOUT_OBJECTS:,} are read")
        if len(self.rooms) > MAX_LAYOUT_ROOMS:
            raise WorldError(f"the layout has {len(self.rooms):,} rooms; at most {MAX_LAYOUT_ROOMS} are read (what "
                             "following reads grows with a power of the rooms)")
        self._validate_added_attributes()
        self.palette.check_values(self.objects[1:])
        for i, r in enumerate(self.rooms):
            if r.right - r.left < 2 or r.top - r.bottom < 2:
                raise WorldError(
                    f"room{i} ({r.left},{r.top},{r.right},{r.bottom}) has no interior "
                    "(need RIGHT-LEFT >= 2 and TOP-BOTTOM >= 2)"
                )
            if min(r.left, r.bottom) < 0:
                raise WorldError(f"room{i} has a negative coordinate")
        bounds = np.array([(r.left, r.right, r.bottom, r.top) for r in self.rooms], dtype=np.int64).reshape(-1, 4)
        left, right, bottom, top = bounds.T
        for i in range(len(self.rooms) - 1):  # interiors overlap: against every later room at once
            overlap = ((np.maximum(left[i], left[i + 1:]) + 1 < np.minimum(right[i], right[i + 1:]))
                       & (np.maximum(bottom[i], bottom[i + 1:]) + 1 < np.minimum(top[i], top[i + 1:])))
            if overlap.any():
                raise WorldError(f"room{i} and room{i + 1 + int(np.argmax(overlap))} overlap")
        for i, d in enumerate(self.doors):
            if d.right < d.left or d.top < d.bottom:
                raise WorldError(f"door{i} has RIGHT < LEFT or TOP < BOTTOM")
            where = f"door{i} ({d.left},{d.top},{d.right},{d.bottom})"
            if min(d.left, d.bottom) < 0 or d.right >= self.width or d.top >= self.height:
                raise WorldError(f"{where} reaches outside the rooms (the grid is {self.width} x {self.height})")
            problem = _door_problem(bounds, d)
            if problem:
                raise WorldError(f"{where} {problem}")
        # Two doors on one cell are one opening named twice: a command could name either, a plan not tell them
        # apart. Refused as overlapping rooms are (against every later door at once).
        doors = np.array([(d.left, d.right, d.bottom, d.top) for d in self.doors], dtype=np.int64).reshape(-1, 4)
        for i in range(len(self.doors) - 1):
            shared = ((np.maximum(doors[i, 0], doors[i + 1:, 0]) <= np.minimum(doors[i, 1], doors[i + 1:, 1]))
                      & (np.maximum(doors[i, 2], doors[i + 1:, 2]) <= np.minimum(doors[i, 3], doors[i + 1:, 3])))
            if shared.any():
                raise WorldError(f"door{i} and door{i + 1 + int(np.argmax(shared))} open a wall cell both: one "
                                 "door is enough there")

    def _validate_added_attributes(self) -> None:
        """Every object of a class the palette gives an attribute has one of its values, and no other
        object has one."""
        pal = self.palette
        twice = [k for k, c in Counter((n, a) for n, a, _ in self.added_attributes).items() if c > 1]
        if twice:
            raise WorldError(f"{twice[0][0]} is given two values of {twice[0][1]}")
        given = {(n, a): v for n, a, v in self.added_attributes}
        names = {ROOM_CLASS: self.room_names, DOOR_CLASS: self.door_names, TOY_CLASS: self.toy_names}
        wanted = {(n, a) for cls, objects in names.items() for a in pal.attributes_of(cls) for n in objects}
        if extra := sorted(set(given) - wanted):
            n, a = extra[0]
            raise WorldError(f"{n} has a {a}, which palette {pal.name!r} does not give its class "
                             "(attribute/2 of the palette file)")
        if missing := sorted(wanted - set(given)):
            n, a = missing[0]
            raise WorldError(f"{n} has no {a}; palette {pal.name!r} gives every {object_class(n)} one")
        for (n, a), v in given.items():
            if v not in pal.values_of(a):
                raise WorldError(f"{n} has the {a} {v!r}, which palette {pal.name!r} does not have "
                                 f"(it has {', '.join(pal.values_of(a))})")


def _door_problem(bounds: np.ndarray, d: Door) -> str | None:
    """Why a door joins no two rooms, or None; ``bounds`` ``[R, 4]``: each room's left, right, bottom, top.
    Every door cell must lie in some room's rectangle (a cell between two rooms' walls stays solid), and the
    door must open the walls of two rooms: a cell on a room's wall next to that room's interior. Vectorised
    over the door's cells and the rooms at once (one room at a time, 2,000 doors among 2,000 rooms took
    minutes)."""
    xs, ys = np.meshgrid(np.arange(d.left, d.right + 1), np.arange(d.bottom, d.top + 1), indexing="ij")
    xs, ys = xs.ravel()[None, :], ys.ravel()[None, :]  # [1, C]
    left, right, bottom, top = (bounds[:, k, None] for k in range(4))  # [R, 1] each
    inside = (left <= xs) & (xs <= right) & (bottom <= ys) & (ys <= top)  # [R, C]
    # on the room's wall next to its interior (corners excluded): the cell across the wall is inside
    beside = ((left < xs) & (xs < right) & ((ys == bottom) | (ys == top))) | (
        (bottom < ys) & (ys < top) & ((xs == left) | (xs == right)))
    if not inside.any(axis=0).all():
        return "has cells outside every room; a door opens the walls of two rooms"
    if int(beside.any(axis=1).sum()) < 2:
        return "is not in a wall between two rooms; a door opens the walls of two rooms"
    return None


def _validate_layout(layout: Layout) -> None:
    try:
        hash(layout)
    except TypeError:  # built with lists: checked every time
        layout._validate()
    else:
        _validate_hashable_layout(layout)


@lru_cache(maxsize=1024)
def _validate_hashable_layout(layout: Layout) -> None:
    layout._validate()  # raises for a bad layout, and a raise is not remembered


@dataclass(frozen=True)
class State:
    """A full Cleanup World state: a layout plus the agent's and toys' positions."""

    layout: Layout
    agent: Agent
    toys: tuple[Toy, ...]

    @property
    def positions(self) -> np.ndarray:
        """Dynamic part as ``[1 + num_toys, 2]`` int64 (agent first, then toys)."""
        return np.array([[self.agent.x, self.agent.y]] + [[t.x, t.y] for t in self.toys])

    def with_positions(self, positions: np.ndarray) -> "State":
        agent = Agent(int(positions[0, 0]), int(positions[0, 1]))
        toys = tuple(
            replace(t, x=int(p[0]), y=int(p[1])) for t, p in zip(self.toys, positions[1:])
        )
        return State(self.layout, agent, toys)

    def validate(self) -> None:
        """Raise WorldError when an object stands where no object may be."""
        self.layout.validate()
        walk = self.layout.walkable
        w, h = walk.shape
        for name, (x, y) in zip(["agent0"] + self.layout.toy_names, self.positions):
            if not (0 <= x < w and 0 <= y < h) or not walk[x, y]:
                raise WorldError(f"{name} at ({x},{y}) is inside a wall or outside every room")
        shared = self.shared_cell()
        if shared is not None:
            raise WorldError(shared)

    def shared_cell(self) -> str | None:
        """Which two objects share a cell ("agent0 and block1 share the cell (3,4)"), or None."""
        seen: dict[tuple[int, int], str] = {}
        for name, (x, y) in zip(["agent0"] + self.layout.toy_names, self.positions.tolist()):
            if (x, y) in seen:
                return f"{seen[(x, y)]} and {name} share the cell ({x},{y})"
            seen[(x, y)] = name
        return None


def step(state: State, action: Action) -> State:
    """Apply one move with Sokoban pushes; blocked moves leave the state unchanged."""
    pos = state.positions
    walk = state.layout.walkable
    dx, dy = ACTION_DELTAS[int(action)]
    ax, ay = pos[0]
    tx, ty = ax + dx, ay + dy

    def free(x: int, y: int) -> bool:
        return 0 <= x < walk.shape[0] and 0 <= y < walk.shape[1] and bool(walk[x, y])

    if not free(tx, ty):
        return state
    for i in range(1, len(pos)):
        if pos[i, 0] == tx and pos[i, 1] == ty:
            bx, by = tx + dx, ty + dy
            blocked = not free(bx, by) or any(
                pos[j, 0] == bx and pos[j, 1] == by for j in range(1, len(pos))
            )
            if blocked:
                return state
            new = pos.copy()
            new[i] = (bx, by)
            new[0] = (tx, ty)
            return state.with_positions(new)
    new = pos.copy()
    new[0] = (tx, ty)
    return state.with_positions(new)


def replay(start: State, actions) -> tuple[State, ...]:
    """The states a sequence of actions visits from ``start``, ``start`` included."""
    states = [start]
    for action in actions:
        states.append(step(states[-1], action))
    return tuple(states)
