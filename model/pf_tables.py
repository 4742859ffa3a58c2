"""Every PF's value over the placements of its movable arguments, tabulated by clingo once per layout.

A PF's meaning is written once, as ``holds/2`` rules in ASP (``logic/pfs.lp`` and
any PF file of a task library). To know where ``agentTouchingToy(agent0, block1)``
holds in each of 10^5 states without a solve per state, the layout is grounded
once with every object of a movable class (``movable/1``, ``domain.lp``) copied
onto every walkable cell (``v(block1, X, Y)`` stands on ``(X, Y)``) and
``logic/tabulate.lp`` shows where each PF with a movable argument holds. The
answer becomes, per grounded atom, a boolean grid over the cells of its
movable arguments (``[W, H]`` for one, ``[W, H, W, H]`` for two); a state's
value is one fancy-indexing lookup with its positions.

What a PF with no movable argument says (a colour, a size, "the largest room")
holds in every state as in the layout; its value is read from the same grounding.
"""

from __future__ import annotations

import hashlib
import re
from collections import Counter
from dataclasses import dataclass
from functools import cached_property, lru_cache

import clingo
import numpy as np

from groundlang.logic.atoms import Atom, canonical_predicate, parse_atom
from groundlang.logic.program import DEFAULT_TIME_LIMIT, AspError, Program, package_source
from groundlang.logic.tasks import pf_name

from .geometry import fact, layout_facts, palette_facts, palette_value_facts
from .palette import check_attribute_clash
from .world import Layout

__all__ = ["PFTables", "TabulationError", "pf_tables", "library_pf_tables", "tabulation_program", "MAX_TABLE_CELLS",
           "MAX_TABULATED_COPIES", "check_table_size", "tabulation_refusal"]

# Entries of one atom's table (cells to the power of its movable arguments): two movable arguments
# on a 32x32 grid are 10^6; three are refused here rather than grounded for minutes.
MAX_TABLE_CELLS = 1 << 24
# Walkable cells a layout may have to be tabulated: every movable object is copied onto each, and a
# PF of two movable objects joins two such sets (4096^2 = MAX_TABLE_CELLS). Checked before grounding.
MAX_TABULATED_CELLS = 1 << 12
# Copies of movable objects on cells a layout's tabulation may make (cells x movable objects): the facts
# are written and parsed before grounding, outside its time limit, at about 0.1 ms and 1 kB each; 850
# blocks on 1,521 cells took 159 s and 1.2 GB before the limit could act. The published corpus's layouts
# need at most 800 (16x16, three blocks), the 32x32 fixture of five toys 5,400; a 64x64 room with four
# toys (19,845) already does not ground within the default 10 s, so this bound only stops what a raised
# time limit could not finish in minutes.
MAX_TABULATED_COPIES = 1 << 16


class TabulationError(AspError):
    """A PF that cannot be tabulated (too many movable arguments for the layout) or an atom that is
    not a PF of the layout."""


@lru_cache(maxsize=32)
def tabulation_program(sources: tuple, allow_scripts: bool = False) -> Program:
    """``domain.lp``, ``pfs.lp``, a library's own sources (its PF rules) and ``tabulate.lp``."""
    own = tuple(package_source(f) for f in ("domain.lp", "pfs.lp"))
    isolated = not all(s.name.startswith("groundlang.") for s in sources)
    return Program(own + tuple(sources) + (package_source("tabulate.lp"),), allow_scripts, isolated)


