"""Candidate tasks of an environment: groundings and binding constraints for a State.

The generative model's task part: L uniform over permissible lifted tasks,
T | L uniform over groundings not already true in the initial state, C | T
uniform over conjunctions of colour/shape PFs true of T's bound objects. This
module produces the candidates (one clingo Control per environment, cached)
and narrows them by predicates a logical form already knows.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from types import MappingProxyType
from typing import Collection, Mapping, Sequence

from groundlang.logic.atoms import Atom
from groundlang.logic.classes import domain_classes
from groundlang.logic.groundings import MAX_ENUMERATED_ATOMS, BindingConstraints, ground_environment
from groundlang.logic.tasks import BindingConstraint, GroundedTask, TaskLibrary

from .geometry import state_facts
from .palette import check_attribute_clash
from .world import State

__all__ = [
    "Candidate", "candidate_tasks", "check_position_pfs", "object_descriptions", "object_relations", "attribute_pfs",
    "spatial_descriptions", "viewpoint_pfs", "kind_pfs", "narrow_by_known", "NarrowedCandidate",
]

Candidate = tuple[GroundedTask, BindingConstraints]


# Training walks a corpus's start states twice (interpretations, then the pairs' evidence), in the same
# order: with fewer slots than distinct states (the Williams corpus has 70), least-recently-used eviction
# dropped each state just before it was needed again. An entry is a layout's candidates, tens of kB.
@lru_cache(maxsize=256)
def _environment(state: State, library: TaskLibrary) -> tuple:
    check_attribute_clash(state.layout.palette, library.grounding_program)
    palette = state.layout.palette.name
    found, described, terms, related = ground_environment(library, state_facts(state),
                                                          environment=f"palette {palette}", wholly_true=True)
    frozen = MappingProxyType({obj: MappingProxyType(by_class) for obj, by_class in described.items()})
    return tuple(found), frozen, MappingProxyType(terms), MappingProxyType(related)


def candidate_tasks(state: State, library: TaskLibrary, wholly_true: bool = False) -> list[Candidate]:
    """Every permissible grounding not true in ``state`` (with ``wholly_true``, those too), each with all
    its binding constraints (a :class:`BindingConstraints`, made as read).

    Order: tasks in library order, then bound objects in variable order; constraints
    largest first, the empty conjunction last. One clingo Control per (state, library),
    cached (the library is keyed by identity, the state by value). Raises AspError.
    """
    return [(g, c) for g, c in _environment(state, library)[0] if wholly_true or not g.holds_wholly]


def check_position_pfs(state: State, library: TaskLibrary, tables) -> None:
    """TabulationError naming the first goal PF whose table (``tables``, tabulated over placements of its own
    arguments, every other object standing everywhere at once) and the state's own grounding disagree at
    ``state``'s positions. A position PF that reads where another object is (``at(T2, ...)`` of a toy not
    among its arguments) does: its table then holds wherever that object could be, so planning and the
    groundings would each say something else, silently."""
    from groundlang.model.pf_tables import TabulationError

    # Each goal atom once (conjunctions share them), with whether the grounding found it holding at the start.
    held = {tables.check(a): a in g.holding for g, _ in candidate_tasks(state, library, wholly_true=True)
            for a in g.goal}
    for atom, holds in held.items():
        if atom.predicate in tables.tabulated and bool(tables.column(atom, state.positions[None])[0]) != holds:
            says = "holds" if holds else "does not hold"
            raise TabulationError(
                f"{atom} {says} in the state, but its table over the positions of its arguments says otherwise: "
                f"a position PF may read the positions (at/3) of its own arguments only; does {atom.predicate} "
                "read where another object is?")


def check_library_at(state: State, library: TaskLibrary, where: str) -> None:
    """``library``'s PF rules checked in ``state``'s layout as training meets them, for a command that reads a
    library without training (check, tasks): its PF tables (a holds/2 of another arity, or of objects of another
    class), its groundings (a PF of a class no object has), each goal PF against the state's own grounding.
    The error names the library's files and, after them, ``where`` (the file of the state). A layout too large
    to tabulate is passed over, as readers of many layouts set it aside."""
    from groundlang.logic.program import AspError
    from groundlang.model.pf_tables import TabulationError, library_pf_tables, tabulation_refusal

    if tabulation_refusal(state.layout) is not None:
        return
    try:
        tables = library_pf_tables(state.layout, library)
    except AspError as exc:  # TabulationError too: the message names the library's files
        raise type(exc)(f"{exc} (in the layout of {where})") from None
    try:
        check_position_pfs(state, library, tables)
    except TabulationError as exc:
        raise TabulationError(f"{library.program.user_names}: {exc} (in the layout of {where})") from None
    except AspError as exc:  # the groundings' diagnostics, which name the library
        raise type(exc)(f"{exc} (in the layout of {where})") from None


def object_descriptions(state: State, library: TaskLibrary) -> Mapping[str, Mapping[str, tuple[str, ...]]]:
    """Object -> PF class -> the unary PFs of that class (every class but a goal class) true of it in
    ``state``: colours and shapes, the spatial PFs where the agent stands, and any class a user's
    library declares (``{"room0": {"colour": ("roomIsGreen",)}}``).

    From the same cached solve as :func:`candidate_tasks` (hence read-only mappings);
    objects no such PF holds of are absent. Raises AspError.
    """
    return _environment(state, library)[1]


def object_relations(state: State, library: TaskLibrary) -> Mapping[str, tuple[tuple[str, int, str], ...]]:
    """Object -> the PFs of two objects that hold of it in ``state``, as ``(PF, its argument index, the
    other object)``: ``{"block0": (("toyInRoom", 0, "room2"),), "room2": (("toyInRoom", 1, "block0"),)}``
    (``related/4`` of ``groundings.lp``; spatial PFs and the addressee left out). From the same cached
    solve as :func:`candidate_tasks`; objects with none are absent. Raises AspError."""
    return _environment(state, library)[3]


def attribute_pfs(state: State, library: TaskLibrary) -> Mapping[str, tuple[tuple[str, str], ...]]:
    """Object -> its property PFs in ``state`` (colour, shape, a library's own classes: the PFs ``restrict/3``
    may name), by class name (colour first): ``((name, term), ...)`` with the name as groundlang writes it and
    the term as a library does, ``{"room0": (("roomIsGreen", "roomIs(green)"),)}``. Every family the
    library declares counts, pfs.lp's and a user's own (``toyHue(purple)``); objects with none are absent.
    From the same cached solve as :func:`candidate_tasks`. Raises AspError."""
    described = object_descriptions(state, library)
    terms = _environment(state, library)[2]
    return MappingProxyType({
        obj: pairs for obj, by_class in described.items()
        if (pairs := tuple((name, terms[name]) for cls in sorted(by_class) if library.pf_roles.property_class(cls)
                           for name in by_class[cls]))
    })


def viewpoint_pfs(about: Mapping[str, tuple[str, ...]], library: TaskLibrary) -> tuple[str, ...]:
    """The PFs of a viewpoint class (``viewpoint_class/1``: spatial) among one object's descriptions
    ``about`` (class -> PFs, an entry of :func:`object_descriptions`)."""
    return tuple(pf for cls in sorted(library.pf_roles.viewpoint_classes) for pf in about.get(cls, ()))


def kind_pfs(about: Mapping[str, tuple[str, ...]]) -> tuple[str, ...]:
    """The PFs of attributes whose values name kinds (``kind/1`` of ``domain.lp``: a toy's shape) among one
    object's descriptions ``about``: what a head noun may say of it besides its class ("the star")."""
    return tuple(pf for attribute in sorted(domain_classes().kinds) for pf in about.get(attribute, ()))


def spatial_descriptions(state: State, library: TaskLibrary) -> Mapping[str, tuple[str, ...]]:
    """The PFs of a viewpoint class (``pfs.lp``: spatial) true of each object where the agent stands in
    ``state``; objects none holds of are absent."""
    described = object_descriptions(state, library)
    return MappingProxyType({obj: said for obj, d in described.items() if (said := viewpoint_pfs(d, library))})


@dataclass(frozen=True)
class NarrowedCandidate:
    """A grounding that agrees with what is known, its consistent constraints and its probability."""

    grounded: GroundedTask
    constraints: tuple[BindingConstraint, ...]
    probability: float  # uniform over the surviving groundings of all tasks


def narrow_by_known(
    candidates: Sequence[Candidate],
    known: Mapping[str, Collection[str]],
    *,
    task: str | None = None,
) -> list[NarrowedCandidate]:
    """Keep the groundings whose bound objects satisfy the known PFs; the rest stays uniform.

    known: PF names (as groundlang writes them) per variable of the lifted task, e.g.
           ``{"T": {"toyIsStar"}}`` for "the star" (the paper's new-colour-name case).
           A grounding whose task lacks one of these variables is dropped.
    task: the lifted task's name when the logical form names it; ``None`` keeps every task.
    Each kept grounding keeps only the constraints that contain the known atoms, since the
    known words are part of the description. Probabilities are uniform, 1/len(result);
    an empty result means nothing in the environment fits what is known.
    """
    kept: list[tuple[GroundedTask, tuple[BindingConstraint, ...]]] = []
    for grounded, constraints in candidates:
        if task is not None and grounded.task != task:
            continue
        binding = dict(grounded.binding)
        if any(v not in binding for v in known):
            continue
        required = {Atom(p, (binding[v],)) for v, pfs in known.items() for p in pfs}
        # The first (largest) constraint holds every colour/shape PF true of the bound objects.
        true_atoms = set(constraints[0].atoms) if constraints else set()
        if not required <= true_atoms:
            continue
        if len(true_atoms) > MAX_ENUMERATED_ATOMS:
            raise ValueError(f"{grounded}: its bound objects have {len(true_atoms)} property PFs, whose "
                             f"{2 ** len(true_atoms):,} conjunctions would each be kept; at most {MAX_ENUMERATED_ATOMS} PFs")
        consistent = tuple(c for c in constraints if required <= set(c.atoms))
        kept.append((grounded, consistent))
    if not kept:
        return []
    p = 1.0 / len(kept)
    return [NarrowedCandidate(g, c, p) for g, c in kept]
