"""Breadth-first search over packed state keys: the array kernel behind :mod:`groundlang.model.statespace`.

A state's dynamic part (the agent's cell, then each toy's cell) is encoded as
one int64 key over the layout's walkable cells: ``key = sum_j cell_j * W**j``
with ``W`` walkable cells and ``j = 0`` the agent. The search expands a whole
frontier at once: successor keys for all frontier states and all four actions
come from array operations on a per-cell neighbour table, so there is no
Python loop over states. Seen keys are tracked in a dense index map when the
key space ``W**(1+k)`` is small enough, and in a sorted key array otherwise.
:mod:`groundlang.model.relevance` runs the same search on the toys a goal moves.
"""

from __future__ import annotations

import logging
import math
import numbers
import os
import re
from collections.abc import Sequence

import numpy as np

from groundlang.model.world import ACTION_DELTAS

__all__ = ["StateSpaceError", "DEFAULT_MAX_STATES", "MAX_STATES_VARIABLE", "default_max_states", "max_states_given",
           "StateKeyError", "describe_positions", "key_powers", "search", "state_count_bound", "too_many_states"]

logger = logging.getLogger(__name__)

NUM_ACTIONS = len(ACTION_DELTAS)

# Largest key space (entries) for which the search keeps a dense int32 index
# map (4 bytes per entry, so at most 128 MiB); beyond it, sorted keys.
DENSE_KEY_LIMIT = 1 << 25

# Default refusal threshold of enumerate_states; users of the CLI raise it
# with this environment variable (library callers pass max_states). The bound it
# is checked against counts every placement of distinct cells, far above what a
# walled layout reaches: an 8x8 grid of three rooms with three blocks is bounded
# by 2.4 million and reaches a few tens of thousands, so the default admits it.
DEFAULT_MAX_STATES = 5_000_000
MAX_STATES_VARIABLE = "GROUNDLANG_MAX_STATES"


# The tables of an enumerated space take at least this many bytes a state (its keys, positions and next
# states: measured 32 and 36 on two corpus layouts); enumerating and planning in it take more.
SPACE_BYTES_PER_STATE = 36


def _check_fits_memory(max_states, said: str) -> None:
    """StateSpaceError where ``max_states`` states' tables alone could not fit in this machine's memory: such
    a bound is no limit (a run given 2,000,000,000 had grown past 6 GB before anything was refused)."""
    try:
        memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):  # a system that does not say: nothing to check against
        return
    if max_states * SPACE_BYTES_PER_STATE > memory:
        raise StateSpaceError(f"{said}: a space that large needs at least {SPACE_BYTES_PER_STATE} bytes a state for its "
                              f"tables alone, more than this machine's {memory / 2**30:.0f} GiB hold; at most "
                              f"{memory // SPACE_BYTES_PER_STATE:,}")


def default_max_states() -> int:
    """``$GROUNDLANG_MAX_STATES`` when set (a positive integer), else DEFAULT_MAX_STATES."""
    given = os.environ.get(MAX_STATES_VARIABLE, "").strip()
    if not given:
        return DEFAULT_MAX_STATES
    # ASCII digits, grouped as "1_000_000" or "1,000,000" if at all ("1,2,3" is no number; "²" is a digit to
    # str.isdigit, not to int)
    if not re.fullmatch(r"[0-9]+|[0-9]{1,3}(,[0-9]{3})+|[0-9]+(_[0-9]+)+", given) or int(given.replace(",", "")) < 1:
        raise StateSpaceError(f"{MAX_STATES_VARIABLE}={os.environ[MAX_STATES_VARIABLE]!r}: expected a positive integer")
    bound = int(given.replace(",", ""))
    _check_fits_memory(bound, f"{MAX_STATES_VARIABLE}={os.environ[MAX_STATES_VARIABLE]!r}")
    return bound


