"""Relational descriptions: an object the task does not bind, described by its relation to one it does.

"Go to the room with the red chair" says which room by a toy in it: ``toyInRoom(T, R)`` holds at the
start between the goal room R and a toy T that words describe by its own unary PFs ("red", "chair").
An interpretation offers such a toy in a role of its own, named by the relation and the bound
object's role: ``other:toyInRoom.0@agentInRoom.1`` is "argument 0 of toyInRoom, whose argument 1 is
the room the agent must reach". A phrase aligned with that role ("with the red chair") is generated
from the toy's PFs; in an interpretation whose room holds no such toy the role is not offered, or is
offered with another toy whose PFs explain the words worse: so the words choose the room.

Which relations hold comes from clingo (``related/4`` of ``groundings.lp``: every PF of two objects but
the spatial ones, neither of them the addressee), so a user's PF of two objects describes objects as
``toyInRoom`` does, with no Python edit.

Bounded: one hop (a bystander related to a bound object, never to another bystander), only
bystanders of the classes commands name as things (``mentioned`` of ``logic.classes``: movable and not
the addressee, the toys), and the role *replaces* the bystander's ``other:<class>`` role, so each
object keeps exactly one role binding: the number of interpretations and of role bindings per
interpretation are unchanged. An object related to several bound objects takes the first relation, in
the order of the task's variables, then of PF name and argument index. The role names a lifted task
can offer are at most (its variables) x (PFs of two objects) x 2, listed by :func:`relational_roles`.
Rooms and doors keep their own descriptions: described by a relation to a bound toy (the room the
star starts in), they lost executions in novel layouts of the crowd corpus (ABLATIONS.md).
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping, Sequence

__all__ = ["relational_role", "relational_roles", "relational_links", "is_relational_role"]

_MARK = "@"


def relational_role(pf: str, index: int, bound_role: str) -> str:
    """The role of an object that is argument ``index`` of ``pf`` whose other argument is bound in
    ``bound_role``: ``relational_role("toyInRoom", 0, "agentInRoom.1")`` -> ``other:toyInRoom.0@agentInRoom.1``.
    A bystander's role (``other:``), so the alignment prior gives it no argument bonus."""
    return f"other:{pf}.{index}{_MARK}{bound_role}"


def is_relational_role(role: str) -> bool:
    return role.startswith("other:") and _MARK in role


def relational_roles(variables: Sequence[tuple[str, str]], relational_pfs: Iterable[tuple[str, tuple[str, str]]],
                     unaligned: Iterable[str], described: Collection[str]) -> tuple[str, ...]:
    """Every relational role a lifted task may offer: ``variables`` as ``(role, class)`` pairs in
    variable order, ``relational_pfs`` as ``TaskLibrary.relational_pfs`` lists them, ``unaligned`` the
    classes no phrase names (the addressee), which relate nothing, ``described`` the classes a
    relation may describe (see the module docstring)."""
    unaligned = set(unaligned)
    pfs = [(pf, sig) for pf, sig in relational_pfs if not unaligned & set(sig)]
    out = []
    for role, cls in variables:
        if cls in unaligned:
            continue
        for pf, sig in pfs:
            for index in (0, 1):
                if sig[1 - index] == cls and sig[index] in described:  # the bound object is the other argument
                    out.append(relational_role(pf, index, role))
    return tuple(dict.fromkeys(out))


def relational_links(bound: Sequence[tuple[str, str]], relations: Mapping[str, Sequence[tuple[str, int, str]]],
                     described: Collection[str]) -> dict[str, str]:
    """Object -> its relational role, for the objects not bound that relate to one that is.

    ``bound``: ``(object, role)`` of the task's variables in variable order; ``relations``: per object,
    ``(PF, its argument index, the other object)`` (``model.tasks.object_relations``); ``described``:
    the objects a relation may describe (of the classes commands name as things). The first relation
    wins (see the module docstring)."""
    taken = {obj for obj, _ in bound}
    links: dict[str, str] = {}
    for obj, role in bound:
        for pf, index, other in relations.get(obj, ()):
            if other not in taken and other not in links and other in described:
                links[other] = relational_role(pf, 1 - index, role)
    return links
