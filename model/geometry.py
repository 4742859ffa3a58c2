"""From a Layout/State to ASP facts, and per-cell tables computed once per layout by clingo.

The static geometry (which cell is inside which room, which cell is a door
cell) is defined by the rules of ``groundlang.logic/domain.lp``; clingo runs
them once per layout and the answers become integer grids that per-state PF
values are computed from with numpy/torch (no clingo call per state).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from groundlang.logic.program import DEFAULT_TIME_LIMIT, AspError, Program, package_source
from groundlang.logic.terms import ASP_CONSTANT

from .world import Layout, State

__all__ = ["CellTables", "cell_tables", "layout_facts", "state_facts", "domain_program"]



def _constant(value: str, what: str) -> str:
    """An attribute value as an ASP constant (palette names are lower camel case)."""
    if not ASP_CONSTANT.match(value):
        raise AspError(f"{what} {value!r} cannot be an ASP constant (expected lowerCamelCase)")
    return value


def fact(cls: str, name: str, facts) -> str:
    text = f"{cls}({name})."
    for predicate, args in facts:
        values = ",".join(str(a) if isinstance(a, int) else _constant(a, predicate) for a in args)
        text += f" {predicate}({name},{values})."
    return text


def palette_facts(layout: Layout) -> str:
    """``palette_A/1`` for each attribute ``A`` of the layout's palette: ``palette_colour/1``,
    ``palette_shape/1`` and one per added attribute (pfs.lp declares its families over them)."""
    return palette_value_facts(layout.palette)


def palette_value_facts(palette) -> str:
    """:func:`palette_facts` of a palette, without a layout."""
    return "\n".join(f"palette_{attribute}({_constant(v, attribute)})."
                     for attribute, values in palette.all_values for v in values)


def layout_facts(layout: Layout, movable: bool = True) -> str:
    """Facts for the static part: palette, every object's class and attributes (see domain.lp);
    ``movable=False`` leaves out the objects that move (the agent and the toys)."""
    lines = [palette_facts(layout)]
    moving = set(layout.movable_names)
    lines += [fact(cls, name, facts) for cls, name, facts in layout.objects
              if name != "agent0" and (movable or name not in moving)]
    return "\n".join(lines) + "\n"


def state_facts(state: State) -> str:
    """Facts for a whole state: the layout's facts plus the agent and every position (at/3)."""
    lines = [layout_facts(state.layout), "agent(agent0).",
             f"at(agent0,{state.agent.x},{state.agent.y})."]
    lines += [f"at({n},{t.x},{t.y})." for n, t in zip(state.layout.toy_names, state.toys)]
    return "\n".join(lines) + "\n"


@lru_cache(maxsize=1)
def domain_program() -> Program:
    """``domain.lp`` alone, parsed once per process."""
    return Program((package_source("domain.lp"),))


@dataclass(frozen=True)
class CellTables:
    """Per-cell lookup grids ``[W, H]`` int16 (read-only) for one layout.

    room_of: index of the room whose interior holds the cell, -1 if none.
    door_of: index of the door whose rectangle holds the cell (walkable door cells only;
             the lowest index where door rectangles overlap), -1 if none.
    """

    room_of: np.ndarray
    door_of: np.ndarray


def _index(name: str, prefix: str) -> int:
    return int(name[len(prefix):])


@lru_cache(maxsize=256)
def cell_tables(layout: Layout) -> CellTables:
    """The ``inside/3`` and ``door_cell/3`` atoms of domain.lp as grids; cached per layout."""
    ctl = domain_program().control(layout_facts(layout), time_limit=DEFAULT_TIME_LIMIT)
    w, h = layout.width, layout.height
    room_of = np.full((w, h), -1, dtype=np.int16)
    door_of = np.full((w, h), -1, dtype=np.int16)
    for grid, signature, prefix in ((room_of, "inside", "room"), (door_of, "door_cell", "door")):
        cells = [
            (_index(a.symbol.arguments[0].name, prefix), a.symbol.arguments[1].number,
             a.symbol.arguments[2].number)
            for a in ctl.symbolic_atoms.by_signature(signature, 3)
        ]
        # Highest index first so that the lowest index wins where rectangles overlap.
        for i, x, y in sorted(cells, reverse=True):
            if 0 <= x < w and 0 <= y < h:
                grid[x, y] = i
    room_of.flags.writeable = False
    door_of.flags.writeable = False
    return CellTables(room_of, door_of)