def max_states_given(max_states) -> int | float:
    """``max_states`` where given (a positive number), else :func:`default_max_states`: TypeError for a bool or
    a non-number, ValueError for nan or a bound below 1 (nan compared false with every count, so it had
    meant "no limit" in one check and "none fits" in the next)."""
    if max_states is None:
        return default_max_states()
    if isinstance(max_states, bool) or not isinstance(max_states, numbers.Real):
        raise TypeError(f"max_states must be a positive number of states, not {type(max_states).__name__}")
    if not max_states >= 1:
        raise ValueError(f"max_states={max_states!r}: expected a positive number of states")
    _check_fits_memory(max_states, f"max_states={max_states!r}")
    return max_states


class StateSpaceError(ValueError):
    """A state space that cannot be built, or a state that is not in it."""


class StateKeyError(StateSpaceError):
    """Too many moving objects for a state's key to fit in 64 bits: a space too large to build."""


def describe_positions(positions: np.ndarray) -> str:
    """``agent0@(4,2) block0@(2,2)`` for error messages."""
    pos = np.asarray(positions)
    names = ["agent0"] + [f"block{i}" for i in range(len(pos) - 1)]
    return " ".join(f"{n}@({int(p[0])},{int(p[1])})" for n, p in zip(names, pos))


def key_powers(base: int, count: int) -> np.ndarray:
    """The place values of a state's key: ``count`` positions, each one of ``base`` cells, as one int64.
    StateKeyError when the keys would not fit in 64 bits (too many moving objects for the cells)."""
    largest = int(np.iinfo(np.int64).max)
    if count > 1 and base ** count > largest:
        fits = count - 1
        while base ** fits > largest:
            fits -= 1
        raise StateKeyError(f"{count} moving objects in a layout of {base} cells: its states cannot be keyed "
                              f"in 64 bits (at most {fits} objects with the agent)")
    return np.array([base**j for j in range(count)], dtype=np.int64)


