"""Interpretations: the enumerable latent (L, T, C) of one instance, with its prior.

An interpretation is a grounded task T of a lifted task L together with one
binding constraint C (a conjunction of colour/shape PFs true of T's bound
objects). The prior is the design's: L uniform over the lifted tasks
permissible in the initial state, T uniform over L's groundings not already
true, C uniform over the conjunctions of T. Each bound variable also gets a
*role*, ``predicate.position`` of the first goal atom it appears in
(``toyInRoom.1`` is "the room the toy must reach"), so that word alignments
learned for one lifted task carry over to another that shares the role.

Every other object of the state is offered too, with the role
``other:<class>`` ("from the orange room", "through the door on the left"):
a noun phrase may describe an object that is not part of the goal, and its
words are then generated from that object's colour and shape PFs. This keeps
all words grounded: the colour words of the rooms a worker walks *through*
teach the colours as well as those of the goal, and no free distribution is
left for phrases to escape into (one free "unaligned" distribution learns to
explain every phrase there; ABLATIONS.md, "Figures moved out of comments").
A phrase may still align with nothing (role ``none``); its
words then come from ``NULL``.

The room the agent starts in has a bystander role of its own, ``other:start``
("go *from the orange room* to ..."; "leave the room you're in"), so that what
commands say of where they start is learned apart from the rooms they pass or
find the star in, and teaches the colours with a known referent. On a door cell
the agent is in no room; a command may then presuppose any room as its start,
so every room the task does not bind is offered both as the start room and as
another room (:func:`start_rooms`): a command written for another layout starts
where it says, and the agent of a new layout may stand on a door cell. What the
start role and the door-cell rule measured: ABLATIONS.md. Both kinds of bystander role are switches
(the parse model's ``start_role`` and ``bystander_roles``): without the first the start room is one more
``other:room``; without the second every bystander shares one role, ``other:*`` (:data:`BYSTANDER_ROLE`).

Every object, bound or not, may also be described by the spatial PFs
(``pfs.lp``) true of it where the agent stands: "the door on the left"
(``doorWestOfAgent``). They are not part of C: a side is not a property the
object keeps in another layout. What each object is described by comes from
clingo (``groundings.lp`` shows ``described/3``), so a PF class a user's
library declares describes bystanders as it constrains bound objects.

With ``relational`` (the parse model's ``relational_descriptions``), a bystander related to a bound
object by a PF of two objects ("the room *with the chair*") takes a role named by that relation
instead of ``other:<class>`` (:mod:`groundlang.model.relational`, which says how it is bounded).
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from groundlang.logic.atoms import Atom
from groundlang.logic.tasks import BindingConstraint, GroundedTask, LiftedTask, TaskLibrary
from groundlang.logic.groundings import MAX_ENUMERATED_ATOMS
from groundlang.model.features import atoms_hold_along
from groundlang.model.geometry import cell_tables
from groundlang.model.pf_tables import PFTables
from groundlang.model.relational import relational_links, relational_roles
from groundlang.model.tasks import candidate_tasks, kind_pfs, object_descriptions, object_relations, viewpoint_pfs
from groundlang.model.vocabulary import NO_ROLE
from groundlang.logic.classes import domain_classes
from groundlang.model.world import WORLD_CLASSES, State

__all__ = [
    "Interpretation",
    "NoTaskError",
    "RoleBinding",
    "interpretations",
    "unbroken_held_parts",
    "without_unbroken_held_parts",
    "object_names",
    "task_roles",
    "alignable_roles",
    "OTHER_ROLES",
    "START_ROLE",
    "BYSTANDER_ROLE",
    "bystander_roles",
    "start_rooms",
    "UNALIGNED_CLASSES",
]

# The room a command may presuppose the agent starts in ("go *from the orange room* to ..."): a bystander
# role of its own (see start_rooms).
START_ROLE = "other:start"
OTHER_ROLES = tuple(f"other:{cls}" for cls in WORLD_CLASSES) + (START_ROLE,)
# The one role of every bystander when bystanders are not told apart by their class (``bystander_roles``
# off): a phrase about an object the task leaves alone aligns with it whatever the object is.
BYSTANDER_ROLE = "other:*"
# The addressee (addressee/1 of logic/domain.lp) is "you", which the parser leaves without words: no
# noun phrase aligns with it (model.encoding), whatever its role.
UNALIGNED_CLASSES = domain_classes().addressee


@dataclass(frozen=True)
class RoleBinding:
    """One thing a noun phrase may align with: a role, the object and its PF tokens."""

    role: str  # "toyInRoom.1", "other:room", ...
    obj: str  # object name, e.g. "room2"
    cls: str  # object class: agent, room, door, toy
    constraint_tokens: tuple[str, ...]  # PFs words may express: C's for a bound object, all for others; then spatial PFs
    kind_tokens: tuple[str, ...] = ()  # PFs a head noun may express besides the class: a toy's shape


@dataclass(frozen=True)
class Interpretation:
    """One (L, T, C) candidate of an instance."""

    task: GroundedTask
    constraint: BindingConstraint
    log_prior: float
    roles: tuple[RoleBinding, ...]  # goal variables first, then every other object (a room twice on a door cell)

    @property
    def lifted(self) -> str:
        return self.task.task

    @property
    def goal(self) -> tuple[Atom, ...]:
        return self.task.goal

    @property
    def constraint_tokens(self) -> tuple[str, ...]:
        return tuple(a.predicate for a in self.constraint.atoms)


def task_roles(lifted: LiftedTask) -> tuple[str, ...]:
    """The roles of a lifted task's variables, in variable order: each variable's first goal
    atom and its place there (``toyInRoom.0`` for the toy of toyToRoom, ``toyInRoom.1`` for the room).
    Tasks with the same goal predicates share roles, and so what their words say of them."""
    return tuple(
        next(f"{pred}.{args.index(var.name)}" for pred, args in lifted.goal if var.name in args)
        for var in lifted.variables
    )


def bystander_roles(start_role: bool = True, by_class: bool = True) -> tuple[str, ...]:
    """The roles of objects a task does not bind: one per class and the start room's
    (:data:`OTHER_ROLES`), or with ``by_class`` off one for all (:data:`BYSTANDER_ROLE`) and the start
    room's; without ``start_role`` no start room's."""
    roles = OTHER_ROLES[:-1] if by_class else (BYSTANDER_ROLE,)
    return roles + ((START_ROLE,) if start_role else ())


def alignable_roles(lifted: LiftedTask, relational_pfs=(), start_role: bool = True,
                    by_class: bool = True) -> tuple[str, ...]:
    """Every role a noun phrase may align with in an interpretation of ``lifted``: nothing, the
    roles of its own variables and those of bystanders, but never the agent's (UNALIGNED_CLASSES)
    nor another task's variables. What the parse model's per-task alignment tables span.
    ``relational_pfs`` (``TaskLibrary.relational_pfs``, when relational descriptions are on): the
    relational roles of its variables too. ``start_role``, ``by_class``: :func:`bystander_roles`."""
    own = (role for var, role in zip(lifted.variables, task_roles(lifted)) if var.cls not in UNALIGNED_CLASSES)
    others = (role for role in bystander_roles(start_role, by_class)
              if role.removeprefix("other:") not in UNALIGNED_CLASSES)
    related = relational_roles([(role, var.cls) for var, role in zip(lifted.variables, task_roles(lifted))],
                               relational_pfs, UNALIGNED_CLASSES, domain_classes().mentioned)
    return (NO_ROLE, *dict.fromkeys(own), *others, *related)


def object_names(state: State) -> list[str]:
    """Every object of ``state`` in the layout's order: the agent, rooms, doors, toys."""
    return [name for _, name, _ in state.layout.objects]