def _copies(layout: Layout) -> str:
    """Facts that put a copy of every movable object on every walkable cell, with its attributes."""
    xs, ys = np.nonzero(layout.walkable)
    moving = set(layout.movable_names)
    lines = []
    for cls, name, facts in layout.objects:
        if name in moving:
            lines.extend(fact(cls, f"v({name},{x},{y})", facts + (("at", (x, y)),))
                         for x, y in zip(xs.tolist(), ys.tolist()))
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class PFTables:
    """Where each grounded PF of a layout holds, per placement of its movable arguments.

    signatures: PF name -> classes of its arguments, for every PF the program declares.
    order:      the position PFs (their value changes with the state), as the program declares them.
    grids:      atom -> (indices of its movable arguments among a state's positions, bool grid
                ``[W, H] * m``); atoms that hold nowhere are absent.
    static:     atoms of the other PFs (but the spatial ones) that hold in the layout.
    objects:    object name -> class.
    """

    layout: Layout
    signatures: dict[str, tuple[str, ...]]
    order: tuple[str, ...]
    grids: dict[Atom, tuple[tuple[int, ...], np.ndarray]]
    static: frozenset[Atom]
    objects: dict[str, str]

    @cached_property
    def tabulated(self) -> frozenset[str]:
        return frozenset(self.order)

    def check(self, atom: Atom) -> Atom:
        """The atom with the paper's predicate name; TabulationError when its predicate, arity or
        objects are not a PF of this layout."""
        predicate = canonical_predicate(atom.predicate)
        classes = self.signatures.get(predicate)
        if classes is None:
            raise TabulationError(f"{atom}: unknown predicate {atom.predicate!r}; the domain declares "
                                  f"{', '.join(sorted(self.signatures)) or 'no PF'}")
        if len(atom.args) != len(classes):
            raise TabulationError(f"{atom} has {len(atom.args)} arguments; {predicate} takes {len(classes)} "
                                  f"({', '.join(classes)})")
        for name, cls in zip(atom.args, classes):
            if name not in self.objects:
                raise TabulationError(f"{atom} names {name}, which does not exist (objects: {', '.join(self.objects)})")
            if self.objects[name] != cls:
                raise TabulationError(f"{atom}: {name} is {_a(self.objects[name])}; expected {_a(cls)} there")
        return Atom(predicate, atom.args)

    def column(self, atom: Atom | str, positions: np.ndarray) -> np.ndarray:
        """``[S]`` bool values of ``atom`` in the states whose positions are ``[S, 1 + k, 2]``."""
        atom = self.check(parse_atom(atom) if isinstance(atom, str) else atom)
        if atom.predicate not in self.tabulated:
            return np.full(len(positions), atom in self.static)
        if atom not in self.grids:
            return np.zeros(len(positions), dtype=bool)
        movers, grid = self.grids[atom]
        index = tuple(positions[:, m, axis] for m in movers for axis in (0, 1))
        return grid[index]

    @cached_property
    def position_atoms(self) -> tuple[Atom, ...]:
        """Every grounded atom of a position PF over this layout's objects, by PF (in the order the
        files declare them) then objects."""
        by_class: dict[str, list[str]] = {}
        for name, cls in self.objects.items():
            by_class.setdefault(cls, []).append(name)
        out = []
        for predicate in self.order:
            tuples = [()]
            for cls in self.signatures[predicate]:
                tuples = [t + (o,) for t in tuples for o in by_class.get(cls, []) if o not in t]
            out.extend(Atom(predicate, t) for t in tuples)
        return tuple(out)

    def position_holding(self, positions: np.ndarray) -> list[Atom]:
        """The position atoms that hold in the state with positions ``[1 + k, 2]``, in ``position_atoms`` order."""
        return [a for a in self.position_atoms if self.column(a, positions[None])[0]]

    def holding(self, positions: np.ndarray) -> list[Atom]:
        """Every atom that holds in the state with positions ``[1 + k, 2]``: the position ones, then the
        static ones (sorted)."""
        return self.position_holding(positions) + sorted(self.static)


def _a(word: str) -> str:
    return f"{'an' if word[:1] in 'aeiou' else 'a'} {word}"


# A shown holds/2 atom as clingo prints it, and the objects in its tuple: copies v(O, X, Y) or names.
# Reading the text is ten times faster than walking clingo's symbols argument by argument.
_HOLDS = re.compile(r"holds\((.+?),\((.*)\)\)")
_ARGUMENT = re.compile(r'v\(([^,()]+),(-?\d+),(-?\d+)\)|("(?:[^"\\]|\\.)*"|[^,()]+)')


def _decode(text: str, names: dict[str, str], where: str) -> tuple[str, tuple[str, ...], tuple[int, ...]]:
    """``(PF name, object names, cells of the copies)`` of one ``holds/2`` atom's text; TabulationError
    starting with ``where`` (the library's files) for one whose arguments are no tuple."""
    m = _HOLDS.fullmatch(text)
    if m is None:
        raise TabulationError(f"{where}: {text}: the objects of holds/2 must be a tuple, written (A,) for one "
                              "object or (A, R) for two, as pf/3 declares them")
    term = m.group(1)
    if term not in names:
        names[term] = pf_name(clingo.parse_term(term))
    objects, cells = [], []
    for copy, x, y, name in _ARGUMENT.findall(m.group(2)):
        if copy:
            objects.append(copy)
            cells += (int(x), int(y))
        else:
            objects.append(name.strip('"'))
    return names[term], tuple(objects), tuple(cells)


@dataclass(frozen=True)
class _Declarations:
    signatures: dict[str, tuple[str, ...]]
    order: tuple[str, ...]  # position PFs, in declared order
    movers: dict[str, int]  # position PF -> how many of its arguments move


