"""One demonstration's behaviour likelihood under many goals without the whole world's state space.

Where the whole world is too large, a goal is scored in a relevance abstraction
(:mod:`groundlang.model.relevance`): the agent, the toys the goal names and the toys the demonstration
moves move, every other toy is a wall. When the goal names a toy the demonstration leaves alone
and the demonstration moves another, that abstraction keeps both and is as large as the whole
world of those toys. This module scores such a goal *stepwise* instead: the toys the demonstration
moves but the goal does not name (the *carried* toys) are walls too, fixed where the demonstration
has them at each step. For every distinct placement of the carried toys the demonstration visits
(and every placement one push away from a visited state), the goal is solved in the abstraction
of the agent and the named toys with the carried toys as walls there. At a demonstration state,
the four moves are looked up in the real dynamics: a move that pushes a carried toy reads the
value of the pushed state in the space of the pushed placement, the others in the step's own
space, and the policy at the state is the soft-max of those Q-values and the terminate action,
as :func:`groundlang.inference.sweeps.policy_from_carry` forms it from a solved space.

What it loses: within one placement's space, a plan cannot push the carried toy again later
(such a move is blocked there, as scenery is in any abstraction), so values of goals whose best
plan moves a carried toy are pessimistic. The goals the demonstration pursues name the toys it
moves, so those are scored in the ordinary abstraction; the stepwise goals are the unpursued ones.

Which of the two is used per goal is decided by their sizes' bounds (the stepwise one counts one
space per placement). All the spaces of one demonstration are solved together in one soft value
iteration over their disjoint union (a block-diagonal MDP): one compiled sweep loop rather than
many small ones.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np
import torch

from groundlang.inference.planning import TaskSettings, solve_task, task_rewards
from groundlang.model.features import goal_mask
from groundlang.model.state_search import default_max_states
from groundlang.model.relevance import (abstract_space_uncached, abstraction_bound, announce, relevant_toys,
                                        state_space_for)
from groundlang.model.statespace import StateSpaceError, state_count_bound, trajectory_indices
from groundlang.model.world import ACTION_DELTAS

__all__ = ["approximate_likelihoods", "successor_positions"]

logger = logging.getLogger(__name__)

# Below this bound the one abstraction of every toy involved is cheap enough that stepwise (pessimistic
# for goals whose plans would push a carried toy) is not worth its error.
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
    """The spaces of one goal's named toys, one (or more, when a placement splits the world) per
    placement of the carried toys; ``lookup`` finds each needed state in them."""

    def __init__(self, initial, named: tuple[int, ...], carried: tuple[int, ...], needed: np.ndarray,
                 max_states: int) -> None:
        self.named, self.carried = named, carried
        cols = [1 + i for i in carried]
        configs = needed[:, cols].reshape(len(needed), -1)  # [N, 2c] placement of the carried toys
        _, group = np.unique(configs, axis=0, return_inverse=True)
        group = group.ravel()
        self.placements = int(group.max()) + 1
        self.spaces: list = []
        self.where = np.full((len(needed), 2), -1, dtype=np.int64)  # (space number, index) per needed state
        for g in range(int(group.max()) + 1):
            rows = np.flatnonzero(group == g)
            while len(rows):  # a placement may split the world: a new space from the first unfound state
                space = abstract_space_uncached(initial.with_positions(needed[rows[0]].astype(initial.positions.dtype)),
                                                named, max_states)
                index = space.indices_of(needed[rows])
                found = index >= 0
                self.where[rows[found]] = np.stack([np.full(found.sum(), len(self.spaces)), index[found]], axis=1)
                self.spaces.append(space)
                rows = rows[~found]

    @property
    def num_states(self) -> int:
        return sum(s.num_states for s in self.spaces)


def approximate_likelihoods(initial, goals: Sequence[tuple], states: Sequence, actions: Sequence[int], tables,
                            settings: TaskSettings = TaskSettings(), max_states: int | None = None) -> np.ndarray:
    """``[G]`` float64: log P(demonstration | goal) for each of ``goals`` (tuples of Atoms), each in its
    relevance abstraction or stepwise (module docstring), whichever is bounded smaller; ``states`` are
    the demonstration's States (first = ``initial``), ``actions`` its moves. StateSpaceError (one line)
    when a goal fits neither under ``max_states``."""
    max_states = default_max_states() if max_states is None else max_states
    actions = np.asarray([int(a) for a in actions], dtype=np.int64)
    demo = np.stack([s.positions for s in states]).astype(np.int64)  # [T + 1, 1 + k, 2]
    moved = relevant_toys(initial, (), [states])
    plans: list = []  # per goal: ("whole", space) or ("steps", _Stepwise)
    stepwise: dict = {}  # (named, carried) -> _Stepwise, shared by the goals naming the same toys
    for goal in goals:
        named = relevant_toys(initial, goal)
        carried = tuple(i for i in moved if i not in named)
        plan = None
        if carried and abstraction_bound(initial, tuple(sorted(set(named) | set(moved)))) > STEPWISE_MIN_STATES \
                and abstraction_bound(initial, named) <= max_states:
            key = (named, carried)
            if key not in stepwise:
                stepwise[key] = _stepwise_spaces(initial, named, carried, demo, max_states)
            held = stepwise[key]
            whole = abstraction_bound(initial, tuple(sorted(set(named) | set(moved))))
            # by bounds: the placements' spaces together against the one space of every toy involved
            if whole > STEPWISE_MIN_STATES and held.placements * abstraction_bound(initial, named) < whole:
                plan = ("steps", held)
                if whole <= max_states and not any(goal_mask(s, goal, tables).any() for s in held.spaces):
                    plan = None  # out of reach with the carried toys as walls: the one space may reach it
        plans.append(plan or ("whole", state_space_for(initial, goal, [states], tables=tables,
                                                        max_states=max_states, method="abstraction")))
    # every (space, goal) to solve, as blocks of one disjoint union
    blocks: list = []  # (space, mask)
    first: list[int] = []  # per goal: its first block
    for goal, (kind, held) in zip(goals, plans):
        first.append(len(blocks))
        spaces = [held] if kind == "whole" else held.spaces
        blocks.extend((space, goal_mask(space, goal, tables)) for space in spaces)
    used_steps = sum(kind == "steps" for kind, _ in plans)
    exact = state_count_bound(int(initial.layout.walkable.sum()), len(initial.toys))
    announce(initial.layout, max_states, "behaviour likelihoods: approximate (the whole layout up to %s states, %s "
             "max_states=%s): %d goal(s) stepwise (toys the demonstration moves and the goal does not name fixed "
             "per step), %d in a relevance abstraction; %d spaces, %s states solved together", f"{exact:,}",
             ">" if exact > max_states else "<=", f"{max_states:,}", used_steps, len(goals) - used_steps,
             len(blocks), f"{sum(s.num_states for s, _ in blocks):,}")
    values, log_policy, reward, stop = _solve_blocks(blocks, settings)
    offsets = np.cumsum([0] + [s.num_states for s, _ in blocks])
    out = np.empty(len(goals))
    for g, (kind, held) in enumerate(plans):
        base = first[g]
        if kind == "whole":
            path = offsets[base] + trajectory_indices(held, list(states))
            lp = log_policy[path[:-1], actions].sum() + log_policy[path[-1], 4]
        else:
            lp = _stepwise_log_likelihood(held, offsets[base:], values, reward, stop, actions, settings)
        out[g] = float(lp)
    return out


def _stepwise_spaces(initial, named, carried, demo, max_states) -> _Stepwise:
    """The spaces holding every demonstration state and every state one move from it (real dynamics
    with the unmoved, unnamed toys as walls)."""
    objects = [0] + [1 + i for i in sorted(set(named) | set(carried))]
    walkable = initial.layout.walkable.copy()
    still = [j for j in range(1, demo.shape[1]) if j not in objects]
    walkable[demo[0, still, 0], demo[0, still, 1]] = False
    after = successor_positions(walkable, demo[:, objects])  # [T + 1, 4, m, 2]
    needed = np.repeat(demo[:, None], 5, axis=1)  # [T + 1, 5, 1 + k, 2]: the state, then its four successors
    needed[:, 1:, objects] = after
    return _Stepwise(initial, named, carried, needed.reshape(-1, *demo.shape[1:]), max_states)


def _stepwise_log_likelihood(held: _Stepwise, offsets, values, reward, stop, actions, settings) -> torch.Tensor:
    """The demonstration's log-likelihood with each state's policy formed from its successors' values."""
    where = held.where.reshape(-1, 5, 2)  # [T + 1, 5, (space, index)]
    flat = torch.as_tensor(offsets[where[..., 0]] + where[..., 1])  # [T + 1, 5] into the union
    q = reward[flat[:, 1:]] + settings.discount * values[flat[:, 1:]]  # [T + 1, 4]
    q = torch.cat([q, stop[flat[:, 0]][:, None]], dim=1)  # terminate last
    temperature = settings.temperature
    log_policy = (q - temperature * torch.logsumexp(q / temperature, dim=1, keepdim=True)) / temperature
    steps = torch.arange(len(actions))
    return log_policy[steps, torch.as_tensor(actions)].sum() + log_policy[-1, 4]


