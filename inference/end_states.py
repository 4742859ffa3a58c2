"""The likelihood of an end state under a grounded task, for data that show no trajectory.

A corpus of (start, end) pairs (Williams et al. 2018) shows where the demonstrator stopped, not how it
got there. Under a grounded task ``g`` the demonstrator plans a shortest route to a state where ``g``
holds and stops there, so its end state is one of the *nearest* goal states of ``g`` (fewest moves
from the start). Pairs are noisy, so two more ways to end are allowed:

    P(end | g) = (1 - rho_goal - rho_any) * [end in N_g] / |N_g|
               + rho_goal * [end in G_g] / |G_g|
               + rho_any / |S|

with ``N_g`` the nearest goal states, ``G_g`` every goal state and ``S`` every state reachable from
the start. A goal true of the end state but reached the long way round still explains it, less well;
a goal the end state does not satisfy explains it only as noise. One breadth-first search per start
state gives every distance; a goal then costs one mask over the states (no value iteration).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence

import numpy as np

from groundlang.model.features import goal_mask
from groundlang.model.pf_tables import pf_tables
from groundlang.model.statespace import StateSpace, enumerate_states
from groundlang.model.world import Action

__all__ = ["EndStateNoise", "distances", "end_state_log_likelihood", "end_state_likelihood_table"]

logger = logging.getLogger(__name__)


class EndStateNoise:
    """The two noise weights of the end-state likelihood (see the module docstring)."""

    def __init__(self, goal: float = 0.1, anywhere: float = 0.01):
        if not (0 <= goal and 0 < anywhere and goal + anywhere < 1):
            raise ValueError(f"end-state noise: expected 0 <= goal, 0 < anywhere and goal + anywhere < 1; "
                             f"got goal={goal}, anywhere={anywhere}")
        self.goal = goal
        self.anywhere = anywhere

    def key(self) -> tuple[float, float]:
        return (self.goal, self.anywhere)


def distances(space: StateSpace, start: int = 0) -> np.ndarray:
    """``[S]`` int: the fewest moves from state ``start`` to each state (-1: unreachable), breadth-first
    a layer at a time, vectorised over the layer."""
    next_state = np.asarray(space.next_state)[:, : len(Action)]
    dist = np.full(space.num_states, -1, dtype=np.int64)
    dist[start] = 0
    frontier = np.array([start], dtype=np.int64)
    depth = 0
    while frontier.size:
        depth += 1
        successors = next_state[frontier].ravel()
        successors = successors[dist[successors] < 0]
        dist[successors] = depth
        frontier = np.unique(successors)
    return dist


def end_state_log_likelihood(dist: np.ndarray, end: int, masks: np.ndarray, noise: EndStateNoise) -> np.ndarray:
    """``[G]``: log P(end | g) for each goal mask (``masks`` ``[G, S]`` bool over the states)."""
    reachable = dist >= 0
    masks = masks & reachable[None, :]
    big = np.iinfo(np.int64).max
    nearest_dist = np.where(masks, dist[None, :], big).min(axis=1)  # [G]
    in_goal = masks[:, end]
    n_goal = masks.sum(axis=1)
    n_nearest = (masks & (dist[None, :] == nearest_dist[:, None])).sum(axis=1)
    is_nearest = in_goal & (dist[end] == nearest_dist)
    near = 1.0 - noise.goal - noise.anywhere
    with np.errstate(divide="ignore", invalid="ignore"):
        p = (near * np.where(is_nearest, 1.0 / np.maximum(n_nearest, 1), 0.0)
             + noise.goal * np.where(in_goal, 1.0 / np.maximum(n_goal, 1), 0.0)
             + noise.anywhere / int(reachable.sum()))
    return np.log(p)


def end_state_likelihood_table(instances: Sequence, goals: Sequence[Sequence[tuple]], program,
                               noise: EndStateNoise | None = None, max_states: int | None = None) -> list[np.ndarray]:
    """``table[i][k] = log P(end state of instances[i] | goals[i][k])``. Instances need
    ``initial_state`` and ``final_state`` in one layout; ``program`` is the task library's tabulation
    program (PF meanings). An end state not reachable from its start raises StateSpaceError."""
    noise = noise or EndStateNoise()
    table = []
    for inst, row in zip(instances, goals):
        space = enumerate_states(inst.initial_state, max_states=max_states)
        end = space.index_of(inst.final_state)
        dist = distances(space)
        tables = pf_tables(space.layout, program)
        masks = np.stack([goal_mask(space, g, tables) for g in row]) if row else np.zeros((0, space.num_states), bool)
        table.append(end_state_log_likelihood(dist, end, masks, noise))
    if table:
        logger.info("end-state likelihoods: %d pairs, %d goals", len(table), sum(len(r) for r in table))
    return table


def log_mean_exp(values: np.ndarray) -> float:
    """log of the mean of exp(values); -inf for no values."""
    if len(values) == 0:
        return -math.inf
    top = float(np.max(values))
    return top + math.log(float(np.mean(np.exp(np.asarray(values) - top))))