def _neighbour_table(walkable: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Walkable cells and their neighbours.

    Returns ``(cell_xy [W, 2], cell_of [width, height] int64 (-1 off cells),
    neighbour [W + 1, 4] int64)``; ``W`` is the sentinel "no cell", and the
    sentinel's own neighbours are the sentinel, so two-step look-ups need no
    special case.
    """
    cell_xy = np.argwhere(walkable).astype(np.int64)
    count = len(cell_xy)
    width, height = walkable.shape
    cell_of = np.full(walkable.shape, -1, dtype=np.int64)
    cell_of[cell_xy[:, 0], cell_xy[:, 1]] = np.arange(count)
    neighbour = np.full((count + 1, NUM_ACTIONS), count, dtype=np.int64)
    for a, (dx, dy) in enumerate(ACTION_DELTAS):
        x, y = cell_xy[:, 0] + dx, cell_xy[:, 1] + dy
        inside = (x >= 0) & (x < width) & (y >= 0) & (y < height)
        target = np.full(count, -1, dtype=np.int64)
        target[inside] = cell_of[x[inside], y[inside]]
        neighbour[:count, a] = np.where(target >= 0, target, count)
    return cell_xy, cell_of, neighbour


def _initial_cells(pos: np.ndarray, names: Sequence[str], cell_of: np.ndarray) -> np.ndarray:
    """Cells of the objects at ``pos`` ``[m, 2]``; StateSpaceError when one is off the walkable cells."""
    width, height = cell_of.shape
    cells = []
    for name, (x, y) in zip(names, pos):
        if not (0 <= x < width and 0 <= y < height) or cell_of[x, y] < 0:
            raise StateSpaceError(
                f"initial state {describe_positions(pos)}: {name} at ({x},{y}) is inside a wall "
                "or outside every room"
            )
        cells.append(int(cell_of[x, y]))
    if len(set(cells)) != len(cells):
        raise StateSpaceError(f"initial state {describe_positions(pos)}: two objects share a cell")
    return np.array(cells, dtype=np.int64)


def state_count_bound(num_cells: int, num_toys: int) -> int:
    """Upper bound on reachable states: distinct cells for the agent and each (named) toy."""
    return math.perm(num_cells, num_toys + 1) if num_cells >= num_toys + 1 else 0


def count_text(n: int) -> str:
    """``n`` for a message: with thousands separators, or as a power of ten past 10^15 (a layout of a thousand
    toys bounds its states by a number of thousands of digits, more than a line should hold or Python
    converts to text)."""
    if n < 10**15:
        return f"{n:,}"
    return f"about 10^{int(n.bit_length() * math.log10(2))}"


def _pair_tables(neighbour: np.ndarray, powers: np.ndarray, dtype: type) -> list[np.ndarray]:
    """Per-toy transition tables indexed by (agent cell, toy cell) pairs, ``[W * W, 4]``.

    The successor of a state is ``key + (sum_i T_i[agent + W * toy_i] >> 2)``
    unless the pushed toy would land on another toy. Each entry packs a key
    displacement (times 4) with two flag bits: 1 when toy i is at the agent's
    target cell, 2 when it is at the cell beyond. No toy has both and at most
    one toy has each, so the flags of all toys sum to 3 exactly when a push is
    blocked by another toy. T_1 also carries the agent's own move; a toy
    pushed into a wall cancels it. With no toys, the table is indexed by the
    agent's cell alone.
    """
    sentinel = neighbour.shape[0] - 1
    cells = np.arange(sentinel)
    target = neighbour[:sentinel]  # [W, 4]
    beyond = neighbour[target, np.arange(NUM_ACTIONS)]  # [W, 4]
    agent_move = np.where(target != sentinel, (target - cells[:, None]) * powers[0], 0)
    if len(powers) == 1:
        return [(agent_move * 4).astype(dtype)]
    tables = []
    toy = cells[:, None, None]  # pair index = agent + W * toy: toy is the slow axis
    for i in range(1, len(powers)):
        at_target = toy == target[None]  # [W(toy), W(agent), 4]
        at_beyond = toy == beyond[None]
        push = np.where(beyond == sentinel, -agent_move, (beyond - target) * powers[i])
        delta = np.where(at_target, push[None], 0) + (agent_move[None] if i == 1 else 0)
        packed = delta * 4 + at_target + 2 * at_beyond
        tables.append(packed.reshape(-1, NUM_ACTIONS).astype(dtype))
    return tables


def too_many_states(bound: int, num_cells: int, num_toys: int, max_states: int) -> str:
    return (f"this layout could reach up to {count_text(bound)} states ({num_cells} walkable cells, "
            f"{num_toys} toy(s)), more than max_states={max_states:,}; "
            f"pass max_states={count_text(bound)} (or more) to enumerate_states, or set "
            f"{MAX_STATES_VARIABLE}={bound} in the environment, to allow it")


def search(walkable: np.ndarray, start: np.ndarray, names: Sequence[str], max_states: int,
           dense: bool | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Breadth-first search over the cells ``walkable`` ``[width, height]`` of objects starting at ``start``
    ``[m, 2]`` (the pusher first); returns ``(next_state [S, 4] int32, positions [S, m, 2] int16,
    keys [S] int64, cell_of [width, height] int64, level_sizes [D] int64)``, states in breadth-first
    order, ``level_sizes[d]`` of them first reached after ``d`` moves."""
    cell_xy, cell_of, neighbour = _neighbour_table(walkable)
    num_cells = len(cell_xy)
    num_toys = len(start) - 1
    start_cells = _initial_cells(np.asarray(start), names, cell_of)
    bound = state_count_bound(num_cells, num_toys)
    if bound > max_states:
        raise StateSpaceError(too_many_states(bound, num_cells, num_toys, max_states))
    key_space = num_cells ** (1 + num_toys)
    if key_space >= 2**60:
        raise StateSpaceError(
            f"{num_cells} walkable cells and {num_toys} toys do not fit an int64 state key"
        )
    if dense is None:
        dense = key_space <= DENSE_KEY_LIMIT
    # int32 arithmetic is cheaper; the packed displacements need 2 spare bits.
    dtype = np.int32 if key_space < 2**28 else np.int64
    powers = key_powers(num_cells, 1 + num_toys)
    tables = _pair_tables(neighbour, powers, dtype)
    pair_space = num_cells * num_cells

    keys = (start_cells @ powers).astype(dtype)[None]
    level_keys = [keys]
    level_next: list[np.ndarray] = []
    count = 1
    if dense:
        index_map = np.full(key_space, -1, dtype=np.int32)
        index_map[keys] = 0
    else:
        seen_keys, seen_index = keys.copy(), np.zeros(1, dtype=np.int64)

    while len(keys):
        # Successor keys [n, 4] of the whole frontier. ``take`` and
        # ``compress`` rather than fancy indexing: the frontier arrays are
        # small, so per-call overhead dominates.
        if num_toys == 0:
            packed = tables[0].take(keys, axis=0)
        else:
            agent = keys - (keys // num_cells) * num_cells
            packed = tables[0].take(keys - (keys // pair_space) * pair_space, axis=0)
            for i in range(2, 1 + num_toys):
                toy = keys // powers[i]
                if i < num_toys:
                    toy -= (toy // num_cells) * num_cells
                packed += tables[i - 1].take(agent + num_cells * toy, axis=0)
        move = packed >> 2
        if num_toys >= 2:
            move[(packed & 3) == 3] = 0
        successor = (keys[:, None] + move).ravel()

        if dense:
            index = index_map.take(successor)
            fresh = successor.compress(index < 0)
            if len(fresh):
                # Dedupe without sorting everything: each fresh key writes a
                # distinct negative tag, the surviving tag marks one copy.
                tags = -2 - np.arange(len(fresh), dtype=np.int32)
                index_map[fresh] = tags
                new_keys = fresh.compress(index_map.take(fresh) == tags)
                new_keys.sort()
                index_map[new_keys] = np.arange(count, count + len(new_keys), dtype=np.int32)
                index = index_map.take(successor)
            else:
                new_keys = fresh
        else:
            at = np.searchsorted(seen_keys, successor)
            np.minimum(at, len(seen_keys) - 1, out=at)
            seen = seen_keys.take(at) == successor
            unseen = successor.compress(~seen)
            unseen.sort()
            new_keys = unseen.compress(np.diff(unseen, prepend=unseen[:1] - 1) != 0)
            index = np.empty(len(successor), dtype=np.int64)
            index[seen] = seen_index.take(at.compress(seen))
            index[~seen] = count + np.searchsorted(new_keys, successor.compress(~seen))
            where = np.searchsorted(seen_keys, new_keys)
            seen_keys = np.insert(seen_keys, where, new_keys)
            seen_index = np.insert(seen_index, where, np.arange(count, count + len(new_keys)))
        level_next.append(index.reshape(-1, NUM_ACTIONS))
        count += len(new_keys)
        keys = new_keys
        level_keys.append(keys)

    all_keys = np.concatenate(level_keys)
    next_state = np.concatenate(level_next).astype(np.int32, copy=False)
    positions = _decode(all_keys, num_cells, 1 + num_toys, cell_xy)
    logger.debug(
        "enumerated %d states in %d levels (%s key map)",
        count, len(level_next), "dense" if dense else "sorted",
    )
    sizes = np.array([len(k) for k in level_keys if len(k)], dtype=np.int64)
    return next_state, positions, all_keys.astype(np.int64), cell_of, sizes


def _decode(keys: np.ndarray, num_cells: int, num_objects: int, cell_xy: np.ndarray) -> np.ndarray:
    """Positions ``[S, num_objects, 2]`` int16 of state keys ``[S]``; cell_xy is ``[W, 2]``."""
    # Each (x, y) int16 pair gathered as one int32: half the gather calls.
    xy_pairs = np.ascontiguousarray(cell_xy, dtype=np.int16).view(np.int32).ravel()
    packed = np.empty((len(keys), num_objects), dtype=np.int32)
    rest = keys
    for j in range(num_objects):
        if j + 1 < num_objects:
            quotient = rest // num_cells
            packed[:, j] = xy_pairs.take(rest - quotient * num_cells)
            rest = quotient
        else:
            packed[:, j] = xy_pairs.take(rest)
    return packed.view(np.int16).reshape(len(keys), num_objects, 2)
