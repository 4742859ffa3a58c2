"""Lifted tasks, their groundings and binding constraints, enumerated by clingo.

A lifted task (the paper's parametric reward/termination function) is written
in ASP as facts (see ``tasks.lp``)::

    task(toyToRoom). var(toyToRoom, "T", toy). var(toyToRoom, "R", room).
    goal(toyToRoom, toyInRoom, ("T", "R")).

For one environment (facts from ``groundlang.model.geometry``), one clingo
Control grounds ``domain.lp + pfs.lp + library + groundings.lp`` once and one
solve enumerates every grounding as an answer set; the colour/shape PFs true
of the bound objects come with it, and Python only builds their subsets
(the binding constraints) and a deterministic order.

This module knows clingo terms and object names only; it never imports the
world model.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Sequence

import clingo

from .atoms import Atom, format_goal
from .classes import domain_classes
from .library_checks import (Declarations, PFRoles, check_domain_left_alone, check_pfs_declared_once,
                             check_pfs_said_to_hold, check_tasks_declared_once, declare, declare_families,
                             read_pf_roles, read_phrases, restriction_problem)
from .program import DEFAULT_TIME_LIMIT, AspError, Program, Source, package_source
from .terms import natural_key, pf_name, symbol_text, tuple_args
from . import sources as _sources

__all__ = [
    "Variable",
    "LiftedTask",
    "GroundedTask",
    "BindingConstraint",
    "TaskLibrary",
    "PFRoles",
    "natural_key",
    "tuple_args",
    "symbol_text",
    "pf_name",
    "format_lifted_task",
    "DOMAIN_FILES",
    "CLASS_ORDER",
]

# The domain rules every task program needs, in load order.
DOMAIN_FILES = ("domain.lp", "pfs.lp")
# Variables of a lifted task are listed in this class order (class_rank/2 of domain.lp), then by name.
CLASS_ORDER = domain_classes().classes
# groundings.lp derives goal atoms for PFs of these arities.
MAX_GOAL_ARITY = 3


@dataclass(frozen=True)
class Variable:
    """A typed variable of a lifted task, e.g. ``Variable("R", "room")``."""

    name: str
    cls: str


@dataclass(frozen=True)
class LiftedTask:
    """A task over typed variables; ``goal`` is a conjunction of (predicate, variable names)."""

    name: str
    variables: tuple[Variable, ...]
    goal: tuple[tuple[str, tuple[str, ...]], ...]
    # (variable, PF term as ASP writes it, e.g. ("T", "toyIs(star)")): the bound object must satisfy it.
    restrictions: tuple[tuple[str, str], ...] = ()

    def variable(self, name: str) -> Variable:
        for v in self.variables:
            if v.name == name:
                return v
        raise KeyError(f"lifted task {self.name} has no variable {name!r}")

    def __str__(self) -> str:
        params = ", ".join(f"{v.name}: {v.cls}" for v in self.variables)
        body = " ∧ ".join(f"{p}({', '.join(a)})" for p, a in self.goal)
        where = "".join(f", {term} of {v}" for v, term in self.restrictions)
        return f"{self.name}({params}) := {body}" + (f" where{where[1:]}" if where else "")


@dataclass(frozen=True)
class GroundedTask:
    """A lifted task with its variables bound to objects; ``goal`` atoms use object names."""

    task: str
    binding: tuple[tuple[str, str], ...]  # (variable, object name), in the lifted task's variable order
    goal: tuple[Atom, ...]
    # The goal atoms that already hold in the initial state the grounding was enumerated in.
    holding: tuple[Atom, ...] = field(default=(), compare=False)

    @property
    def holds_wholly(self) -> bool:
        """Every goal atom already holds in the initial state: the task asks for nothing there."""
        return len(self.holding) == len(self.goal)

    def object_of(self, variable: str) -> str:
        return dict(self.binding)[variable]

    @property
    def goal_text(self) -> str:
        """The goal as the labels CSV writes it: ``toyInRoom(block0, room2)``."""
        return format_goal(self.goal)

    def __str__(self) -> str:
        return f"{self.task}[{', '.join(f'{v}={o}' for v, o in self.binding)}]: {self.goal_text}"


@dataclass(frozen=True)
class BindingConstraint:
    """A conjunction of colour/shape atoms over bound objects; ``()`` is the empty conjunction."""

    atoms: tuple[Atom, ...] = ()

    def __str__(self) -> str:
        return " ∧ ".join(str(a) for a in self.atoms) if self.atoms else "true"


def format_lifted_task(task: LiftedTask) -> str:
    """ASP facts that define ``task`` (loadable as a library); the inverse of reading one."""
    lines = [f"task({task.name})."]
    lines += [f'var({task.name}, "{v.name}", {v.cls}).' for v in task.variables]
    for pred, args in task.goal:
        vs = ", ".join(f'"{a}"' for a in args)
        lines.append(f"goal({task.name}, {pred}, ({vs}{',' if len(args) == 1 else ''})).")
    lines += [f'restrict({task.name}, "{v}", {term}).' for v, term in task.restrictions]
    return "\n".join(lines) + "\n"


# Shown atoms of a library solved without an environment (a user's own #show cannot hide them).
_LIBRARY_SHOW = Source("groundlang.logic.tasks", "#show task/1. #show var/3. #show goal/3. #show pf/3. #show restrict/3. "
                       "#show goal_class/1. #show viewpoint_class/1. #show phrase/2.")


def _read_lifted_tasks(program: Program, time_limit: float | None):
    """:func:`_lifted_tasks_read`, every error naming the library's files (a PF's name is checked where no file
    is known)."""
    try:
        return _lifted_tasks_read(program, time_limit)
    except AspError as exc:
        if program.user_names in str(exc):
            raise
        raise type(exc)(f"{program.user_names}: {exc}") from None  # its class kept: a timeout says how to raise it


def _lifted_tasks_read(program: Program, time_limit: float | None) -> tuple[
        tuple[LiftedTask, ...], tuple[str, ...], tuple[tuple[str, tuple[str, str]], ...], PFRoles,
        tuple[tuple[str, str], ...]]:
    """Solve the library without an environment: the lifted tasks (task/1, var/3, goal/3,
    restrict/3), the names of the unary PFs of a viewpoint class (spatial), sorted, the PFs of
    two objects but the viewpoint ones with their signatures, sorted (what ``related/4`` of
    ``groundings.lp`` may relate objects by), the part each PF class plays, and the PFs' phrases
    (``phrase/2``, :func:`read_phrases`) as sorted pairs.

    Checked here, each a one-line AspError naming the sources and the task: variables, goal PFs
    (of a goal class) and their argument classes, and that every restrict/3 whose PF the library
    declares (alone or with the palette values restrictions name) names a property PF of one
    argument of its variable's class. A PF no pf/3 declares here may be declared by an environment (a family over
    its facts): :func:`ground_environment` refuses it where none is."""
    models = program.solve("", models=1, time_limit=time_limit)
    if not models:
        raise AspError(f"{program.user_names}: the task library has no answer set (a constraint always fails)")
    by_signature: dict[tuple[str, int], list] = {}
    for sym in models[0]:
        by_signature.setdefault((sym.name, len(sym.arguments)), []).append(sym)
    roles = read_pf_roles(by_signature, program.user_names)
    task_atoms = by_signature.get(("task", 1), [])
    if negated := next((a for a in task_atoms if a.arguments[0].type is clingo.SymbolType.Function
                        and a.arguments[0].negative), None):
        raise AspError(f"{program.user_names}: {negated}: a task's name is negated; name it without '-'")
    names = sorted(symbol_text(a.arguments[0]) for a in task_atoms)
    if twice := next((n for n, m in zip(names, names[1:]) if n == m), None):
        # task(t) and task("t") are two atoms of one name: their var/3 and goal/3 atoms would be mixed.
        raise AspError(f'{program.user_names}: task {twice} is declared twice, as task({twice}) and task("{twice}"); '
                       "write its name one way")
    variables: dict[str, list[Variable]] = {n: [] for n in names}
    goals: dict[str, list[tuple[str, tuple[str, ...]]]] = {n: [] for n in names}
    restrictions: dict[str, list[tuple[str, clingo.Symbol]]] = {n: [] for n in names}
    signatures: dict[str, tuple[str, ...]] = {}
    spatial = set()
    relational = set()
    movable = set()  # PFs of a goal class: the agent's moves change them
    declared: Declarations = {}
    for a in by_signature.get(("pf", 3), []):
        cls_, name, sig = a.arguments
        if sig.type is not clingo.SymbolType.Function or sig.name:
            # clingo reads "(toy)" as the constant toy: groundings.lp would neither describe objects
            # by such a PF nor let restrict/3 name it.
            raise AspError(f"{program.user_names}: {a}: the signature of PF {name} must be a tuple of classes, "
                           f"written ({sig},) for one argument (the comma makes it a tuple)")
        if not 1 <= len(tuple_args(sig)) <= MAX_GOAL_ARITY:  # groundings.lp and tabulate.lp read up to three
            raise AspError(f"{program.user_names}: {a}: PF {name} has {len(tuple_args(sig))} arguments; a PF "
                           f"relates 1 to {MAX_GOAL_ARITY} objects")
        declare(declared, a)
        cls = symbol_text(cls_)
        if cls in roles.goal_classes:
            signatures[pf_name(name)] = tuple(symbol_text(s) for s in tuple_args(sig))
            movable.add(pf_name(name))
        elif cls in roles.viewpoint_classes and len(tuple_args(sig)) == 1:
            spatial.add(pf_name(name))  # groundings.lp describes objects by unary viewpoint PFs only
        if cls not in roles.viewpoint_classes and len(tuple_args(sig)) == 2:
            relational.add((pf_name(name), tuple(symbol_text(s) for s in tuple_args(sig))))
    for a in by_signature.get(("var", 3), []):
        t, v, c = (symbol_text(x) for x in a.arguments)
        if t not in variables:
            raise AspError(f"{program.user_names}: var({t}, \"{v}\", {c}) names no task({t})")
        variables[t].append(Variable(v, c))
    for a in by_signature.get(("goal", 3), []):
        t, p, args = a.arguments
        t = symbol_text(t)
        if t not in goals:
            raise AspError(f"{program.user_names}: goal({t}, ...) names no task({t})")
        goals[t].append((pf_name(p), tuple(symbol_text(x) for x in tuple_args(args))))
    for a in by_signature.get(("restrict", 3), []):
        t, v, p = a.arguments
        t, v = symbol_text(t), symbol_text(v)
        if t not in restrictions:
            raise AspError(f"{program.user_names}: restrict({t}, ...) names no task({t})")
        restrictions[t].append((v, p))
    phrased = by_signature.get(("phrase", 2), [])
    # Members of families (toyIs(wood)) that restrictions and phrases name are declared with their values.
    declare_families(program, [p for rs in restrictions.values() for _, p in rs] + [a.arguments[0] for a in phrased],
                     declared, time_limit)
    phrases = read_phrases(phrased, declared, program.user_names)
    tasks = []
    rank = {c: i for i, c in enumerate(CLASS_ORDER)}
    for n in names:
        vs = sorted(set(variables[n]), key=lambda v: (rank.get(v.cls, len(rank)), v.cls, v.name))
        if len({v.name for v in vs}) != len(vs):
            raise AspError(f"{program.user_names}: task {n} declares a variable with two classes")
        if not goals[n]:
            raise AspError(f"{program.user_names}: task {n} has no goal/3 atom")
        by_name = {v.name: v.cls for v in vs}
        if unknown := sorted({v.cls for v in vs} - set(CLASS_ORDER)):  # a typo ("rooom") matched nothing later
            raise AspError(f"{program.user_names}: task {n}: var/3 names class {unknown[0]!r}, which the domain "
                           f"does not declare (classes: {', '.join(CLASS_ORDER)})")
        for pred, args in goals[n]:
            if not 1 <= len(args) <= MAX_GOAL_ARITY:
                raise AspError(f"{program.user_names}: task {n}: goal {pred} has {len(args)} arguments "
                               f"(1..{MAX_GOAL_ARITY} supported)")
            for arg in args:
                if arg not in by_name:
                    raise AspError(f"{program.user_names}: task {n}: goal {pred} uses variable "
                                   f"{arg!r} that has no var({n}, \"{arg}\", Class)")
            if pred not in movable:
                raise AspError(f"{program.user_names}: task {n}: goal {pred} is not a declared PF of a goal class "
                               f"({', '.join(sorted(roles.goal_classes)) or 'none: goal_class/1'}), so no plan can "
                               f"make it true (their PFs: {', '.join(sorted(movable))})")
            sig = signatures.get(pred)
            if sig is not None and tuple(by_name[a] for a in args) != sig:
                given = ", ".join(f"{a}: {by_name[a]}" for a in args)
                raise AspError(f"{program.user_names}: task {n}: goal {pred}({', '.join(args)}) "
                               f"needs arguments of classes {sig}; the task's var/3 give ({given})")
        in_goal = {a for _, args in goals[n] for a in args}
        for v in vs:
            if v.name not in in_goal:
                # It would multiply the groundings by objects the goal never mentions (and it has no role).
                raise AspError(f"{program.user_names}: task {n}: variable {v.name!r} appears in no goal/3 atom; "
                               "every variable of a task must be an argument of its goal")
        for v, term in restrictions[n]:
            if v not in by_name:
                raise AspError(f"{program.user_names}: task {n}: restrict uses variable {v!r} "
                               f"that has no var({n}, \"{v}\", Class)")
            if term not in declared:
                continue  # only an environment declares it (or nothing does): ground_environment checks
            problem = restriction_problem(term, v, by_name[v], declared[term], roles)
            if problem:
                raise AspError(f"{program.user_names}: task {n}: restrict({n}, \"{v}\", {term}): {problem}")
        kept = {(v, str(term)) for v, term in restrictions[n]}
        tasks.append(LiftedTask(n, tuple(vs), tuple(sorted(set(goals[n]))), tuple(sorted(kept))))
    return tuple(tasks), tuple(sorted(spatial)), tuple(sorted(relational)), roles, tuple(sorted(phrases.items()))


@functools.lru_cache(maxsize=32)
def _lifted_tasks_of(sources: tuple[Source, ...], allow_scripts: bool, isolated: bool, time_limit: float | None):
    """:func:`_read_lifted_tasks`, kept: a process loads one library many times (each model, each fold), a
    user's in a child process each time. What it returns is immutable; errors are raised anew each load."""
    return _read_lifted_tasks(Program(sources, allow_scripts, isolated), time_limit)


