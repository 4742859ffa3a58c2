"""Lifting grounded goals to lifted tasks: typed variables, structural identity, names, singling-out PFs.

Used by task discovery (:mod:`groundlang.inference.discovery`): objects in
a goal become typed variables (agent A, toy T, room R, door D, then R2 ...),
two goals with the same structure lift to the same task up to renaming, and
the smallest conjunction of colour/shape PFs that tells an object from its
peers is what a restriction of the lifted task would say.
"""

from __future__ import annotations

from itertools import combinations, permutations
from typing import Mapping, Sequence

from groundlang.logic.atoms import Atom
from groundlang.logic.classes import domain_classes
from groundlang.logic.tasks import CLASS_ORDER, LiftedTask, Variable

__all__ = ["structure_key", "lifted_key", "task_name", "lift_goal", "singling_out"]



def structure_key(goal: Sequence[tuple[str, Sequence[str]]], classes: dict[str, str]) -> tuple:
    """Canonical form of a goal up to renaming its variables/objects: ``((pred, (cls#k, ...)), ...)``.

    ``classes`` maps each argument to its class. Two goals have the same key exactly when
    one is the other with arguments renamed one-to-one within classes.
    """
    best = None
    for order in permutations(sorted(goal, key=lambda pa: pa[0])):
        if [p for p, _ in order] != sorted(p for p, _ in order):
            continue  # only orders that keep predicates sorted; ties between equal predicates are tried
        names: dict[str, str] = {}
        counts: dict[str, int] = {}
        key = []
        for pred, args in order:
            renamed = []
            for a in args:
                if a not in names:
                    c = classes[a]
                    counts[c] = counts.get(c, 0) + 1
                    names[a] = f"{c}#{counts[c]}"
                renamed.append(names[a])
            key.append((pred, tuple(renamed)))
        key = tuple(key)
        best = key if best is None or key < best else best
    return best


def lifted_key(task: LiftedTask) -> tuple:
    """:func:`structure_key` of a lifted task (e.g. to compare with the default library)."""
    return structure_key(task.goal, {v.name: v.cls for v in task.variables})


def _mover_rank(pred_args: tuple[str, tuple[str, ...]], classes: dict[str, str]) -> tuple:
    # The toy's goal before the agent's, as tasks.lp names toyToRoomAgentToRoom.
    first = classes[pred_args[1][0]]
    classes_ = domain_classes()
    movers = [c for c in reversed(classes_.classes) if c in classes_.movable]
    return (movers.index(first) if first in movers else len(movers), pred_args[0], pred_args[1])


def task_name(goal: Sequence[tuple[str, Sequence[str]]], classes: dict[str, str]) -> str:
    """A readable name from the goal predicates: toyInRoom -> toyToRoom, agentTouchingToy -> agentToToy."""
    parts = []
    for pred, _ in sorted(goal, key=lambda pa: _mover_rank((pa[0], tuple(pa[1])), classes)):
        name = pred
        for word in ("In", "Touching"):
            head, sep, tail = pred.partition(word)
            if sep and head and tail[:1].isupper():
                name = f"{head}To{tail}"
                break
        parts.append(name)
    return parts[0] + "".join(p[:1].upper() + p[1:] for p in parts[1:])


def lift_goal(goal: Sequence[Atom], classes: dict[str, str], name: str | None = None) -> LiftedTask:
    """Replace the objects of a grounded goal by typed variables (``A``, ``T``, ``R``, ``R2``, ...).

    ``classes``: object name -> class. One object, one variable; distinct objects of a class get
    distinct variables (as groundings bind them). Raises KeyError for an object of unknown class.
    """
    key = structure_key([(a.predicate, a.args) for a in goal], classes)
    names: dict[str, str] = {}
    counts: dict[str, int] = {}
    for _, args in key:
        for slot in args:
            if slot not in names:
                cls = slot.split("#")[0]
                counts[cls] = counts.get(cls, 0) + 1
                letter = cls[:1].upper()
                names[slot] = letter if counts[cls] == 1 else f"{letter}{counts[cls]}"
    rank = {c: i for i, c in enumerate(CLASS_ORDER)}
    variables = sorted({Variable(n, s.split("#")[0]) for s, n in names.items()},
                       key=lambda v: (rank.get(v.cls, len(rank)), v.cls, v.name))
    lifted_goal = tuple(sorted({(p, tuple(names[s] for s in args)) for p, args in key}))
    var_classes = {v.name: v.cls for v in variables}
    return LiftedTask(name or task_name(lifted_goal, var_classes), tuple(variables), lifted_goal)


# ---------------------------------------------------------------- colour/shape PFs that pick an object out


def singling_out(layout, obj: str, peers: Sequence[str],
                 attributes: Mapping[str, Sequence[tuple[str, str]]]) -> tuple[Atom, ...] | None:
    """Smallest colour/shape conjunction true of ``obj`` and of none of ``peers`` (same class).

    ``attributes``: object -> its ``(PF name, term)`` pairs, as ``model.tasks.attribute_pfs`` gives them
    (the families of pfs.lp and of a library's own PF rules).
    ``()`` when there are no peers; None when no conjunction of its PFs tells it apart.
    """
    if not peers:
        return ()
    pfs = attributes
    own = tuple(Atom(name, (obj,)) for name, _ in pfs.get(obj, ()))
    others = [{name for name, _ in pfs.get(p, ())} for p in peers]
    for k in range(1, len(own) + 1):
        for subset in combinations(own, k):
            wanted = {a.predicate for a in subset}
            if not any(wanted <= o for o in others):
                return subset
    return None


# ---------------------------------------------------------------- library search