def _solve_blocks(blocks, settings: TaskSettings):
    """Solve every ``(space, mask)`` as one MDP, their disjoint union, in batches of at most
    BATCH_STATES states; returns ``(values, log_policy, arrival reward, stop reward)`` over the union."""
    if settings.absorbing_goal:
        raise StateSpaceError("stepwise likelihoods need goals that do not absorb (absorbing_goal=false)")
    parts: list = [[], [], [], []]
    batch: list = []

    def flush():
        sizes = [s.num_states for s, _ in batch]
        offsets = np.cumsum([0] + sizes[:-1])
        union = np.concatenate([s.next_state.astype(np.int64) + o for (s, _), o in zip(batch, offsets)])
        mask = np.concatenate([m for _, m in batch])
        result = solve_task(union, mask, settings)
        if not result.converged:
            logger.warning("soft value iteration stopped after %d sweeps (residual %.3g)", result.sweeps,
                           result.residual)
        reward, stop, _ = task_rewards(mask, settings)
        for part, value in zip(parts, (result.values, result.log_policy, reward, stop)):
            part.append(value)
        batch.clear()

    total = 0
    for block in blocks:
        if batch and total + block[0].num_states > BATCH_STATES:
            flush()
            total = 0
        batch.append(block)
        total += block[0].num_states
    if batch:
        flush()
    return tuple(torch.cat(p) for p in parts)