def _roles(task: GroundedTask, constraint: BindingConstraint, state: State, library: TaskLibrary,
           described: Mapping[str, Mapping[str, tuple[str, ...]]],
           starts: tuple[frozenset[str], bool], relation_words: bool = False,
           relations: Mapping[str, tuple] | None = None, by_class: bool = True) -> tuple[RoleBinding, ...]:
    """The roles of an interpretation: the task's variables (what words may say of a bound object:
    its PFs in C, then its spatial PFs), then every other object (all its unary PFs, as clingo
    describes it: colours, shapes, spatial PFs, any class a user's library adds). A head noun may
    also say an object's shape PF. ``starts``: :func:`start_rooms` of ``state``. ``relations``
    (:func:`~groundlang.model.tasks.object_relations`, when relational descriptions are on): a bystander
    related to a bound object takes its relational role instead of ``other:<class>``, which is
    :data:`BYSTANDER_ROLE` for every class without ``by_class``."""
    lifted = library.task(task.task)
    binding = dict(task.binding)
    bindings = []
    # The goal's relations, which a phrase about an argument may say ("the left side of the chair").
    relation = tuple(dict.fromkeys(a.predicate for a in task.goal)) if relation_words else ()
    for var, role in zip(lifted.variables, task_roles(lifted)):
        obj = binding[var.name]
        about = described.get(obj, {})
        said = tuple(a.predicate for a in constraint.atoms if a.args == (obj,)) + viewpoint_pfs(about, library)
        bindings.append(RoleBinding(role, obj, var.cls, said + relation, kind_pfs(about) + relation))
    bound = set(binding.values())
    classes = {name: cls for cls, name, _ in state.layout.objects}
    links = relational_links([(binding[v.name], r) for v, r in zip(lifted.variables, task_roles(lifted))], relations,
                             {o for o, c in classes.items() if c in domain_classes().mentioned}) if relations is not None else {}
    start_set, start_known = starts
    for obj in object_names(state):
        if obj not in bound:
            cls = classes[obj]
            about = described.get(obj, {})
            said = tuple(name for names in about.values() for name in names)
            if obj in start_set:
                bindings.append(RoleBinding(START_ROLE, obj, cls, said, kind_pfs(about)))
                if start_known:
                    continue
            other = f"other:{cls}" if by_class or cls in UNALIGNED_CLASSES else BYSTANDER_ROLE
            bindings.append(RoleBinding(links.get(obj, other), obj, cls, said, kind_pfs(about)))
    return tuple(bindings)