@lru_cache(maxsize=64)
def _declarations(program: Program, palette_facts: str, time_limit: float | None) -> _Declarations:
    """What ``program`` declares with a palette's values, before any layout is grounded (one solve per
    program and palette): the PFs' signatures, the position PFs in order, their movable arguments."""
    models = program.solve(palette_facts, models=1, time_limit=time_limit)
    if not models:
        raise TabulationError(f"{program.user_names}: no answer set (a constraint always fails)")
    args: dict[str, dict[int, str]] = {}
    tabulated, movable, never = set(), set(), []
    for sym in models[0]:
        kind = sym.name
        if kind == "pf_arg":
            args.setdefault(pf_name(sym.arguments[0]), {})[sym.arguments[1].number] = str(sym.arguments[2])
        elif kind == "tabulated":
            tabulated.add(pf_name(sym.arguments[0]))
        elif kind == "movable":
            movable.add(str(sym.arguments[0]))
        elif kind == "position_pf_never_moves":
            never.append(pf_name(sym.arguments[0]))
    if never:
        raise TabulationError(f"{program.user_names}: PF {min(never)} is of a goal class (goal_class/1: goals are "
                              f"made of where objects are) but has no argument of a class that moves "
                              f"({', '.join(sorted(movable))}): no state could change it; declare it in another PF class")
    signatures = {n: tuple(a[i] for i in sorted(a)) for n, a in args.items()}
    declared = {name: i for i, name in enumerate(program.declared_order("pf", 3, 1))}
    order = tuple(sorted(tabulated, key=lambda n: (declared.get(n, len(declared)), n)))
    return _Declarations(signatures, order, {n: sum(c in movable for c in signatures[n]) for n in order})


def pf_tables(layout: Layout, program: Program | None = None,
              time_limit: float | None = DEFAULT_TIME_LIMIT) -> PFTables:
    """The PF tables of ``layout`` under ``program`` (default: the package's PFs), grounded within
    ``time_limit`` seconds; cached per (layout, program, limit), however the arguments are written.
    Refused (TabulationError), before the layout is grounded, when a table would be too large."""
    return _tables(layout, program or tabulation_program(()), time_limit)


def check_table_size(layout: Layout) -> None:
    """TabulationError where the layout's PF tables would be too large, said before anything is grounded or
    enumerated in it: a reader of many layouts checks each first (a state space of a layout too large to
    tabulate, enumerated first, had taken gigabytes to be refused afterwards)."""
    cells = int(layout.walkable.sum())
    if cells > MAX_TABULATED_CELLS:
        raise TabulationError(f"this layout has {cells:,} walkable cells; PFs are tabulated for at most "
                              f"{MAX_TABULATED_CELLS:,} (every movable object is copied onto each cell)")
    moving = len(layout.movable_names)
    if cells * moving > MAX_TABULATED_COPIES:
        raise TabulationError(f"this layout has {moving:,} movable objects on {cells:,} walkable cells; PFs are "
                              f"tabulated for at most {MAX_TABULATED_COPIES:,} objects x cells (every movable "
                              "object is copied onto each cell)")


def tabulation_refusal(layout: Layout) -> str | None:
    """Why the layout's PF tables would be too large (:func:`check_table_size`'s message), or None where they
    are not: for a reader of many layouts that sets such a layout aside rather than stop."""
    try:
        check_table_size(layout)
    except TabulationError as exc:
        return str(exc)
    return None


