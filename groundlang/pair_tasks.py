"""What a command's (start, end) pairs show, and whether a final state does it (Williams et al. 2018).

The corpus gives no goal label. Its README judges a command by its pairs: the task is every relation
and description that holds in all of its end states and not in all of its start states; following the
command is correct when the final state satisfies all of them. Pairs lie in different layouts ("the
red room" is room0 in one, room2 in the next), so facts are lifted: a position PF that holds, with
each argument replaced by one thing said of it (its class or one of its property PFs: a colour, a
shape, a size, "the largest room", or what it holds there, "the room with the chair"), e.g.
``agentInRoom(agent, roomIsRed)`` or ``agentNextToToy(agent, toyIsChair)``. What holds, and what is said
of an object, are read from the PF tables (``model.pf_tables``): the domain's ASP, nothing written here.
"""

from __future__ import annotations

from itertools import product

from groundlang.logic.program import AspError
from groundlang.logic.tasks import TaskLibrary
from groundlang.logic.atoms import Atom
from groundlang.logic.classes import domain_classes
from groundlang.model.pf_tables import PFTables, library_pf_tables, tabulation_refusal
from groundlang.model.relevance import AbstractStateSpace, state_space_for
from groundlang.model.statespace import StateSpaceError
from groundlang.model.world import State

__all__ = ["lifted_facts", "pair_task", "command_task", "satisfies", "reachable", "covers", "text_agreement",
           "REACHABILITY_MAX_STATES"]

# Upper bound (the enumerator's estimate) on the states a reachability check may enumerate: the 8x8
# layouts with three blocks estimate 2.4 million and reach about 10^4; the 16x16 ones estimate 10^9 and
# are searched in their relevance abstraction (the blocks the pair moves; the others are walls).
REACHABILITY_MAX_STATES = 5_000_000


def _pair_space(start: State, end: State, max_states: int):
    """The exact space where it fits, else the abstraction moving the toys that differ from start to end."""
    return state_space_for(start, demonstrations=[(start, end)], max_states=max_states)


def _said(tables: PFTables) -> dict[str, tuple[str, ...]]:
    """Object -> its class and the unary property PFs that hold of it (the same in every state)."""
    out = {name: [cls] for name, cls in tables.objects.items()}
    for atom in tables.static:
        if len(atom.args) == 1:
            out[atom.args[0]].append(atom.predicate)
    return {name: tuple(sorted(set(said), key=said.index)) for name, said in out.items()}


def _with_what_they_hold(said: dict[str, tuple[str, ...]], holding: list[Atom], objects: dict[str, str],
                         relations: frozenset[str] | None) -> dict[str, list[tuple[str, str | None]]]:
    """Each object's ways of being said, with the object each way goes through (None for its own class and
    properties): also by what a relation of two objects holding in this state puts in it, as its second
    argument, "the room with the chair", ``toyInRoom(toyIsChair, _)`` through the chair, one for each thing
    said of the chair. The corpus's README counts a room by what it holds among the descriptions a task is
    judged by; the addressee (the agent, "you") neither holds nor is held in such a description."""
    addressee = domain_classes().addressee
    out = {name: [(way, None) for way in ways] for name, ways in said.items()}
    for atom in holding:
        if len(atom.args) != 2 or (relations is not None and atom.predicate not in relations):
            continue
        held, holder = atom.args
        if objects[held] in addressee or objects[holder] in addressee:
            continue
        out[holder] += [(f"{atom.predicate}({way}, _)", held) for way in said[held]]
    return out


def lifted_facts(state: State, library: TaskLibrary | None = None) -> frozenset[Atom]:
    """Every lifted fact of ``state``: each relation (:func:`_relations`) that holds, with its arguments said every way
    (an Atom whose arguments are what is said of the objects, ``agentInRoom(agent, roomIsRed)``, and by what
    they hold there, ``agentInRoom(agent, toyInRoom(toyIsChair, _))``; never through another argument of the
    same fact: the chair's room is not "the room with the chair" in the fact that puts the chair there)."""
    tables = library_pf_tables(state.layout, library)
    relations = _relations(library)
    holding = tables.position_holding(state.positions)
    said = _with_what_they_hold(_said(tables), holding, tables.objects, relations)
    return frozenset(Atom(atom.predicate, combo) for atom in holding
                     if relations is None or atom.predicate in relations
                     for combo in product(*([way for way, via in said[o] if via not in atom.args]
                                            for o in atom.args)))


def _relations(library: TaskLibrary | None) -> frozenset[str] | None:
    """The relations a task is made of: the goal predicates of the library's tasks (None: every
    position PF). A position PF no task has as its goal (``agentInDoor`` where the corpus's tasks never
    ask for a door) holds in end states by chance and is not what a command asks."""
    return None if library is None else library.goal_relations


def pair_task(pairs, library: TaskLibrary | None = None, where: list[str] | None = None) -> frozenset[Atom]:
    """What ``pairs`` (``(start, end)`` States) show: the facts of every end state that do not hold of
    every start state. Empty when the pairs agree on nothing that changed (a noisy command). ``where``:
    per pair, the place (file and line) named when its layout's facts cannot be read (too many cells to
    tabulate): then a ValueError that names it."""
    starts, ends = [], []
    pairs = list(pairs)
    if not pairs:
        raise ValueError("pair_task: no (start, end) pair: a command's task is what its pairs show")
    for k, (start, end) in enumerate(pairs):
        if start.layout != end.layout:  # a pair is one layout's start and end: facts of two say nothing
            raise ValueError(f"{where[k] + ': ' if where else ''}a pair's start and end states are of two layouts")
        try:
            starts.append(lifted_facts(start, library))
            ends.append(lifted_facts(end, library))
        except AspError as exc:
            if where is None:
                raise
            raise ValueError(f"{where[k]}: {exc}") from None
    return frozenset.intersection(*ends) - frozenset.intersection(*starts)