def start_rooms(state: State) -> tuple[frozenset[str], bool]:
    """The rooms that may be the one a command presupposes the agent starts in, and whether it is known.

    The room the agent stands in (known: it is offered as the start room only). Outside every room's
    interior (on a door cell, the only other walkable cells) the agent is in no room, and a command
    written for it may say it starts in any: every room the task does not bind is offered both as the
    start room and as another room."""
    room_of = cell_tables(state.layout).room_of
    names = state.layout.room_names
    inside = int(room_of[state.agent.x, state.agent.y])
    if inside >= 0:
        return frozenset({names[inside]}), True
    return frozenset(names), False


class NoTaskError(ValueError):
    """No task of the library can be asked in a state: every grounding is impossible or already true.
    Its own class so that a caller reading many states (training, evaluation) can say which one, or
    leave that one out, without catching every ValueError."""


def interpretations(state: State, library: TaskLibrary, enumerate_constraints: bool = True,
                    relation_words: bool = False, relational: bool = False,
                    held_parts: bool = False, demonstrated: bool = False, start_role: bool = True,
                    bystander_roles: bool = True) -> list[Interpretation]:
    """Every (L, T, C) of ``state`` with its log prior, in a deterministic order.

    With ``enumerate_constraints=False`` each grounding appears once, with C
    the largest conjunction (every colour/shape PF of its bound objects) and
    no C term in the prior: for a language model that lets each word pick
    the property it expresses (the parse-aligned model), enumerating C would
    only tax the goal's description with the C prior, which other objects'
    descriptions do not pay (measured: the model then learned to read "to the
    orange room" as a room other than the goal).

    With ``relation_words`` the goal's PFs join what words may say of each argument of the task
    (the parse model's setting of that name). With ``relational`` a bystander related to a bound
    object is offered in a relational role (the parse model's ``relational_descriptions``).

    With ``held_parts`` a conjunctive grounding one of whose parts already holds is offered too: "put
    the bag in the blue room and come back to the green room", said in the green room, asks for a
    part the plan must break and restore. Without it such groundings are left out: they then ask
    no more than the smaller task unless the plan breaks the part, and, kept where nothing breaks it,
    they duplicate that task (:func:`unbroken_held_parts` says which a demonstration rules out).
    With ``held_parts`` and ``demonstrated`` (the instance comes with a demonstration) a goal that holds
    at the start as a whole is offered too, for a demonstration that leaves it and comes back; its
    prior is its lifted task's share for one grounding, so the other readings' priors are those of an
    instance without it. Without a demonstration it asks for nothing and is left out.

    ``start_role`` offers the room the agent starts in (any room, on a door cell) in the role
    :data:`START_ROLE` (:func:`start_rooms`); without it that room is another room like the rest.
    ``bystander_roles`` gives each class of bystander a role of its own (``other:room``); without it they
    share :data:`BYSTANDER_ROLE` (the parse model's settings of these names).

    Raises NoTaskError (a ValueError) when no lifted task has a grounding that is not already
    true in ``state`` (nothing could be asked of the agent).
    """
    candidates = [
        (task, constraints)
        for task, constraints in candidate_tasks(state, library, wholly_true=held_parts and demonstrated)
        if len(task.goal) == 1 or not task.holding or held_parts
    ]
    if not candidates:
        raise NoTaskError(
            "no task of the library can be carried out from this state "
            "(every grounding is impossible or already true)"
        )
    # Once per state, shared by every interpretation.
    described = object_descriptions(state, library)
    starts = start_rooms(state) if start_role else (frozenset(), True)
    relations = object_relations(state, library) if relational else None
    # Counted over what could be asked of the agent: a goal that wholly holds takes a share, not a count.
    per_lifted = Counter(task.task for task, _ in candidates if not task.holds_wholly)
    per_lifted.update({task.task: 1 for task, _ in candidates if task.task not in per_lifted})
    n_lifted = len(per_lifted)
    result = []
    for task, constraints in candidates:
        log_prior_t = -math.log(n_lifted) - math.log(per_lifted[task.task])
        if not enumerate_constraints:
            largest = constraints[0]  # every colour/shape PF true of the bound objects (largest first)
            roles = _roles(task, largest, state, library, described, starts, relation_words, relations, bystander_roles)
            result.append(Interpretation(task, largest, log_prior_t, roles))
            continue
        if len(constraints[0].atoms) > MAX_ENUMERATED_ATOMS:
            raise ValueError(f"{task}: its bound objects have {len(constraints[0].atoms)} property PFs, and this "
                             f"language model offers each of their {2 ** len(constraints[0].atoms):,} conjunctions as "
                             f"a reading of its own; at most {MAX_ENUMERATED_ATOMS} PFs (the parse model's "
                             "largest_constraint offers the largest alone)")
        for constraint in constraints:
            result.append(
                Interpretation(
                    task,
                    constraint,
                    log_prior_t - math.log(len(constraints)),
                    _roles(task, constraint, state, library, described, starts, relation_words, relations,
                           bystander_roles),
                )
            )
    return result


