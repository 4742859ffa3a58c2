"""The likelihood of an end state under a grounded task, for data that show no trajectory.

A corpus of (start, end) pairs (Williams et al. 2018) shows where the demonstrator stopped, not how it
got there. Under a grounded task ``g`` the demonstrator heads for the states where ``g`` holds and
stops in one; the farther a goal state is beyond the nearest one, the less likely it stops there
(it walks a step or two into a room, seldom across it):

    P(end | g) = (1 - rho) * [end in G_g] * exp(-beta * (d(end) - d_g)) / Z_g  +  rho / |S|

with ``d`` the fewest moves from the start, ``G_g`` the goal states of ``g``, ``d_g`` the nearest of
them, ``Z_g`` the sum of ``exp(-beta * (d(s) - d_g))`` over ``G_g`` and ``S`` every state reachable
from the start: a goal the end state does not satisfy explains it only as noise (weight ``rho``).
``beta = 0`` is uniform over the goal states, ``beta -> inf`` the nearest ones only. One breadth-first
search per start state gives every distance; a goal then costs one mask over the states.
"""

from __future__ import annotations

import math

import numpy as np

from groundlang.model.statespace import StateSpace
from groundlang.model.world import Action

__all__ = ["EndStateNoise", "distances", "end_state_log_likelihood"]



class EndStateNoise:
    """The two parameters of the end-state likelihood (see the module docstring): ``beta``, how sharply
    the end is drawn to the nearest goal states, and ``anywhere`` (rho), the weight of noise. Defaults
    chosen by the likelihood of training pairs (ABLATIONS.md)."""

    def __init__(self, beta: float = 1.5, anywhere: float = 0.05):
        if not (0 <= beta < math.inf and 0 < anywhere < 1):
            raise ValueError(f"end-state noise: expected 0 <= beta < inf and 0 < anywhere < 1; "
                             f"got beta={beta}, anywhere={anywhere}")
        self.beta = beta
        self.anywhere = anywhere

    def key(self) -> tuple[float, float]:
        return (self.beta, self.anywhere)


def distances(space: StateSpace, start: int = 0) -> np.ndarray:
    """``[S]`` int: the fewest moves from state ``start`` to each state (-1: unreachable). From the
    initial state of a space enumerated breadth-first, its levels; else breadth-first here, a layer at
    a time, vectorised over the layer."""
    if start == 0 and space.level_sizes is not None:
        return np.repeat(np.arange(len(space.level_sizes), dtype=np.int64), space.level_sizes)
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
    out = np.empty(len(masks))
    floor = noise.anywhere / int(reachable.sum())
    for g, mask in enumerate(masks):  # a loop over goals; each step is vectorised over the states
        p = floor
        if mask[end]:
            goal_dist = dist[mask & reachable]
            nearest = goal_dist.min()
            z = np.exp(-noise.beta * (goal_dist - nearest)).sum()
            p += (1 - noise.anywhere) * math.exp(-noise.beta * (dist[end] - nearest)) / z
        out[g] = math.log(p)
    return out
