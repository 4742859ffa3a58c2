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
from dataclasses import dataclass
from functools import lru_cache

import clingo
import numpy as np

from groundlang.logic.atoms import Atom, canonical_predicate, parse_atom
from groundlang.logic.program import DEFAULT_TIME_LIMIT, AspError, Program, package_source
from groundlang.logic.tasks import pf_name

from .geometry import fact, layout_facts
from .world import Layout

__all__ = ["PFTables", "TabulationError", "pf_tables", "tabulation_program", "MAX_TABLE_CELLS"]

# Entries of one atom's table (cells to the power of its movable arguments): two movable arguments
# on a 32x32 grid are 10^6; three are refused here rather than grounded for minutes.
MAX_TABLE_CELLS = 1 << 24
# Walkable cells a layout may have to be tabulated: every movable object is copied onto each, and a
# PF of two movable objects joins two such sets (4096^2 = MAX_TABLE_CELLS). Checked before grounding.
MAX_TABULATED_CELLS = 1 << 12


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
    tabulated:  names of the PFs with a movable argument (their value changes with the state).
    grids:      atom -> (indices of its movable arguments among a state's positions, bool grid
                ``[W, H] * m``); atoms that hold nowhere are absent.
    static:     atoms of PFs with no movable argument that hold in the layout.
    objects:    object name -> class.
    """

    layout: Layout
    signatures: dict[str, tuple[str, ...]]
    tabulated: frozenset[str]
    grids: dict[Atom, tuple[tuple[int, ...], np.ndarray]]
    static: frozenset[Atom]
    objects: dict[str, str]
    order: tuple[str, ...]  # the tabulated PFs in the order the program declares them

    def check(self, atom: Atom) -> Atom:
        """The atom with the paper's predicate name; TabulationError when its predicate, arity or
        objects are not a PF of this layout."""
        predicate = canonical_predicate(atom.predicate)
        classes = self.signatures.get(predicate)
        if classes is None:
            raise TabulationError(
                f"{atom}: unknown predicate {atom.predicate!r} in {atom}; the domain declares "
                f"{', '.join(sorted(self.signatures)) or 'no PF'}")
        if len(atom.args) != len(classes):
            raise TabulationError(f"{atom} has {len(atom.args)} arguments; expected {len(classes)}: {predicate} takes "
                                  f"{len(classes)} argument{'s' if len(classes) != 1 else ''} ({', '.join(classes)})")
        for i, (name, cls) in enumerate(zip(atom.args, classes)):
            if name not in self.objects:
                raise TabulationError(f"{atom} names {name}, which does not exist (objects: "
                                      f"{', '.join(self.objects)}): argument {i + 1} {name!r} is not {_a(cls)} "
                                      "of this layout")
            if self.objects[name] != cls:
                raise TabulationError(f"{atom}: {name} is {_a(self.objects[name])}; expected {_a(cls)} there: "
                                      f"argument {i + 1} {name!r} is not {_a(cls)}")
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

    def atoms(self) -> list[Atom]:
        """Every grounded atom of a tabulated PF over this layout's objects, by PF (in the order the
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
        return out


    def holding(self, positions: np.ndarray) -> list[Atom]:
        """Every atom that holds in the state with positions ``[1 + k, 2]``: the tabulated ones (by PF in
        declared order, then objects), then the static ones (sorted)."""
        atoms = self.atoms()
        values = [self.column(a, positions[None])[0] for a in atoms]
        return [a for a, v in zip(atoms, values) if v] + sorted(self.static)


def _a(word: str) -> str:
    return f"{'an' if word[:1] in 'aeiou' else 'a'} {word}"


# A shown holds/2 atom as clingo prints it, and the objects in its tuple: copies v(O, X, Y) or names.
# Reading the text is ten times faster than walking clingo's symbols argument by argument.
_HOLDS = re.compile(r"holds\((.+?),\((.*)\)\)")
_ARGUMENT = re.compile(r'v\(([^,()]+),(-?\d+),(-?\d+)\)|("(?:[^"\\]|\\.)*"|[^,()]+)')