def unbroken_held_parts(interps: Sequence[Interpretation], states: Sequence[State],
                        tables: PFTables) -> np.ndarray:
    """``[J]`` bool: interpretations with a goal part that holds at the start and in every state of
    the demonstration ``states``. Such a part explains nothing the demonstration shows (nobody asks
    for what already holds and is never at stake), so a learner scores the reading out; the part
    the plan breaks and restores ("... and come back to the green room") is what is kept."""
    held = sorted({a for i in interps for a in i.task.holding}, key=str)
    out = np.zeros(len(interps), dtype=bool)
    if not held or not states:
        return out
    positions = np.stack([s.positions for s in states])
    always = atoms_hold_along(states[0].layout, positions, held, tables).all(axis=0)
    unbroken = {a for a, kept in zip(held, always) if kept}
    for j, interp in enumerate(interps):
        out[j] = any(a in unbroken for a in interp.task.holding)
    return out


def without_unbroken_held_parts(groups: Sequence[Sequence[Interpretation]], behaviour: Sequence[Sequence[float]],
                                demonstrations: Sequence[Sequence[State]], tables: Sequence[PFTables]):
    """Each instance's interpretations and behaviour values without the readings its demonstration
    rules out (:func:`unbroken_held_parts`): ``(groups, behaviour)`` as lists of lists."""
    kept_groups, kept_values = [], []
    for group, values, states, table in zip(groups, behaviour, demonstrations, tables):
        out = unbroken_held_parts(group, states, table)
        kept_groups.append([i for i, o in zip(group, out) if not o])
        kept_values.append([v for v, o in zip(values, out) if not o])
    return kept_groups, kept_values
