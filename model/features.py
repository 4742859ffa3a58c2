"""Per-state values of grounded propositional functions, as tensors over a state space.

A feature is a grounded PF (``toyInRoom(block0, room2)``); its value in every
state of a :class:`~groundlang.model.statespace.StateSpace` comes from the
per-cell tables clingo computes once per layout
(:func:`groundlang.model.geometry.cell_tables`), looked up with the states'
positions by fancy indexing: one array operation per feature, never a call
per state.

Position PFs vary over states: ``agentInRoom(agent0, roomR)``,
``toyInRoom(blockI, roomR)``, ``agentInDoor(agent0, doorD)``,
``toyInDoor(blockI, doorD)``, ``agentTouchingToy(agent0, blockI)`` (the agent
on one of the four cells next to the toy). Colour and shape PFs
(``roomIsGreen(room0)``, ``toyIsYellow(block0)``, ``toyIsStar(block0)``) are
constant columns read from the layout. The corpus's spellings
(``blockInRoom`` ...) are accepted as aliases.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import torch

from groundlang.logic.atoms import PREDICATE_ALIASES, Atom, attribute_pf, parse_atom

from .statespace import StateSpace
from .world import Layout

if TYPE_CHECKING:  # geometry needs clingo; features only read its tables
    from .geometry import CellTables

__all__ = ["FeatureError", "POSITION_PREDICATES", "position_atoms", "feature_matrix", "goal_mask"]

# Position PF -> classes of its arguments.
POSITION_PREDICATES: dict[str, tuple[str, str]] = {
    "agentInRoom": ("agent", "room"),
    "toyInRoom": ("toy", "room"),
    "agentInDoor": ("agent", "door"),
    "toyInDoor": ("toy", "door"),
    "agentTouchingToy": ("agent", "toy"),
}


class FeatureError(ValueError):
    """An atom that is not a PF of the layout (unknown predicate, object or arity)."""


def position_atoms(layout: Layout) -> list[Atom]:
    """Every grounded position PF of a layout, grouped by predicate in the order of POSITION_PREDICATES."""
    agent = "agent0"
    atoms = [Atom("agentInRoom", (agent, r)) for r in layout.room_names]
    atoms += [Atom("toyInRoom", (t, r)) for t in layout.toy_names for r in layout.room_names]
    atoms += [Atom("agentInDoor", (agent, d)) for d in layout.door_names]
    atoms += [Atom("toyInDoor", (t, d)) for t in layout.toy_names for d in layout.door_names]
    atoms += [Atom("agentTouchingToy", (agent, t)) for t in layout.toy_names]
    return atoms


class _Columns:
    """Feature columns of one state space, computing each per-object lookup once."""

    def __init__(self, space: StateSpace, tables: CellTables) -> None:
        layout = space.layout
        expected = layout.walkable.shape
        for name in ("room_of", "door_of"):
            grid = getattr(tables, name)
            if grid.shape != expected:
                raise FeatureError(
                    f"cell table {name} has shape {tuple(grid.shape)}, but the layout's grid is {expected}"
                )
        self.space = space
        self.layout = layout
        self.tables = tables
        self.objects = {"agent": {"agent0": 0}, "toy": {t: 1 + i for i, t in enumerate(layout.toy_names)},
                        "room": {r: i for i, r in enumerate(layout.room_names)},
                        "door": {d: i for i, d in enumerate(layout.door_names)}}
        self._lookups: dict[tuple[str, int], np.ndarray] = {}

    def _object(self, atom: Atom, position: int, kind: str) -> int:
        name = atom.args[position]
        try:
            return self.objects[kind][name]
        except KeyError:
            known = ", ".join(self.objects[kind]) or "none"
            raise FeatureError(
                f"{atom}: argument {position + 1} {name!r} is not {'an' if kind == 'agent' else 'a'} "
                f"{kind} of this layout (known: {known})"
            ) from None

    def _lookup(self, table: str, obj: int) -> np.ndarray:
        """``[S]`` room or door index under object ``obj`` (0 = agent), -1 where none."""
        key = (table, obj)
        if key not in self._lookups:
            pos = self.space.positions[:, obj]
            self._lookups[key] = getattr(self.tables, table)[pos[:, 0], pos[:, 1]]
        return self._lookups[key]

    def column(self, atom: Atom | str) -> np.ndarray | bool:
        """``[S]`` bool values of a position PF, or one bool for a colour/shape PF."""
        if isinstance(atom, str):
            atom = parse_atom(atom)
        predicate = PREDICATE_ALIASES.get(atom.predicate, atom.predicate)
        if predicate in POSITION_PREDICATES:
            kinds = POSITION_PREDICATES[predicate]
            if len(atom.args) != 2:
                raise FeatureError(f"{atom}: {predicate} takes 2 arguments ({', '.join(kinds)})")
            first = self._object(atom, 0, kinds[0])
            second = self._object(atom, 1, kinds[1])
            if kinds[1] == "room":
                return self._lookup("room_of", first) == second
            if kinds[1] == "door":
                return self._lookup("door_of", first) == second
            pos = self.space.positions
            distance = np.abs(pos[:, first, 0] - pos[:, second, 0]) + np.abs(pos[:, first, 1] - pos[:, second, 1])
            return distance == 1
        return self._attribute(atom, predicate)

    def _attribute(self, atom: Atom, predicate: str) -> bool:
        palette = self.layout.palette
        for prefix, kind in (("roomIs", "room"), ("toyIs", "toy")):
            if not predicate.startswith(prefix) or len(predicate) == len(prefix):
                continue
            value = predicate[len(prefix):]
            colours = {attribute_pf("", c): c for c in palette.colours}
            shapes = {attribute_pf("", s): s for s in palette.shapes} if kind == "toy" else {}
            if value not in colours and value not in shapes:
                break
            if len(atom.args) != 1:
                raise FeatureError(f"{atom}: {predicate} takes 1 argument (a {kind})")
            index = self._object(atom, 0, kind)
            if kind == "room":
                return self.layout.rooms[index].colour == colours[value]
            colour, shape = self.layout.toy_attributes[index - 1]
            return colour == colours[value] if value in colours else shape == shapes[value]
        raise FeatureError(
            f"{atom}: unknown predicate {atom.predicate!r}; expected a position PF "
            f"({', '.join(POSITION_PREDICATES)}) or a colour/shape PF of palette {palette.name!r} "
            "such as roomIsGreen or toyIsStar"
        )


def _boolean_matrix(space: StateSpace, atoms: Sequence[Atom | str], tables: CellTables) -> np.ndarray:
    columns = _Columns(space, tables)
    out = np.empty((space.num_states, len(atoms)), dtype=bool)
    for f, atom in enumerate(atoms):
        out[:, f] = columns.column(atom)
    return out


def feature_matrix(space: StateSpace, atoms: Sequence[Atom | str], tables: CellTables) -> torch.Tensor:
    """Values ``[S, F]`` float32 (0/1) of grounded PFs ``atoms`` in every state of ``space``.

    Raises FeatureError (a ValueError) naming the first atom whose predicate,
    arity or objects do not belong to the layout.
    """
    return torch.from_numpy(_boolean_matrix(space, list(atoms), tables).astype(np.float32))


def goal_mask(space: StateSpace, goal_atoms: Iterable[Atom | str], tables: CellTables) -> np.ndarray:
    """``[S]`` bool: states where every atom of the conjunction ``goal_atoms`` holds."""
    atoms = list(goal_atoms)
    if not atoms:
        raise FeatureError("empty goal: expected one or more atoms like agentInRoom(agent0, room1)")
    return _boolean_matrix(space, atoms, tables).all(axis=1)


@dataclass(frozen=True)
class _SingleState:
    """One state seen as a state space of size 1 (what the column builders read)."""

    layout: Layout
    positions: np.ndarray  # [1, 1 + k, 2]
    num_states: int = 1


def atoms_hold(state, atoms: Sequence[Atom | str], tables: CellTables) -> np.ndarray:
    """``[F]`` bool: which of ``atoms`` hold in one ``model.world.State`` (as in feature_matrix)."""
    return _boolean_matrix(_SingleState(state.layout, state.positions[None]), list(atoms), tables)[0]