def _decode(text: str, names: dict[str, str]) -> tuple[str, tuple[str, ...], tuple[int, ...]]:
    """``(PF name, object names, cells of the copies)`` of one ``holds/2`` atom's text."""
    m = _HOLDS.fullmatch(text)
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


@lru_cache(maxsize=256)
def pf_tables(layout: Layout, program: Program | None = None,
              time_limit: float | None = DEFAULT_TIME_LIMIT) -> PFTables:
    """The PF tables of ``layout`` under ``program`` (default: the package's PFs); cached per pair."""
    program = program or tabulation_program(())
    cells = int(layout.walkable.sum())
    if cells > MAX_TABULATED_CELLS:
        raise TabulationError(f"this layout has {cells:,} walkable cells; PFs are tabulated for at most "
                              f"{MAX_TABULATED_CELLS:,} (every movable object is copied onto each cell)")
    models = program.solve(layout_facts(layout, movable=False) + _copies(layout), models=1, time_limit=time_limit)
    if not models:
        raise TabulationError(f"{program.user_names}: no answer set for the layout (a constraint always fails)")
    args: dict[str, dict[int, str]] = {}
    tabulated = set()
    holds = []
    movable_classes = set()
    never = []
    for sym in models[0]:
        kind = sym.name  # one call into clingo per symbol: the atoms are thousands
        if kind == "holds":
            holds.append(sym)
        elif kind == "pf_arg":
            args.setdefault(pf_name(sym.arguments[0]), {})[sym.arguments[1].number] = str(sym.arguments[2])
        elif kind == "tabulated":
            tabulated.add(pf_name(sym.arguments[0]))
        elif kind == "movable":
            movable_classes.add(str(sym.arguments[0]))
        elif kind == "position_pf_never_moves":
            never.append(pf_name(sym.arguments[0]))
    if never:
        raise TabulationError(f"{program.user_names}: position PF {min(never)} has no argument of a class that "
                              f"moves ({', '.join(sorted(movable_classes))}): no state could change it; "
                              "declare it in another PF class")
    signatures = {n: tuple(a[i] for i in sorted(a)) for n, a in args.items()}
    objects = {name: cls for cls, name, _ in layout.objects}
    movable_index = {name: i for i, name in enumerate(layout.movable_names)}
    for n in tabulated:
        movers = sum(cls in movable_classes for cls in signatures[n])
        if cells ** movers > MAX_TABLE_CELLS:
            raise TabulationError(f"{program.user_names}: PF {n} has {movers} movable arguments: its table over "
                                  f"{cells} walkable cells would hold {cells}^{movers} entries per atom "
                                  f"(at most {MAX_TABLE_CELLS})")
    found: dict[Atom, list[tuple[int, ...]]] = {}
    static = set()
    names: dict[str, str] = {}
    for sym in holds:
        name, objects_of, cells_of = _decode(str(sym), names)
        atom = Atom(name, objects_of)
        if name not in tabulated:
            static.add(atom)
            continue
        found.setdefault(atom, []).append(cells_of)
    shape = layout.walkable.shape
    grids = {}
    for atom, placements in found.items():
        movers = tuple(movable_index[o] for o in atom.args if o in movable_index)
        grid = np.zeros(shape * len(movers), dtype=bool)
        grid[tuple(np.array(placements, dtype=np.intp).T)] = True
        grid.flags.writeable = False
        grids[atom] = (movers, grid)
    declared = {name: i for i, name in enumerate(program.declared_order("pf", 3, 1))}
    order = tuple(sorted(tabulated, key=lambda n: (declared.get(n, len(declared)), n)))
    return PFTables(layout, signatures, frozenset(tabulated), grids, frozenset(static), objects, order)


def program_digest(program: Program) -> str | None:
    """A short digest of a program's sources other than the package's own (a user's PF rules may say
    what a goal means): what cache keys of PF-dependent values include; None when there are none."""
    mine = [s for s in program.sources if not s.name.startswith("groundlang.")]
    if not mine:
        return None
    text = "\n".join(f"{s.name}\n{s.text}" for s in mine)
    return hashlib.sha256(text.encode()).hexdigest()[:16]