def command_task(command, library: TaskLibrary | None = None) -> frozenset[Atom] | None:
    """:func:`pair_task` of a ``.bdm`` command's pairs whose layouts can be tabulated (None where none can: what
    its pairs show cannot be read), a layout it cannot read otherwise named by file and line."""
    pairs = [p for p in command.pairs if tabulation_refusal(p.start.layout) is None]
    if not pairs:
        return None
    return pair_task([(p.start, p.end) for p in pairs], library, [f"{command.path}, line {p.line}" for p in pairs])


def _by_relation(task: frozenset[Atom]) -> dict[str, set[tuple]]:
    out: dict[str, set[tuple]] = {}
    for atom in task:
        out.setdefault(atom.predicate, set()).add(atom.args)
    return out


def covers(task: frozenset[Atom], other: frozenset[Atom]) -> bool:
    """Whether doing what ``task`` shows (one command's pairs) would do what ``other`` shows: each relation of
    ``other`` is one of ``task``'s, with a way of saying its objects in common (``agentInRoom(agent,
    roomIsRed)`` in both). Lifted facts name objects by description, so this is generous: the red room
    of one layout need not be the largest room of another."""
    mine, theirs = _by_relation(task), _by_relation(other)
    return all(relation in mine and mine[relation] & said for relation, said in theirs.items())


def text_agreement(commands, tasks) -> tuple[int, int, int]:
    """How far commands that share a text (lower-cased, stripped) agree on what their pairs show:
    ``(texts, commands, covered)`` over the texts given more than once, ``covered`` the commands that the
    best single task per text :func:`covers`. A reader of the words alone answers a text one way, so it can
    be right about at most ``covered`` of them: the rest is noise in the labels (a worker who described
    one pair, named a wrong colour, or wrote "move to chair" for a chair pushed into a room). A command
    whose task is None (:func:`command_task`: no layout of it could be tabulated) is left out."""
    by_text: dict[str, list[frozenset[Atom]]] = {}
    for command, task in zip(commands, tasks):
        if task is not None:
            by_text.setdefault(command.text.strip().lower(), []).append(task)
    shared = [group for group in by_text.values() if len(group) > 1]
    covered = sum(max(sum(covers(best, t) for t in group) for best in set(group)) for group in shared)
    return len(shared), sum(map(len, shared)), covered


def satisfies(state: State, task: frozenset[Atom], library: TaskLibrary | None = None) -> bool:
    """True when every fact of ``task`` holds in ``state`` (in its own layout); False for an empty task."""
    if not isinstance(task, (set, frozenset)) or not all(isinstance(a, Atom) for a in task):
        raise TypeError(f"satisfies: task must be a set of Atoms (pair_task's), not {type(task).__name__}")
    return bool(task) and task <= lifted_facts(state, library)


def reachable(start: State, end: State, max_states: int = REACHABILITY_MAX_STATES) -> bool | None:
    """Whether ``end`` can be reached from ``start`` under the project's dynamics; None when the state
    space is too large to enumerate (its estimate exceeds ``max_states``), or when only the relevance
    abstraction fits and ``end`` is not in it (reaching it might need the other blocks pushed aside)."""
    try:
        space = _pair_space(start, end, max_states)
    except StateSpaceError:
        return None
    try:
        space.index_of(end)
    except (KeyError, ValueError, StateSpaceError):
        return None if isinstance(space, AbstractStateSpace) else False
    return True


def shortest_actions(start: State, end: State, max_states: int = REACHABILITY_MAX_STATES):
    """A shortest action sequence from ``start`` to exactly ``end``: breadth-first over the enumerated
    state space, a layer at a time (vectorised over the layer's states). Of several shortest plans the
    first found is kept: states in index order, actions tried north, south, east, west; so the result is
    deterministic; in a layout only the relevance abstraction fits, shortest among plans that push no
    block the pair leaves in place. None when ``end`` is unreachable or the space is too large (see
    :func:`reachable`)."""
    import numpy as np

    from groundlang.model.world import Action

    try:
        space = _pair_space(start, end, max_states)
        target = space.index_of(end)
    except (StateSpaceError, KeyError, ValueError):
        return None
    next_state = np.asarray(space.next_state)[:, : len(Action)]
    parent = np.full(space.num_states, -1, dtype=np.int64)
    move = np.full(space.num_states, -1, dtype=np.int64)
    parent[0] = 0
    frontier = np.array([0], dtype=np.int64)
    while frontier.size and parent[target] < 0:
        reached = []
        for action in range(next_state.shape[1]):
            successors = next_state[frontier, action]
            fresh = parent[successors] < 0
            found, first = np.unique(successors[fresh], return_index=True)
            parent[found] = frontier[fresh][first]
            move[found] = action
            reached.append(found)
        frontier = np.unique(np.concatenate(reached))
    if parent[target] < 0:
        return None
    actions, s = [], target
    while s != 0:
        actions.append(Action(int(move[s])))
        s = int(parent[s])
    return tuple(reversed(actions))
