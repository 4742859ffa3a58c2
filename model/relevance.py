"""Relevance abstraction: the state space of the objects that matter to a task, the others fixed as walls.

For a goal (grounded atoms) and, optionally, demonstrations, the objects that
matter are the agent, the movable objects the goal names and those a
demonstration moves; every other movable object is *scenery*: it stands where
it is and its cell is a wall. The abstraction's reachable states are then
enumerated as :mod:`groundlang.model.statespace` enumerates a whole world, over
far fewer objects: a 16 x 16 layout of three toys has about 10^9 states, its
abstraction for "take the chair to the blue room" about 4 x 10^4.

Soundness: a move that changes the abstraction's state has the same effect in
the real dynamics, so every state a plan visits is a real state. A move into
scenery is blocked in the abstraction but is a push in reality: such a move
never helps a plan (it wastes a step), and :func:`pushes_scenery` finds it so
that acting stops before it rather than report a state the world would not
be in. What the abstraction loses is plans that must push scenery out of the
way; when the goal cannot be reached without that, :func:`state_space_for`
lets the scenery the agent can touch move too, as long as the space fits.

A state of the abstraction keeps every object's position (``positions`` is
``[S, 1 + k, 2]`` as for the exact space, scenery constant), so goal masks,
features and PF tables read it unchanged; ``indices_of`` finds a real state
when its scenery stands where the abstraction put it.

:func:`state_space_for` is the one place that chooses: the exact space when
its bound fits ``max_states``, else the abstraction, with a log line saying
which and why; it refuses, in one line, what neither fits. Comparing goals by
the states they hold in (confidence) needs no transitions: where the world is
too large, :func:`placement_sample` gives a seeded sample of placements.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from functools import lru_cache

import numpy as np

from groundlang.logic.atoms import Atom, parse_atom

from .pf_tables import MAX_TABULATED_CELLS
from .state_search import MAX_STATES_VARIABLE, count_text, key_powers, max_states_given, search, state_count_bound
from .statespace import StateSpace, StateSpaceError, enumerate_states
from .world import ACTION_DELTAS, State

__all__ = ["AbstractStateSpace", "abstract_space", "abstract_space_uncached", "abstraction_bound", "announce",
           "STATE_SOURCE", "reading_states", "exact_fits", "relevant_toys", "state_space_for",
           "check_abstraction_possible", "pushes_scenery", "PlacementSample", "placement_sample"]

logger = logging.getLogger(__name__)

# An abstraction keeps every object's position in every state ([S, objects, 2] int16): its states are bounded by
# max_states, but a layout of hundreds of toys multiplies them (one of 700 had taken 2.9 GB to be refused).
MAX_POSITION_BYTES = 1 << 30
# (layout, max_states, message) already announced at info level, oldest first (bounded).
_ANNOUNCED: dict = {}
# Where the state being sized was read from ("part2.bdm, line 1234"), set by whoever reads states from a
# file: an announced line then names the pair that needed it. A corpus's many pairs in one layout share
# one line, so it names the first.
STATE_SOURCE: ContextVar[str | None] = ContextVar("state_source", default=None)


@contextmanager
def reading_states() -> Iterator[None]:
    """A loop over states read from files sets :data:`STATE_SOURCE` to each one's place inside this;
    leaving it forgets the last, so that what runs afterwards is not said to come from there."""
    token = STATE_SOURCE.set(None)
    try:
        yield
    finally:
        STATE_SOURCE.reset(token)


class AbstractStateSpace(StateSpace):
    """The reachable states when only the agent and the toys ``relevant`` move; other toys are walls.

    Attributes (beyond StateSpace's): ``relevant``, indices of the moving toys (0-based among the
    layout's toys); ``scenery``, the others. ``positions`` holds every object, scenery constant.
    """

    def __init__(self, initial: State, next_state: np.ndarray, positions: np.ndarray, keys: np.ndarray,
                 cell_of: np.ndarray, relevant: Sequence[int], level_sizes: np.ndarray | None = None) -> None:
        super().__init__(initial, next_state, positions, keys, cell_of, level_sizes=level_sizes)
        self.relevant = tuple(int(i) for i in relevant)
        self.scenery = tuple(i for i in range(len(initial.toys)) if i not in self.relevant)
        self._moving = np.array([0] + [1 + i for i in self.relevant], dtype=np.int64)
        self._still = np.array([1 + i for i in self.scenery], dtype=np.int64)
        self._fixed = initial.positions[self._still]  # [k - m, 2]
        self._powers = key_powers(int(cell_of.max()) + 1, len(self._moving))

    def __repr__(self) -> str:
        names = self.layout.toy_names
        moving = ", ".join(["agent0"] + [names[i] for i in self.relevant])
        return f"AbstractStateSpace({self.num_states} states, moving {moving}; {len(self.scenery)} toy(s) as walls)"

    def indices_of(self, positions: np.ndarray) -> np.ndarray:
        """Indices of states given as full positions ``[n, 1 + k, 2]``; -1 where unreachable or where
        scenery stands elsewhere than in the abstraction."""
        pos = np.asarray(positions, dtype=np.int64)
        if pos.ndim != 3 or pos.shape[1:] != self.positions.shape[1:]:
            raise StateSpaceError(
                f"positions of shape {tuple(pos.shape)} do not match [n, {self.positions.shape[1]}, 2]")
        still = (pos[:, self._still] == self._fixed).all(axis=(1, 2))
        return np.where(still, self._lookup(pos[:, self._moving]), -1)


def _toy_index(layout) -> dict[str, int]:
    return {name: i for i, name in enumerate(layout.toy_names)}


def relevant_toys(state: State, goal: Iterable[Atom | str] = (),
                  demonstrations: Iterable[Sequence[State]] = ()) -> tuple[int, ...]:
    """Indices of the toys the goal's atoms name or a demonstration (a sequence of States) moves."""
    index = _toy_index(state.layout)
    chosen = set()
    for atom in goal:
        atom = parse_atom(atom) if isinstance(atom, str) else atom
        chosen.update(index[a] for a in atom.args if a in index)
    start = state.positions[1:]
    for states in demonstrations:
        if len(states):
            # [T, k, 2] -> toys whose cell ever differs from the first state's
            moved = (np.stack([s.positions[1:] for s in states]) != start[None]).any(axis=(0, 2))
            chosen.update(np.flatnonzero(moved).tolist())
    return tuple(sorted(chosen))


def _cells(state: State) -> int:
    return int(np.count_nonzero(state.layout.walkable))


def abstraction_bound(state: State, relevant: Sequence[int]) -> int:
    """Upper bound on the abstraction's states: the agent and the relevant toys on the cells scenery leaves."""
    scenery = len(state.toys) - len(relevant)
    return state_count_bound(_cells(state) - scenery, len(relevant))


def exact_fits(state: State, max_states: int | None = None) -> bool:
    """Whether the whole world's bound (:func:`state_count_bound`) is within ``max_states``."""
    max_states = max_states_given(max_states)
    return state_count_bound(_cells(state), len(state.toys)) <= max_states


def check_abstraction_possible(state: State, max_states: int | None = None) -> int:
    """Refuse (StateSpaceError, one line) a layout no method can plan in: the whole world's bound exceeds
    ``max_states`` and so does the least abstraction (the agent alone, every toy a wall), or the layout has
    more cells than goal masks can be tabulated over. From cell counts alone: callers ask it before slow
    per-layout work (grounding a layout of 10^6 cells takes 20 s). Returns the least bound."""
    max_states = max_states_given(max_states)
    cells, toys = _cells(state), len(state.toys)
    exact = state_count_bound(cells, toys)
    if exact <= max_states:
        return exact
    if cells > MAX_TABULATED_CELLS:
        raise StateSpaceError(f"this layout could reach up to {count_text(exact)} states ({cells} walkable cells, "
                              f"{toys} toy(s)), more than max_states={max_states:,}, and its cells are more than "
                              f"the relevance abstraction's PF tables are built for ({MAX_TABULATED_CELLS:,})")
    bound = abstraction_bound(state, ())
    if bound > max_states:
        raise StateSpaceError(f"even the agent alone could reach {count_text(bound)} cells here, more than max_states="
                              f"{max_states:,}; set {MAX_STATES_VARIABLE}={bound} (or more) to allow it")
    return bound


def abstract_space(state: State, relevant: Sequence[int], max_states: int | None = None) -> AbstractStateSpace:
    """Enumerate the abstraction in which the agent and the toys ``relevant`` move and every other toy
    is a wall; index 0 is ``state``. StateSpaceError when its bound exceeds ``max_states``. The last few
    are remembered: the candidate goals of one demonstration mostly keep the same toys."""
    max_states = max_states_given(max_states)
    return _abstract_space(state, tuple(sorted(set(int(i) for i in relevant))), max_states)


@lru_cache(maxsize=4)
def _abstract_space(state: State, relevant: tuple[int, ...], max_states: int) -> AbstractStateSpace:
    return abstract_space_uncached(state, relevant, max_states)


def abstract_space_uncached(state: State, relevant: tuple[int, ...], max_states: int) -> AbstractStateSpace:
    """:func:`abstract_space` without its memory (``relevant`` sorted): for callers that build many
    abstractions once each (one per placement of the toys a demonstration moves)."""
    scenery = [i for i in range(len(state.toys)) if i not in relevant]
    pos = state.positions
    walkable = state.layout.walkable.copy()
    walkable[pos[1:][scenery, 0], pos[1:][scenery, 1]] = False
    moving = [0] + [1 + i for i in relevant]
    names = [state.layout.movable_names[j] for j in moving]
    next_state, sub, keys, cell_of, sizes = search(walkable, pos[moving], names, max_states)
    if len(sub) * len(pos) * 4 > MAX_POSITION_BYTES:
        raise StateSpaceError(f"the relevance abstraction has {len(sub):,} states of {len(pos):,} objects each: "
                              f"their positions would take {len(sub) * len(pos) * 4 / 2**30:.1f} GiB, more than "
                              f"{MAX_POSITION_BYTES // 2**30} GiB")
    full = np.empty((len(sub), len(pos), 2), dtype=np.int16)
    full[:] = pos.astype(np.int16)[None]
    full[:, moving] = sub
    return AbstractStateSpace(state, next_state, full, keys, cell_of, relevant, level_sizes=sizes)


def pushes_scenery(space: StateSpace, states: np.ndarray, actions: np.ndarray) -> np.ndarray:
    """``[T]`` bool: which moves ``actions[t]`` from ``states[t]`` (indices) push a scenery toy in the real
    dynamics. The abstraction blocks them (the state stays), so a plan that takes one is valid only up
    to there; always False in an exact space."""
    states, actions = np.asarray(states, dtype=np.int64), np.asarray(actions, dtype=np.int64)
    if not isinstance(space, AbstractStateSpace) or not space.scenery or not len(actions):
        return np.zeros(len(actions), dtype=bool)
    pos = space.positions[states].astype(np.int64)  # [T, 1 + k, 2]
    target = pos[:, 0] + ACTION_DELTAS[actions]  # [T, 2] the cell the agent steps into
    beyond = target + ACTION_DELTAS[actions]
    walk = space.layout.walkable
    w, h = walk.shape
    inside = (beyond[:, 0] >= 0) & (beyond[:, 0] < w) & (beyond[:, 1] >= 0) & (beyond[:, 1] < h)
    free = inside & walk[np.clip(beyond[:, 0], 0, w - 1), np.clip(beyond[:, 1], 0, h - 1)]
    free &= ~(pos[:, 1:] == beyond[:, None]).all(axis=2).any(axis=1)  # no toy there either
    on_scenery = (space._fixed[None] == target[:, None]).all(axis=2).any(axis=1)
    return on_scenery & free


def _touched_scenery(space: AbstractStateSpace) -> tuple[int, ...]:
    """Scenery toys next to a cell the agent reaches in ``space``: those it could try to push."""
    if not space.scenery:
        return ()
    agent = np.unique(space.positions[:, 0].astype(np.int64), axis=0)  # [n, 2] cells the agent reaches
    reach = (agent[:, None, :] + ACTION_DELTAS[None]).reshape(-1, 2)  # cells it could step into
    fixed = space._fixed  # [k - m, 2]
    hit = (reach[:, None, :] == fixed[None]).all(axis=2).any(axis=0)
    return tuple(space.scenery[j] for j in np.flatnonzero(hit))


def _goal_text(goal: Sequence) -> str:
    return " ".join(str(a) for a in goal) or "(no goal)"


def state_space_for(state: State, goal: Iterable[Atom | str] = (), demonstrations: Iterable[Sequence[State]] = (),
                    tables=None, max_states: int | None = None, method: str = "auto") -> StateSpace:
    """The state space to plan and score in: the exact one when its bound fits ``max_states``, else the
    relevance abstraction for ``goal`` and ``demonstrations`` (logged, with the bounds that chose it).
    ``method`` "exact" or "abstraction" forces one (to compare them); "auto" chooses.

    ``tables`` (PFTables of the layout), when given with a goal: if no goal state is reachable in the
    abstraction, the scenery the agent can touch moves too, while the bound still fits; a plan that must
    push scenery aside is found that way. With ``demonstrations``, when the goal's toys and the moved
    ones do not fit, the moved ones alone move. Raises StateSpaceError (one line) when neither fits.
    """
    if method not in ("auto", "exact", "abstraction"):
        raise ValueError(f"method {method!r}: expected auto, exact or abstraction")
    max_states = max_states_given(max_states)
    goal = tuple(parse_atom(a) if isinstance(a, str) else a for a in goal)
    cells, toys = _cells(state), len(state.toys)
    exact = state_count_bound(cells, toys)
    if method == "exact" or (method == "auto" and exact <= max_states):
        # debug, not info: the usual case, and the CLI shows info lines
        logger.debug("state space: exact enumeration (at most %s states <= max_states=%s)", count_text(exact),
                     f"{max_states:,}")
        return enumerate_states(state, max_states)
    demonstrations = list(demonstrations)
    relevant = relevant_toys(state, goal, demonstrations)
    bound = abstraction_bound(state, relevant)
    moved = relevant_toys(state, (), demonstrations) if demonstrations else None
    if bound > max_states and moved is not None and abstraction_bound(state, moved) <= max_states:
        # Scoring a demonstration: a toy the goal names but the demonstration leaves in place is either
        # where the goal wants it from the start (moving it could only undo that) or in a goal the
        # demonstration does not pursue; either way it is scored as a wall rather than refused.
        logger.debug("goal %s: toys it names that the demonstration leaves in place are walls (%s states > %s)",
                     _goal_text(goal), count_text(bound), f"{max_states:,}")
        relevant, bound = moved, abstraction_bound(state, moved)
    if bound > max_states:
        raise StateSpaceError(
            f"too many states for goal {_goal_text(goal)}: the layout could reach {count_text(exact)} ({cells} cells, {toys} "
            f"toy(s)) and the abstraction moving the agent and {len(relevant)} toy(s) {count_text(bound)}, both more than "
            f"max_states={max_states:,}; set {MAX_STATES_VARIABLE}={bound} (or more) to allow the abstraction")
    space = abstract_space(state, relevant, max_states)
    # widening needs room for at least one more toy
    while (tables is not None and goal and space.scenery
           and abstraction_bound(state, relevant + space.scenery[:1]) <= max_states
           and not _goal_reachable(space, goal, tables)):
        more = tuple(sorted(set(relevant) | set(_touched_scenery(space))))
        if more == relevant or abstraction_bound(state, more) > max_states:
            break
        logger.info(*_from_source("relevance abstraction: goal %s unreachable with %d toy(s) as walls; letting %d "
                                  "more move", _goal_text(goal), len(space.scenery), len(more) - len(relevant)))
        relevant = more
        space = abstract_space(state, relevant, max_states)
    announce(state.layout, max_states, "state space: relevance abstraction, %d states (whole layout up to %s %s "
             "max_states=%s; moving agent0%s, %d toy(s) as walls)", space.num_states, f"{exact:,}",
             ">" if exact > max_states else "<=", f"{max_states:,}",
             "".join(f", {state.layout.toy_names[i]}" for i in space.relevant), len(space.scenery))
    return space


def announce(layout, max_states: int, message: str, *args) -> None:
    """Log ``message`` at info level the first time for (layout, max_states), then at debug level (a corpus
    of many pairs in one layout would repeat it)."""
    seen = (layout, max_states, message) in _ANNOUNCED
    _ANNOUNCED[layout, max_states, message] = None
    if len(_ANNOUNCED) > 256:
        _ANNOUNCED.pop(next(iter(_ANNOUNCED)))
    logger.log(logging.DEBUG if seen else logging.INFO, *_from_source(message, *args))


def _from_source(message: str, *args) -> tuple:
    """A log call's message and arguments, said of :data:`STATE_SOURCE`'s pair where one is set."""
    source = STATE_SOURCE.get()
    return (message, *args) if source is None else ("%s: " + message, source, *args)


def _goal_reachable(space: StateSpace, goal: Sequence[Atom], tables) -> bool:
    from .features import goal_mask

    return bool(goal_mask(space, goal, tables).any())


class PlacementSample:
    """A seeded sample of placements of every object (distinct walkable cells), the initial state first:
    ``layout`` and ``positions`` ``[n, 1 + k, 2]`` as a StateSpace has them, for comparing goal masks
    where the reachable states are too many to list. It has no transitions."""

    def __init__(self, state: State, positions: np.ndarray) -> None:
        self.layout = state.layout
        self.initial = state
        self.positions = positions

    @property
    def num_states(self) -> int:
        return len(self.positions)

    def __repr__(self) -> str:
        return f"PlacementSample({self.num_states} placements)"


def placement_sample(state: State, count: int = 1 << 14, seed: int = 0) -> PlacementSample:
    """``count`` placements drawn uniformly (objects on distinct walkable cells), ``state``'s first.

    Two goals whose masks agree on every sampled placement are taken to hold in the same states; a PF
    that holds on one cell in ``W`` is missed by all ``count`` draws with probability ``(1 - 1/W)**count``
    (about e^-80 for 200 cells at the default count).
    """
    cells = np.argwhere(state.layout.walkable).astype(np.int16)  # [W, 2]
    objects = 1 + len(state.toys)
    rng = np.random.default_rng(seed)
    rows: list[np.ndarray] = [np.zeros((0, objects), dtype=np.int64)]
    have = 0
    while objects <= len(cells) and have < count - 1:
        draw = rng.integers(0, len(cells), size=(2 * count, objects))
        ordered = np.sort(draw, axis=1)
        distinct = draw[(np.diff(ordered, axis=1) != 0).all(axis=1)]  # rows with no shared cell
        rows.append(distinct)
        have += len(distinct)
    picked = np.concatenate(rows)[: count - 1]
    positions = np.concatenate([state.positions.astype(np.int16)[None], cells[picked]])
    return PlacementSample(state, positions)
