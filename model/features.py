"""Per-state values of grounded propositional functions, as tensors over a state space.

A feature is a grounded PF (``toyInRoom(block0, room2)``); its value in every
state of a :class:`~groundlang.model.statespace.StateSpace` comes from the PF
tables clingo computes once per layout (:func:`groundlang.model.pf_tables.pf_tables`:
where each PF holds for every placement of its movable arguments), looked up
with the states' positions by fancy indexing: one array operation per feature,
never a call per state. Which PFs exist, and what they mean, is the domain's
ASP (``logic/pfs.lp`` and a library's own PF rules); nothing here names one.
The corpus's spellings (``blockInRoom`` ...) are accepted as aliases.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
import torch

from groundlang.logic.atoms import Atom

from .pf_tables import PFTables, TabulationError
from .statespace import StateSpace
from .world import Layout

__all__ = ["FeatureError", "position_atoms", "feature_matrix", "goal_mask", "atoms_hold", "atoms_hold_along"]

# An atom that is not a PF of the layout (unknown predicate, object or arity).
FeatureError = TabulationError


def position_atoms(layout: Layout, tables: PFTables | None = None) -> list[Atom]:
    """Every grounded position PF of a layout (the PFs that change with the state), by PF then objects."""
    if tables is None:
        from .pf_tables import pf_tables

        tables = pf_tables(layout)
    return list(tables.position_atoms)


def _boolean_matrix(layout: Layout, positions: np.ndarray, atoms: Sequence[Atom | str],
                    tables: PFTables) -> np.ndarray:
    if tables.layout != layout:
        raise FeatureError(f"the PF tables are of a {tables.layout.width}x{tables.layout.height} layout other than "
                           f"this {layout.width}x{layout.height} one")
    out = np.empty((len(positions), len(atoms)), dtype=bool)
    for f, atom in enumerate(atoms):
        out[:, f] = tables.column(atom, positions)
    return out


def feature_matrix(space: StateSpace, atoms: Sequence[Atom | str], tables: PFTables) -> torch.Tensor:
    """Values ``[S, F]`` float32 (0/1) of grounded PFs ``atoms`` in every state of ``space``.

    Raises FeatureError (a ValueError) naming the first atom whose predicate,
    arity or objects do not belong to the layout.
    """
    return torch.from_numpy(_boolean_matrix(space.layout, space.positions, list(atoms), tables).astype(np.float32))


def goal_mask(space: StateSpace, goal_atoms: Iterable[Atom | str], tables: PFTables) -> np.ndarray:
    """``[S]`` bool: states where every atom of the conjunction ``goal_atoms`` holds."""
    atoms = list(goal_atoms)
    if not atoms:
        raise FeatureError("empty goal: expected one or more atoms like agentInRoom(agent0, room1)")
    return _boolean_matrix(space.layout, space.positions, atoms, tables).all(axis=1)


def atoms_hold(state, atoms: Sequence[Atom | str], tables: PFTables) -> np.ndarray:
    """``[F]`` bool: which of ``atoms`` hold in one ``model.world.State`` (as in feature_matrix)."""
    return _boolean_matrix(state.layout, state.positions[None], list(atoms), tables)[0]


def atoms_hold_along(layout: Layout, positions: np.ndarray, atoms: Sequence[Atom | str],
                     tables: PFTables) -> np.ndarray:
    """``[N, F]`` bool: which of ``atoms`` hold at each of ``positions`` ``[N, ...]`` (the states of a
    demonstration, say) in ``layout``."""
    return _boolean_matrix(layout, positions, list(atoms), tables)