@lru_cache(maxsize=256)
def _tables(layout: Layout, program: Program, time_limit: float | None) -> PFTables:
    check_table_size(layout)
    cells = int(layout.walkable.sum())
    check_attribute_clash(layout.palette, program)
    declared = _declarations(program, palette_facts(layout), time_limit)
    for n, movers in declared.movers.items():
        if cells ** movers > MAX_TABLE_CELLS:
            raise TabulationError(f"{program.user_names}: PF {n} has {movers} movable arguments: its table over "
                                  f"{cells} walkable cells would hold {cells}^{movers} entries per atom "
                                  f"(at most {MAX_TABLE_CELLS})")
    models = program.solve(layout_facts(layout, movable=False) + _copies(layout), models=1, time_limit=time_limit)
    if not models:
        raise TabulationError(f"{program.user_names}: no answer set for the layout (a constraint always fails)")
    movable_index = {name: i for i, name in enumerate(layout.movable_names)}
    objects = {name: cls for cls, name, _ in layout.objects}
    found: dict[Atom, list[tuple[int, ...]]] = {}
    static = set()
    names: dict[str, str] = {}
    checked: set[tuple[str, tuple[str, ...]]] = set()
    copies: Counter[Atom] = Counter()  # a static PF's atoms over movable objects: on how many placements each holds
    for sym in models[0]:
        if sym.name != "holds":
            continue
        name, objects_of, cells_of = _decode(str(sym), names, program.user_names)
        if (name, objects_of) not in checked:  # an atom of movable objects recurs once per placement
            _check_classes(name, objects_of, declared.signatures, objects, program.user_names)
            checked.add((name, objects_of))
        if name in declared.movers:
            found.setdefault(Atom(name, objects_of), []).append(cells_of)
        else:
            static.add(Atom(name, objects_of))
            if cells_of:
                copies[Atom(name, objects_of)] += 1
    _check_unmoved(copies, int(layout.walkable.sum()), movable_index, program.user_names)
    grids = {}
    for atom, placements in found.items():
        movers = tuple(movable_index[o] for o in atom.args if o in movable_index)
        grid = np.zeros(layout.walkable.shape * len(movers), dtype=bool)
        grid[tuple(np.array(placements, dtype=np.intp).T)] = True
        grid.flags.writeable = False
        grids[atom] = (movers, grid)
    return PFTables(layout, declared.signatures, declared.order, grids, frozenset(static), objects)


def _check_unmoved(copies: Counter[Atom], cells: int, movable_index: dict[str, int], where: str) -> None:
    """TabulationError starting with ``where`` where a PF that is not of a goal class (so kept the same in
    every state, a binding constraint) holds of a movable object on some placements and not on others: it
    reads where things stand, as a side seen from the agent does, and would bind objects by where they
    happen to be at the start."""
    for atom, held in copies.items():
        if held != cells ** sum(o in movable_index for o in atom.args):
            raise TabulationError(f"{where}: PF {atom.predicate} is of a property class (neither goal_class/1 nor "
                                  f"viewpoint_class/1), but whether it holds of {', '.join(atom.args)} changes as "
                                  "objects move; declare its class with viewpoint_class/1 if it says where an "
                                  "object lies seen from the agent's start, or goal_class/1 if a goal is made of it")


def _check_classes(name: str, objects_of: tuple[str, ...], signatures: dict[str, tuple[str, ...]],
                   objects: dict[str, str], where: str) -> None:
    """TabulationError starting with ``where`` (the library's files) where a PF's holds/2 rules say it of
    objects its pf/3 does not declare it over: its table would be read with objects of another class (a
    goal over rooms checked against doors) or not at all."""
    classes = signatures.get(name)
    if classes is None:
        return  # no declaration: groundings.lp names those
    if len(classes) != len(objects_of):  # groundings.lp names it only where it holds at the start
        raise TabulationError(f"{where}: holds({name}, {_asp_tuple(objects_of)}) says it of {len(objects_of)} "
                              f"object{'s' * (len(objects_of) != 1)}, but pf/3 declares {name} over "
                              f"{_asp_tuple(classes)}")
    for obj, cls in zip(objects_of, classes):
        if objects.get(obj) != cls:
            what = _a(objects[obj]) if obj in objects else "no object of the layout"
            raise TabulationError(f"{where}: holds({name}, {_asp_tuple(objects_of)}): {obj} is {what}, but "
                                  f"pf/3 declares {name} over {_asp_tuple(classes)}")


def _asp_tuple(items: tuple[str, ...]) -> str:
    return "(" + ", ".join(items) + ("," if len(items) == 1 else "") + ")"


def check_declarations(library, palette) -> None:
    """TabulationError, naming the library's files, for what its PF declarations with ``palette``'s values
    say before any layout: a PF of a goal class that no moving object changes (what tabulating any layout
    would refuse)."""
    _declarations(library.tabulation_program, palette_value_facts(palette), library.time_limit)


def library_pf_tables(layout: Layout, library=None) -> PFTables:
    """The PF tables of ``layout`` under a TaskLibrary's PF rules (None: the package's PFs), within the
    library's time limit."""
    if library is None:
        return pf_tables(layout)
    return pf_tables(layout, library.tabulation_program, library.time_limit)


def program_digest(program: Program) -> str | None:
    """A short digest of a program's sources other than the package's own (a user's PF rules may say
    what a goal means): what cache keys of PF-dependent values include; None when there are none."""
    mine = [s for s in program.sources if not s.name.startswith("groundlang.")]
    if not mine:
        return None
    text = "\n".join(f"{s.name}\n{s.text}" for s in mine)
    return hashlib.sha256(text.encode()).hexdigest()[:16]
