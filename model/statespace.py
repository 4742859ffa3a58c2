"""Every state reachable from an initial state, with its deterministic transition table.

States are found by a breadth-first search over packed integer keys, a whole
frontier at a time (:mod:`groundlang.model.state_search`). The result is ``next_state[S, A]`` (gather-style transitions, as
soft value iteration wants them) and ``positions[S, 1+k, 2]``; index 0 is the
initial state.

The dynamics are those of :func:`groundlang.model.world.step`: moving into a
toy pushes it one cell on unless a wall or another toy is there, in which case
nothing moves.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property

import numpy as np

from groundlang.model.state_search import (
    DEFAULT_MAX_STATES,
    MAX_STATES_VARIABLE,
    StateSpaceError,
    default_max_states,
    max_states_given,
    describe_positions,
    key_powers,
    search,
    state_count_bound,
    too_many_states,
)
from groundlang.model.world import Layout, State

__all__ = ["StateSpace", "StateSpaceError", "check_state_count", "enumerate_states", "state_count_bound",
           "trajectory_indices", "DEFAULT_MAX_STATES", "MAX_STATES_VARIABLE", "default_max_states"]


class StateSpace:
    """The reachable states of one initial state, as arrays.

    States are numbered in breadth-first order: a state's index never precedes
    that of any state nearer the initial state (index 0).

    Attributes:
        layout: the static part shared by every state.
        initial: the initial state (index 0).
        next_state: ``[S, 4]`` int32, ``next_state[s, a]`` is the index reached
            from state ``s`` by action ``a`` (``Action`` order NORTH, SOUTH,
            EAST, WEST); blocked moves point back at ``s``.
        positions: ``[S, 1 + k, 2]`` int16, (x, y) of the agent then each toy.
        level_sizes: ``[D]`` the number of states first reached after 0, 1, ...
            moves (breadth-first levels), when the space was built that way; else None.
    """

    def __init__(
        self,
        initial: State,
        next_state: np.ndarray,
        positions: np.ndarray,
        keys: np.ndarray,
        cell_of: np.ndarray,
        level_sizes: np.ndarray | None = None,
    ) -> None:
        self.level_sizes = level_sizes
        self.layout: Layout = initial.layout
        self.initial = initial
        self.next_state = next_state
        self.positions = positions
        # keys[i] encodes state i; cell_of maps (x, y) to a walkable cell index or -1.
        self._keys = keys
        self._cell_of = cell_of
        self._powers = key_powers(int(cell_of.max()) + 1, positions.shape[1])

    @property
    def num_states(self) -> int:
        return int(self.next_state.shape[0])

    @property
    def num_toys(self) -> int:
        return int(self.positions.shape[1]) - 1

    @property
    def object_names(self) -> list[str]:
        """Names of the moving objects in ``positions`` order: agent0, block0, ..."""
        return ["agent0"] + self.layout.toy_names

    def __len__(self) -> int:
        return self.num_states

    def __repr__(self) -> str:
        return f"StateSpace({self.num_states} states, {self.num_toys} toy(s))"

    @cached_property
    def _sorted(self) -> tuple[np.ndarray, np.ndarray]:
        order = np.argsort(self._keys, kind="stable")
        return self._keys[order], order

    def state_at(self, index: int) -> State:
        """The State with index ``index`` (0 <= index < num_states)."""
        if not 0 <= index < self.num_states:
            raise StateSpaceError(f"state index {index} is outside 0..{self.num_states - 1}")
        return self.initial.with_positions(self.positions[index])

    def indices_of(self, positions: np.ndarray) -> np.ndarray:
        """Indices of many states given as positions ``[n, 1 + k, 2]``; -1 where unreachable."""
        pos = np.asarray(positions, dtype=np.int64)
        if pos.ndim != 3 or pos.shape[1:] != self.positions.shape[1:]:
            raise StateSpaceError(
                f"positions of shape {tuple(pos.shape)} do not match [n, {self.positions.shape[1]}, 2]"
            )
        return self._lookup(pos)

    def _lookup(self, pos: np.ndarray) -> np.ndarray:
        """Indices of the states whose encoded objects stand at ``pos`` ``[n, m, 2]``; -1 where unseen."""
        w, h = self._cell_of.shape
        x, y = pos[..., 0], pos[..., 1]
        on_grid = (x >= 0) & (x < w) & (y >= 0) & (y < h)
        cells = np.where(on_grid, self._cell_of[np.clip(x, 0, w - 1), np.clip(y, 0, h - 1)], -1)
        valid = (cells >= 0).all(axis=1)
        keys = np.where(valid, cells @ self._powers, -1)
        sorted_keys, order = self._sorted
        at = np.clip(np.searchsorted(sorted_keys, keys), 0, len(sorted_keys) - 1)
        found = valid & (sorted_keys[at] == keys)
        return np.where(found, order[at], -1)

    def index_of(self, state: State | np.ndarray) -> int:
        """Index of a State or a ``[1 + k, 2]`` positions array; StateSpaceError if unreachable."""
        if isinstance(state, State):
            if state.layout != self.layout:
                raise StateSpaceError(f"state {describe_positions(state.positions)} has a different layout")
            pos = state.positions
        else:
            pos = np.asarray(state)
        index = int(self.indices_of(pos[None])[0])
        if index < 0:
            raise StateSpaceError(
                f"state {describe_positions(pos)} is not reachable from the initial state "
                f"{describe_positions(self.positions[0])}"
            )
        return index


def check_state_count(state: State, max_states: int | None = None) -> int:
    """The bound :func:`enumerate_states` checks, from the count of walkable cells alone (milliseconds, even
    for a 1000 x 1000 room); raises the same StateSpaceError. Callers that do slow per-layout work first
    (grounding a layout's cells in clingo took 20 s there) ask this before it."""
    max_states = max_states_given(max_states)
    num_cells = int(np.count_nonzero(state.layout.walkable))
    bound = state_count_bound(num_cells, len(state.toys))
    if bound > max_states:
        raise StateSpaceError(too_many_states(bound, num_cells, len(state.toys), max_states))
    return bound


def enumerate_states(state: State, max_states: int | None = None) -> StateSpace:
    """Breadth-first enumeration of every state reachable from ``state``.

    Returns a StateSpace whose index 0 is ``state``. Raises StateSpaceError
    (a ValueError) when the initial state is invalid, or when the layout could
    hold more than ``max_states`` states (checked up front, from the number of
    walkable cells and toys; pass a larger ``max_states`` to allow it; the
    default is ``$GROUNDLANG_MAX_STATES`` or 5,000,000).
    """
    return _enumerate(state, max_states_given(max_states), dense=None)


def _enumerate(state: State, max_states: int, dense: bool | None) -> StateSpace:
    next_state, positions, keys, cell_of, sizes = search(
        state.layout.walkable, state.positions, state.layout.movable_names, max_states, dense)
    return StateSpace(state, next_state, positions, keys, cell_of, level_sizes=sizes)


def trajectory_indices(space: StateSpace, states: Sequence[State]) -> np.ndarray:
    """Indices ``[T]`` int64 of a demonstration's states; StateSpaceError naming the first missing step."""
    if not states:
        return np.zeros(0, dtype=np.int64)
    for t, s in enumerate(states):
        if s.layout != space.layout:
            raise StateSpaceError(f"step {t}: state {describe_positions(s.positions)} has a different layout")
    positions = np.stack([s.positions for s in states])
    index = space.indices_of(positions)
    missing = np.flatnonzero(index < 0)
    if len(missing):
        t = int(missing[0])
        raise StateSpaceError(
            f"step {t}: state {describe_positions(positions[t])} is not reachable from the initial state "
            f"{describe_positions(space.positions[0])}"
        )
    return index.astype(np.int64)
