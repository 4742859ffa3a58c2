"""Groundings of lifted tasks in one environment, with their binding constraints and what words may
say of every object: ``groundings.lp`` solved once per environment (one Control, one grounding, one
solve enumerating every answer set)."""

from __future__ import annotations

import time
from collections.abc import Iterable, Iterator, Sequence
from itertools import combinations, islice
from math import comb

import clingo

from .atoms import Atom
from .program import AspError, AspTimeout
from .tasks import CLASS_ORDER, BindingConstraint, GroundedTask, TaskLibrary
from .terms import natural_key, pf_name, symbol_text, tuple_args

__all__ = ["BindingConstraints", "MAX_ENUMERATED_ATOMS", "binding_constraints", "enumerate_groundings", "ground_environment", "Descriptions", "PFTerms", "Relations"]


class BindingConstraints(Sequence):
    """Every conjunction of a grounding's constraint ``atoms`` (all 2^k subsets), largest first, the empty
    one last, made as they are read: a grounding whose objects have many property PFs (a library of
    twenty colours of its own) costs its largest conjunction, not 2^20 of them, until a language model
    that enumerates them asks (:data:`MAX_ENUMERATED_ATOMS` bounds that). ``count`` is how many there are;
    ``len()`` says so too where Python can hold it (up to 62 atoms)."""

    __slots__ = ("_atoms",)

    def __init__(self, atoms: Iterable[Atom]):
        self._atoms = tuple(atoms)

    @property
    def atoms(self) -> tuple[Atom, ...]:
        return self._atoms

    @property
    def count(self) -> int:
        return 2 ** len(self._atoms)

    def __len__(self) -> int:
        return self.count

    def __bool__(self) -> bool:
        return True  # the empty conjunction is always one of them

    def __iter__(self) -> Iterator[BindingConstraint]:
        for k in range(len(self._atoms), -1, -1):
            for c in combinations(self._atoms, k):
                yield BindingConstraint(c)

    def __getitem__(self, index):
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(self.count))]
        if isinstance(index, bool) or not isinstance(index, int):
            raise TypeError(f"binding constraint indices are whole numbers, not {type(index).__name__}")
        n = self.count
        if not -n <= index < n:
            raise IndexError("binding constraint index out of range")
        index %= n
        for k in range(len(self._atoms), -1, -1):  # the conjunctions of k atoms come as one block
            block = comb(len(self._atoms), k)
            if index < block:
                return BindingConstraint(next(islice(combinations(self._atoms, k), index, None)))
            index -= block
        raise AssertionError("unreachable")

    @property
    def largest(self) -> BindingConstraint:
        return BindingConstraint(self._atoms)

    def __eq__(self, other) -> bool:
        if isinstance(other, BindingConstraints):
            return other._atoms == self._atoms
        if isinstance(other, list):  # as the list of them was (a list has no hash to disagree with)
            return len(other) == self.count and list(self) == other
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self._atoms)

    def __repr__(self) -> str:
        return f"BindingConstraints({len(self._atoms)} atoms, {self.count} conjunctions)"


# A language model that offers every conjunction as an interpretation of its own (bag of words, the parse
# model with ``largest_constraint`` off) offers 2^k per grounding: beyond this many atoms it is refused with
# one line rather than growing without bound.
MAX_ENUMERATED_ATOMS = 12


def binding_constraints(atoms: Iterable[Atom]) -> BindingConstraints:
    """Every conjunction of ``atoms`` (all subsets), largest first, the empty one last (made as read)."""
    return BindingConstraints(atoms)


# Object -> PF class -> names of the unary PFs of that class true of the object, e.g.
# {"room0": {"colour": ("roomIsGreen",)}, "door1": {"spatial": ("doorWestOfAgent",)}}.
Descriptions = dict[str, dict[str, tuple[str, ...]]]
# A described PF's name -> its term as the library writes it (restrict/3 takes the term):
# {"roomIsGreen": "roomIs(green)", "doorWestOfAgent": "doorWestOfAgent"}.
PFTerms = dict[str, str]
# Object -> the PFs of two objects that hold of it at the start, as (PF name, its argument index, the
# other object), e.g. {"block0": (("toyInRoom", 0, "room2"),), "room2": (("toyInRoom", 1, "block0"),)};
# neither object is the addressee (related/4 of groundings.lp).
Relations = dict[str, tuple[tuple[str, int, str], ...]]


def enumerate_groundings(
    library: TaskLibrary, facts: str, *, time_limit: float | None = None
) -> list[tuple[GroundedTask, BindingConstraints]]:
    """Every permissible grounding not true initially, with its binding constraints (lazily): the first part
    of :func:`ground_environment`."""
    return ground_environment(library, facts, time_limit=time_limit)[0]


