"""One demonstration's behaviour likelihood under many goals without the whole world's state space.

Where the whole world is too large, a goal is scored in a relevance abstraction
(:mod:`groundlang.model.relevance`): the agent, the toys the goal names and the toys the demonstration
moves move, every other toy is a wall. When the goal names a toy the demonstration leaves alone
and the demonstration moves another, that abstraction keeps both and is as large as the whole
world of those toys. This module scores such a goal *stepwise* instead, in a state space grown only
around the demonstration: the toys the demonstration moves but the goal does not name (the
*carried* toys) stand only where the demonstration puts them. For every distinct placement of the
carried toys that the demonstration visits, the abstraction of the agent and the named toys is
built with the carried toys as walls at that placement; the spaces are joined into one MDP in which
a move that pushes a carried toy leads to the pushed state in the space of the pushed placement
when the demonstration visits that placement. The demonstration's own pushes are therefore real
moves of the joined MDP, and its policy at every demonstration state is the soft-max policy of that
MDP's solution.

Boundary: a push that would put a carried toy where the demonstration never has it is blocked (the
state stays), as a move into scenery is in any relevance abstraction. Values of goals whose plans
would push a carried toy elsewhere are thus pessimistic. The goals the demonstration pursues name
the toys it moves, so those are scored in the ordinary abstraction; the stepwise goals are the
unpursued ones (agreement with exact: README, "Worlds too large to enumerate").

Which of the two is used per goal is decided by their sizes' bounds (the stepwise one counts one
space per placement); below STEPWISE_MIN_STATES the ordinary abstraction is always used. All the
spaces of one demonstration are solved together, one sweep over the disjoint union of those not yet
converged (:mod:`groundlang.inference.disjoint`): one compiled sweep loop rather than many small
ones, and each space stops when it alone would.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np
import torch

from groundlang.inference.disjoint import solve_blocks
from groundlang.inference.planning import TaskSettings
from groundlang.model.features import goal_mask
from groundlang.model.relevance import (abstract_space_uncached, abstraction_bound, announce, relevant_toys,
                                        state_space_for)
from groundlang.model.state_search import count_text, max_states_given
from groundlang.model.statespace import state_count_bound, trajectory_indices
from groundlang.model.world import ACTION_DELTAS

__all__ = ["approximate_likelihoods", "successor_positions"]

logger = logging.getLogger(__name__)

# Below this bound the one abstraction of every toy involved is cheap enough that stepwise (whose
# blocked pushes change the values of goals whose plans would push a carried toy) is not worth its error.
STEPWISE_MIN_STATES = 100_000
# The disjoint union solved at once is split into batches of at most this many states (memory bound).
BATCH_STATES = 4_000_000


def successor_positions(walkable: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """``[n, 4, m, 2]``: the positions after each move from ``positions`` ``[n, m, 2]`` (agent first),
    Sokoban pushes among these ``m`` objects on the cells ``walkable`` ``[width, height]``; a blocked
    move leaves the state as it is."""
    pos = np.asarray(positions, dtype=np.int64)
    n, m = pos.shape[:2]
    w, h = walkable.shape
    out = np.repeat(pos[:, None], 4, axis=1)  # [n, 4, m, 2]

    def free(cells):  # [..., 2] -> walkable and inside
        x, y = cells[..., 0], cells[..., 1]
        inside = (x >= 0) & (x < w) & (y >= 0) & (y < h)
        return inside & walkable[np.clip(x, 0, w - 1), np.clip(y, 0, h - 1)]

    target = pos[:, None, 0] + ACTION_DELTAS[None]  # [n, 4, 2]
    beyond = target + ACTION_DELTAS[None]
    at_target = (pos[:, None, 1:] == target[:, :, None]).all(axis=3)  # [n, 4, m - 1]
    at_beyond = (pos[:, None, 1:] == beyond[:, :, None]).all(axis=3).any(axis=2)  # [n, 4]
    pushing = at_target.any(axis=2)
    moves = free(target) & (~pushing | (free(beyond) & ~at_beyond))
    out[:, :, 0] = np.where(moves[..., None], target, pos[:, None, 0])
    pushed = at_target & moves[..., None]  # [n, 4, m - 1]
    out[:, :, 1:] = np.where(pushed[..., None], beyond[:, :, None], out[:, :, 1:])
    return out


class _Stepwise:
    """The states of the agent and a goal's named toys with the carried toys at any of the placements a
    demonstration needs, as one MDP: one abstraction per placement (more when a placement splits the
    world), concatenated, and a move that pushes a carried toy leads into the space of the pushed
    placement when that is one of them (else it is blocked, as scenery is). Quacks like a StateSpace
    for goal masks: ``layout``, ``positions`` ``[N, 1 + k, 2]``, ``next_state`` ``[N, 4]``."""

    def __init__(self, initial, named: tuple[int, ...], carried: tuple[int, ...], needed: np.ndarray,
                 walkable: np.ndarray, objects: list[int], max_states: int) -> None:
        self.layout = initial.layout
        cols = [1 + i for i in carried]
        configs = needed[:, cols].reshape(len(needed), -1)  # [N, 2c] placement of the carried toys
        _, group = np.unique(configs, axis=0, return_inverse=True)
        group = group.ravel()
        self.placements = int(group.max()) + 1
        spaces: list = []
        where = np.full((len(needed), 2), -1, dtype=np.int64)  # (space number, index) per needed state
        for g in range(self.placements):
            rows = np.flatnonzero(group == g)
            while len(rows):  # a placement may split the world: a new space from the first unfound state
                start = initial.with_positions(needed[rows[0]].astype(initial.positions.dtype))
                space = abstract_space_uncached(start, named, max_states)
                index = space.indices_of(needed[rows])
                found = index >= 0
                where[rows[found]] = np.stack([np.full(found.sum(), len(spaces)), index[found]], axis=1)
                spaces.append(space)
                rows = rows[~found]
        offsets = np.cumsum([0] + [sp.num_states for sp in spaces])
        self.spaces = spaces
        self.indices = offsets[where[:, 0]] + where[:, 1]  # [N] each needed state in the union
        self.positions = np.concatenate([sp.positions for sp in spaces])
        self.next_state = np.concatenate([sp.next_state.astype(np.int64) + o for sp, o in zip(spaces, offsets)])
        # pushes of a carried toy: from a blocked move to the pushed state, where some space holds it;
        # only states with the agent next to a carried toy can push one
        agent = self.positions[:, 0].astype(np.int64)
        near = (np.abs(self.positions[:, cols].astype(np.int64) - agent[:, None]).sum(axis=2) == 1).any(axis=1)
        rows = np.flatnonzero(near)
        after = successor_positions(walkable, self.positions[rows][:, objects])  # [n, 4, m, 2]
        carried_at = [objects.index(c) for c in cols]
        pushed = (after[:, :, carried_at] != self.positions[rows][:, None, cols]).any(axis=(2, 3))  # [n, 4]
        r, a = np.nonzero(pushed)
        s = rows[r]
        target = self.positions[s].astype(np.int64)
        target[:, objects] = after[r, a]
        for number, sp in enumerate(spaces):
            index = sp.indices_of(target)
            hit = index >= 0
            self.next_state[s[hit], a[hit]] = offsets[number] + index[hit]

    @property
    def num_states(self) -> int:
        return len(self.next_state)


def approximate_likelihoods(initial, goals: Sequence[tuple], states: Sequence, actions: Sequence[int], tables,
                            settings: TaskSettings = TaskSettings(), max_states: int | None = None) -> np.ndarray:
    """``[G]`` float64: log P(demonstration | goal) for each of ``goals`` (tuples of Atoms), each in its
    relevance abstraction or stepwise (module docstring), whichever is bounded smaller; ``states`` are
    the demonstration's States (first = ``initial``), ``actions`` its moves. StateSpaceError (one line)
    when a goal fits neither under ``max_states``."""
    max_states = max_states_given(max_states)
    actions = np.asarray([int(a) for a in actions], dtype=np.int64)
    demo = np.stack([s.positions for s in states]).astype(np.int64)  # [T + 1, 1 + k, 2]
    moved = relevant_toys(initial, (), [states])
    plans: list = []  # per goal: ("whole" or "steps", space, goal mask)
    stepwise: dict = {}  # (named, carried) -> _Stepwise, shared by the goals naming the same toys
    for goal in goals:
        named = relevant_toys(initial, goal)
        carried = tuple(i for i in moved if i not in named)
        whole = abstraction_bound(initial, tuple(sorted(set(named) | set(moved))))
        plan = None
        # by bounds: the placements' spaces together (at most max_states) against the one space of every
        # toy involved; counted before any is built
        if carried and whole > STEPWISE_MIN_STATES:
            size = _placements(demo, carried) * abstraction_bound(initial, named)
            if size < whole and size <= max_states:
                if (named, carried) not in stepwise:
                    stepwise[named, carried] = _stepwise_spaces(initial, named, carried, demo, max_states)
                held = stepwise[named, carried]
                mask = goal_mask(held, goal, tables)
                # out of reach with the carried toys where the demonstration has them: the one space may reach it
                plan = None if whole <= max_states and not mask.any() else ("steps", held, mask)
        if plan is None:
            space = state_space_for(initial, goal, [states], tables=tables, max_states=max_states,
                                    method="abstraction")
            plan = ("whole", space, goal_mask(space, goal, tables))
        plans.append(plan)
    # every (goal, space) solved as blocks of one disjoint union
    blocks = [(space, mask) for _, space, mask in plans]
    used_steps = sum(kind == "steps" for kind, _, _ in plans)
    exact = state_count_bound(int(initial.layout.walkable.sum()), len(initial.toys))
    announce(initial.layout, max_states, "behaviour likelihoods: approximate (the whole layout up to %s states, %s "
             "max_states=%s): %d goal(s) stepwise (toys the demonstration moves and the goal does not name at "
             "the placements it needs), %d in a relevance abstraction; %s states solved together", count_text(exact),
             ">" if exact > max_states else "<=", f"{max_states:,}", used_steps, len(goals) - used_steps,
             f"{sum(s.num_states for s, _ in blocks):,}")
    # the demonstration's states in each block: the only rows of the policy its likelihood reads
    paths = [trajectory_indices(space, list(states)) if kind == "whole" else space.indices for kind, space, _ in plans]
    log_policy = _solve_blocks(blocks, settings, paths)  # [sum of path lengths, 5]
    out = np.empty(len(goals))
    start = 0
    moves = torch.as_tensor(actions)
    for g, path in enumerate(paths):
        rows = log_policy[start:start + len(path)]
        start += len(path)
        out[g] = float(rows[torch.arange(len(path) - 1), moves].sum() + rows[-1, 4])
    return out


def _placements(demo: np.ndarray, toys: Sequence[int]) -> int:
    """How many distinct placements of ``toys`` the demonstration ``[T + 1, 1 + k, 2]`` visits."""
    cols = [1 + i for i in toys]
    return len(np.unique(demo[:, cols].reshape(len(demo), -1), axis=0))


def _stepwise_spaces(initial, named, carried, demo, max_states) -> _Stepwise:
    """The union over the placements of the carried toys the demonstration ``[T + 1, 1 + k, 2]`` visits;
    the toys neither moved nor named are walls."""
    objects = [0] + [1 + i for i in sorted(set(named) | set(carried))]
    walkable = initial.layout.walkable.copy()
    still = [j for j in range(1, demo.shape[1]) if j not in objects]
    walkable[demo[0, still, 0], demo[0, still, 1]] = False
    return _Stepwise(initial, named, carried, demo, walkable, objects, max_states)


def _solve_blocks(blocks, settings: TaskSettings, paths):
    """Solve every ``(space, mask)`` (:func:`solve_blocks`: one sweep over the union of those still
    unconverged), in batches of at most BATCH_STATES states; returns the log-policy at each block's
    ``paths`` states, stacked in block order ``[sum of path lengths, 5]``."""
    parts: list = []
    batch: list = []

    def flush():
        parts.extend(solve_blocks([(blocks[b][0].next_state, blocks[b][1]) for b in batch], settings,
                                  [paths[b] for b in batch]))
        batch.clear()

    total = 0
    for b, (space, _) in enumerate(blocks):
        if batch and total + space.num_states > BATCH_STATES:
            flush()
            total = 0
        batch.append(b)
        total += space.num_states
    if batch:
        flush()
    return torch.cat(parts)
