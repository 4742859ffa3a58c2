"""Goals across layouts: carry a gold goal into a novel environment by what its objects are, and name a
goal without its layout's object names."""

from __future__ import annotations

from groundlang.labels import goal_holds
from groundlang.logic.atoms import Atom, format_goal
from groundlang.model.world import State

__all__ = ["NovelEnvironmentError", "GoalHoldsAtStart", "object_properties", "translate_goal", "describe_goal"]


class NovelEnvironmentError(ValueError):
    """A novel layout where the gold goal cannot be carried over unambiguously."""


class GoalHoldsAtStart(NovelEnvironmentError):
    """A gold goal carried over that already holds in the novel layout: nothing there to ask, so that one
    execution cannot be scored (the layout serves every other label)."""


def object_properties(state: State, obj: str) -> tuple:
    """What an object is, whatever its place: its class and attribute values (a room's colour; a
    toy's colour and shape), from the layout's facts that name values rather than coordinates."""
    for cls, name, facts in state.layout.objects:
        if name == obj:
            return (cls,) + tuple(v for _, args in facts for v in args if isinstance(v, str))
    raise NovelEnvironmentError(f"{obj} is no object of the layout")


def translate_goal(goal: tuple[Atom, ...], source: State, target: State, where: str = "novel layout",
                   library=None) -> tuple[Atom, ...]:
    """Carry a goal over by the objects' properties (room colour; toy colour and shape).

    Raises NovelEnvironmentError when an object has no unique counterpart in
    ``target`` or when the translated goal already holds in ``target``.
    """
    names = {}
    for obj in {a for atom in goal for a in atom.args}:
        want = object_properties(source, obj)
        matches = [o for _, o, _ in target.layout.objects if object_properties(target, o) == want]
        if len(matches) != 1:
            raise NovelEnvironmentError(
                f"{where}: the goal's {obj} ({' '.join(want)}) has {len(matches)} counterparts; exactly one is needed"
            )
        names[obj] = matches[0]
    translated = tuple(Atom(a.predicate, tuple(names[x] for x in a.args)) for a in goal)
    if goal_holds(translated, target, library):
        raise GoalHoldsAtStart(f"{where}: the goal {format_goal(translated)} already holds at the start")
    return translated


def describe_goal(goal: tuple[Atom, ...], state: State) -> str:
    """A goal in layout-free words, e.g. ``toyInRoom(star, red)``, for confusion tables."""
    parts = []
    for atom in goal:
        args = []
        for a in atom.args:
            props = object_properties(state, a)
            args.append(props[-1])  # a toy by its shape, a room by its colour, the agent by its class
        parts.append(f"{atom.predicate}({', '.join(args)})")
    return " ".join(parts)