def ground_environment(
    library: TaskLibrary, facts: str, *, time_limit: float | None = None, environment: str | None = None,
    wholly_true: bool = False,
) -> tuple[list[tuple[GroundedTask, BindingConstraints]], Descriptions, PFTerms, Relations]:
    """Every permissible grounding not true initially (with ``wholly_true``, those too), with its
    binding constraints; the
    unary PFs of every class but position true of each object, by class
    (``{"door1": {"spatial": ("doorWestOfAgent",)}}``; objects none holds of are left out); and
    the term of each of those PFs as a library writes it (``{"roomIsGreen": "roomIs(green)"}``); and
    the PFs of two objects that hold of each object at the start (:data:`Relations`).

    ``facts``: one environment in the vocabulary of ``domain.lp`` (object names as constants).
    ``time_limit``: seconds, default the library's. One Control, one grounding, one solve
    enumerating all answer sets; the descriptions are the same in every answer set, one of
    which chooses no task (so an environment where nothing can be asked is still described).
    Order: library order of tasks, then bound objects in variable order (``room2`` before ``room10``).

    A ``restrict/3`` that names no property PF (colour, shape, ...) of one object of its variable's class that
    pf/3 declares with these facts (a palette value they lack, a typo) would bind nothing; it raises
    AspError naming the library's files, the task, ``environment`` (e.g. "palette sokoban") and
    what it does declare. (So declare a family of PFs for every palette value, as pfs.lp does, not
    only for the values the objects of a state have.)
    """
    tasks = {t.name: t for t in library.tasks}
    order = {t.name: i for i, t in enumerate(library.tasks)}
    found = []
    described: dict[str, dict[str, set[str]]] = {}
    terms: PFTerms = {}
    related: dict[str, set[tuple[str, int, str]]] = {}
    # The same atoms recur in many answer sets; decoding clingo symbols is the costly part.
    decoded: dict[clingo.Symbol, tuple[str, object]] = {}

    def decode(sym: clingo.Symbol) -> tuple[str, object]:
        kind, args = sym.name, sym.arguments
        if kind == "chosen" and len(args) == 1:
            return kind, symbol_text(args[0])
        if kind == "bind" and len(args) == 2:
            return kind, (symbol_text(args[0]), symbol_text(args[1]))
        if kind == "described" and len(args) == 3:
            return kind, (symbol_text(args[0]), pf_name(args[1]), symbol_text(args[2]), str(args[1]))
        if kind == "related" and len(args) == 4:
            return kind, (symbol_text(args[2]), (pf_name(args[0]), args[1].number, symbol_text(args[3])))
        if kind == "unusable_restriction" and len(args) == 3:
            return kind, (symbol_text(args[0]), symbol_text(args[1]), args[2])
        if kind == "restrictable" and len(args) == 2:
            return kind, (symbol_text(args[0]), args[1])
        if kind in ("pf_of_no_class", "attribute_pf_not_unary") and len(args) == 2:
            return kind, (str(args[0]), str(args[1]))
        if kind in ("pf_of_two_arities", "holds_of_other_arity") and len(args) == 3:
            return kind, (str(args[0]), args[1].number, args[2].number)
        if kind in ("goal_atom", "constraint_atom", "goal_atom_holds") and len(args) == 2:
            return kind, Atom(pf_name(args[0]), tuple(symbol_text(a) for a in tuple_args(args[1])))
        return "other", None  # atoms a user library shows for its own purposes

    limit = library.time_limit if time_limit is None else time_limit
    unusable: set[tuple[str, str, clingo.Symbol]] = set()
    restrictable: dict[str, set[clingo.Symbol]] = {}
    started = time.monotonic()
    models = library.grounding_program.solve(facts, models=0, time_limit=limit)
    for count, model in enumerate(models):
        # Reading the answer sets counts against the time limit too: a layout with a thousand blocks has
        # answer sets enough to take minutes in Python after clingo's own part has ended in time.
        if limit is not None and count % 64 == 0 and time.monotonic() - started > limit:
            raise AspTimeout(f"the groundings of {environment or 'the environment'} were not read within {limit:g} s "
                             f"({count} of {len(models)} read): a layout with this many objects has too many "
                             "tasks to list (raise the time limit if it is just large)")
        chosen, bind, goal, extra, holding = None, {}, [], [], []
        for sym in model:
            if sym not in decoded:
                decoded[sym] = decode(sym)
            kind, value = decoded[sym]
            if kind == "chosen":
                chosen = value
            elif kind == "bind":
                bind[value[0]] = value[1]
            elif kind == "goal_atom":
                goal.append(value)
            elif kind == "goal_atom_holds":
                holding.append(value)
            elif kind == "constraint_atom":
                extra.append(value)
            elif kind == "described":
                cls, name, obj, term = value
                described.setdefault(obj, {}).setdefault(cls, set()).add(name)
                if terms.setdefault(name, term) != term:
                    raise AspError(f"{library.program.user_names}: PFs {terms[name]} and {term} are both called "
                                   f"{name} in groundlang; rename one of them")
            elif kind == "related":
                related.setdefault(value[0], set()).add(value[1])
            elif kind == "unusable_restriction":
                unusable.add(value)
            elif kind == "restrictable":
                restrictable.setdefault(value[0], set()).add(value[1])
            elif kind in ("pf_of_no_class", "attribute_pf_not_unary"):
                where = f" ({environment})" if environment else ""
                first, second = value
                problem = (f"PF {first} is declared over class {second}, which no object has (classes: "
                           f"{', '.join(sorted(CLASS_ORDER))})" if kind == "pf_of_no_class" else
                           f"{first} PF {second} takes more than one argument; the other {first} PFs, as "
                           f"property PFs do, describe one object each, e.g. pf({first}, {second}, (toy,))")
                raise AspError(f"{library.program.user_names}{where}: {problem}")
            elif kind in ("pf_of_two_arities", "holds_of_other_arity"):
                name, first, second = value
                problem = (f"PF {name} is declared with {first} and with {second} arguments"
                           if kind == "pf_of_two_arities" else
                           f"holds({name}, ...) has {first} argument{'s' if first > 1 else ''} where pf/3 declares "
                           f"{name} with {second}; its rules and its declaration must agree")
                raise AspError(f"{library.program.user_names}: {problem}")
        if chosen is None:
            continue  # the answer set of no task: descriptions and diagnostics only
        lifted = tasks[chosen]
        binding = tuple((v.name, bind[v.name]) for v in lifted.variables)
        # Goal atoms sorted (one text per goal, whatever the binding), constraint atoms in variable order.
        goal.sort(key=lambda a: (a.predicate, tuple(natural_key(o) for o in a.args)))
        position = {o: i for i, (_, o) in enumerate(binding)}
        extra.sort(key=lambda a: (min(position[o] for o in a.args), a.predicate, a.args))
        grounded = GroundedTask(chosen, binding, tuple(goal), tuple(a for a in goal if a in holding))
        key = (order[chosen], tuple(natural_key(o) for _, o in binding))
        found.append((key, grounded, binding_constraints(extra)))
    if unusable:
        first = min(unusable, key=lambda u: (u[0], u[1], str(u[2])))
        more = len(unusable) - 1
        raise AspError(_unusable_restriction_message(library, first, restrictable, environment)
                       + (f" ({more} more restrict/3 fact{'s' if more > 1 else ''} cannot be honoured here)" if more else ""))
    found.sort(key=lambda item: item[0])
    descriptions = {
        o: {cls: tuple(sorted(names)) for cls, names in sorted(described[o].items())}
        for o in sorted(described, key=natural_key)
    }
    relations = {o: tuple(sorted(related[o], key=lambda r: (r[0], r[1], natural_key(r[2]))))
                 for o in sorted(related, key=natural_key)}
    return ([(g, c) for _, g, c in found if wholly_true or not g.holds_wholly], descriptions,
            dict(sorted(terms.items())), relations)


def _unusable_restriction_message(library: TaskLibrary, restriction: tuple[str, str, clingo.Symbol],
                                  restrictable: dict[str, set[clingo.Symbol]], environment: str) -> str:
    """One line: which restrict/3 ``environment`` cannot honour, and the PFs it could name instead."""
    task, var, term = restriction
    cls = next(v.cls for v in library.task(task).variables if v.name == var)
    offered = sorted(restrictable.get(cls, ()), key=str)
    same_name = [p for p in offered if pf_name(p) == pf_name(term)] if term.type is clingo.SymbolType.Function else []
    if same_name:  # groundlang's name for a family term, e.g. toyIsStar for toyIs(star)
        hint = f"; write {same_name[0]}, the term pf/3 declares"
    elif offered:
        hint = f"; it declares these of a {cls}: {', '.join(map(str, offered))}"
    else:
        hint = f"; it declares none of a {cls}"
    where = f"the environment ({environment})" if environment else "the environment"
    return (f'{library.grounding_program.user_names}: task {task}: restrict({task}, "{var}", {term}): '
            f"{where} declares no property PF (colour, shape, ...) {term} of a {cls}, so the task would bind nothing{hint}")
