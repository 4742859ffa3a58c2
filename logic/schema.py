"""The domain's schema, read from its ASP files in one solve: classes, palette, PFs, lifted tasks.

What a domain *is* lives in ASP: ``class/1``, ``class_rank/2`` and ``movable/1``
(``domain.lp``), ``value/3`` (a palette file), ``pf/3`` (``pfs.lp`` and a
library's own PF rules) and ``task/1``, ``var/3``, ``goal/3`` (a task library).
:class:`Domain` gathers them for a reader (a notebook, ``groundlang domain``)
and for the code that needs the lists Python must never write down: every PF
of a class, the classes in order, which of them move.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import clingo

from .classes import ranked
from .palette_files import read_palette
from .program import AspError, Program, Source
from .library_checks import PFRoles
from .tasks import LiftedTask, TaskLibrary, pf_name

__all__ = ["PFDeclaration", "Domain", "domain_schema"]

_SHOW = Source("groundlang.logic.schema", "#show pf/3. #show class/1. #show class_rank/2. #show movable/1.")


@dataclass(frozen=True)
class PFDeclaration:
    """One PF as ``pf/3`` declares it: ``roomIsGreen`` of class ``colour`` over ``(room,)``, written
    ``roomIs(green)`` in ASP."""

    name: str
    pf_class: str
    signature: tuple[str, ...]
    term: str

    def __str__(self) -> str:
        return f"{self.name}({', '.join(self.signature)}) [{self.pf_class}]"


@dataclass(frozen=True)
class Domain:
    """The schema of a domain with one palette (colour and shape families are declared per value)."""

    classes: tuple[str, ...]  # by class_rank/2: the order of a lifted task's variables
    movable: frozenset[str]  # classes whose objects move: their positions make up a state
    palette: str
    values: dict[str, tuple[str, ...]]  # attribute -> values by the index corpus files use
    pfs: dict[str, PFDeclaration]  # in the order the files declare them
    tasks: tuple[LiftedTask, ...]
    roles: PFRoles = PFRoles()  # the part each PF class plays (goal_class/1, viewpoint_class/1)

    def pfs_of_class(self, pf_class: str) -> list[PFDeclaration]:
        return [d for d in self.pfs.values() if d.pf_class == pf_class]

    @property
    def pf_classes(self) -> list[str]:
        return list(dict.fromkeys(d.pf_class for d in self.pfs.values()))

    def describe(self) -> str:
        """The schema as text, a section per part (what ``groundlang domain`` prints)."""
        lines = [f"classes: {', '.join(c + (' (moves)' if c in self.movable else '') for c in self.classes)}",
                 f"palette {self.palette}:"]
        lines += [f"  {attribute}: {', '.join(values)}" for attribute, values in self.values.items()]
        lines.append(f"PFs ({len(self.pfs)}), by PF class (and its part: goal, viewpoint or property):")
        for pf_class in self.pf_classes:
            lines.append(f"  {pf_class} ({self.roles.part(pf_class)}): " + ", ".join(f"{d.name}({', '.join(d.signature)})"
                                                      for d in self.pfs_of_class(pf_class)))
        lines.append(f"lifted tasks ({len(self.tasks)}):")
        lines += [f"  {t}" for t in self.tasks]
        return "\n".join(lines)


def _palette_facts(values: dict[str, tuple[str, ...]]) -> str:
    # pfs.lp declares its families over palette_colour/1 and palette_shape/1, as an environment's facts do.
    return "".join(f"palette_{attribute}({v}).\n" for attribute, vs in values.items() for v in vs)


@lru_cache(maxsize=16)
def domain_schema(library: TaskLibrary | None = None, palette: str | tuple = "sokoban") -> Domain:
    """The schema of ``library`` (default: the package's tasks and PFs) with ``palette``: a shipped name,
    a palette file, or ``(name, ((attribute, values), ...))`` as read already. Raises AspError (one
    line) for a library or palette that cannot be read."""
    library = library or TaskLibrary.load()
    name, values = read_palette(palette)[:2] if isinstance(palette, str) else (palette[0], dict(palette[1]))
    program = Program(library.program.sources + (_SHOW,), library.allow_scripts, library.program.isolated)
    models = program.solve(_palette_facts(values), models=1, time_limit=library.time_limit)
    rank, classes, movable, found = {}, set(), set(), {}
    for sym in models[0] if models else ():
        args = sym.arguments
        if sym.name == "pf" and len(args) == 3 and args[2].type is clingo.SymbolType.Function:
            declared = PFDeclaration(pf_name(args[1]), str(args[0]), tuple(str(a) for a in args[2].arguments),
                                     str(args[1]))
            if (other := found.setdefault(declared.name, declared)).term != declared.term:
                # a colour named largest makes toyIs(largest) the Williams size PF toyIsLargest: one would hide
                raise AspError(f"{library.program.user_names}: PFs {other.term} and {declared.term} are both called "
                               f"{declared.name} in groundlang; rename one of them (or the palette value)")
        elif sym.name == "class":
            classes.add(str(args[0]))
        elif sym.name == "class_rank":
            rank[str(args[0])] = args[1].number
        elif sym.name == "movable":
            movable.add(str(args[0]))
    # In the order the files declare them; a family (roomIs(C), declared once for all its values) keeps
    # the palette's order of its values.
    functors: dict[str, int] = {}
    for term in program.declared_order("pf", 3, 1):
        functors.setdefault(term.split("(")[0], len(functors))
    index = {v: i for vs in values.values() for i, v in enumerate(vs)}

    def key(d: PFDeclaration) -> tuple:
        functor, _, rest = d.term.partition("(")
        return functors.get(functor, len(functors)), d.pf_class, index.get(rest.rstrip(")"), -1), d.name

    pfs = {d.name: d for d in sorted(found.values(), key=key)}
    return Domain(ranked(classes, rank), frozenset(movable),
                  name, values, pfs, library.tasks, library.pf_roles)