class TaskLibrary:
    """Lifted tasks read from ASP: the default ``tasks.lp`` or user ``.lp`` files."""

    def __init__(self, sources: Sequence[Source], *, allow_scripts: bool = False,
                 time_limit: float | None = DEFAULT_TIME_LIMIT) -> None:
        self.sources = tuple(sources)
        self.allow_scripts = allow_scripts
        self.time_limit = time_limit  # seconds per grounding+solve of this library; None: no limit
        domain = tuple(package_source(f) for f in DOMAIN_FILES)
        # User files are solved in a killable child process; the package's own rules in-process.
        isolated = not all(s.name.startswith("groundlang.logic/") for s in self.sources)
        self.program = Program(domain + self.sources + (_LIBRARY_SHOW,), allow_scripts, isolated)
        check_tasks_declared_once(self.program)
        check_pfs_declared_once(self.program)
        check_domain_left_alone(self.program)
        check_pfs_said_to_hold(self.program)
        self.grounding_program = Program(
            domain + self.sources + (package_source("groundings.lp"),), allow_scripts, isolated
        )
        # Where every PF holds per placement of its movable arguments (groundlang.model.pf_tables).
        self.tabulation_program = Program(
            domain + self.sources + (package_source("tabulate.lp"),), allow_scripts, isolated
        )
        # relational_pfs: ((name, (class, class)), ...), the PFs of two objects that may describe one by the other.
        kept = sum(len(s.text) for s in self.program.sources) <= _sources.KEPT_SOURCE_BYTES
        lifted = (_lifted_tasks_of if kept else _lifted_tasks_of.__wrapped__)(self.program.sources, allow_scripts,
                                                                               isolated, time_limit)
        # spatial_pfs: the unary PFs of a viewpoint class; pf_roles: the part each PF class plays (PFRoles);
        # phrases: how a person reads a PF, {name: words} (phrase/2).
        self.tasks, self.spatial_pfs, self.relational_pfs, self.pf_roles, phrases = lifted
        self.phrases = dict(phrases)

    @classmethod
    def load(cls, paths: str | Path | Iterable[str | Path] | None = None, allow_scripts: bool = False,
             time_limit: float | None = DEFAULT_TIME_LIMIT) -> "TaskLibrary":
        """The default library (``paths=None``) or the lifted tasks of the given ``.lp`` files (one path, or
        several; a shipped library by its name, ``"williams2018"``)."""
        if paths is None:
            return cls((package_source("tasks.lp"),), allow_scripts=allow_scripts,
                       time_limit=time_limit)
        return cls(_sources.library_sources(paths, "TaskLibrary.load"), allow_scripts=allow_scripts,
                   time_limit=time_limit)

    @classmethod
    def from_text(cls, text: str, source_name: str = "<text>", allow_scripts: bool = False,
                  time_limit: float | None = DEFAULT_TIME_LIMIT) -> "TaskLibrary":
        return cls((Source(source_name, text),), allow_scripts=allow_scripts, time_limit=time_limit)

    @classmethod
    def from_saved_text(cls, text: str, source_name: str, time_limit: float | None = DEFAULT_TIME_LIMIT
                        ) -> "TaskLibrary":
        """A saved model's library (:meth:`source_text`): the library the package ships when it is one word for
        word, solved in this process as the package's files are; else its text, a user's program, solved in a
        child process (``Program.isolated``: each solve a process, a second or more a layout)."""
        for relative in _sources.library_names().values():
            shipped = package_source(relative)
            if text == _saved_text((shipped,)):
                return cls((shipped,), time_limit=time_limit)
        return cls.from_text(text, source_name, time_limit=time_limit)

    @classmethod
    def from_tasks(cls, tasks: Iterable[LiftedTask], source_name: str = "<tasks>") -> "TaskLibrary":
        """A library of given lifted tasks (e.g. discovered ones), via their ASP text."""
        return cls.from_text("".join(format_lifted_task(t) for t in tasks), source_name)

    def task(self, name: str) -> LiftedTask:
        for t in self.tasks:
            if t.name == name:
                return t
        raise KeyError(f"no lifted task {name!r} in the library ({', '.join(self.names)})")

    @property
    def names(self) -> list[str]:
        return [t.name for t in self.tasks]

    @property
    def goal_relations(self) -> frozenset[str]:
        """The PFs the tasks' goals are made of: the relations a command may ask for."""
        return frozenset(predicate for task in self.tasks for predicate, _ in task.goal)

    def source_text(self) -> str:
        """The library's own ASP text, every source in order with its rules and comments
        (PFs a user defined beside the tasks included): what a saved model keeps."""
        return _saved_text(self.sources)

    def to_lp(self) -> str:
        """The library as ASP facts (normalised; comments and rules of the sources are not kept)."""
        return "".join(format_lifted_task(t) for t in self.tasks)

    def __repr__(self) -> str:
        return f"TaskLibrary({', '.join(self.names)} from {', '.join(s.name for s in self.sources)})"


def _saved_text(sources: Sequence[Source]) -> str:
    """Sources as a saved model keeps them (:meth:`TaskLibrary.source_text`)."""
    return "".join(f"% from {s.name}\n{s.text.rstrip()}\n" for s in sources)
