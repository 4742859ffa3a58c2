"""Acting: roll a planned policy out from an initial state, greedily or by sampling.

A rollout ends when the policy chooses TERMINATE, when the goal holds (if a
goal mask is given), or after ``max_steps`` moves; it returns the trajectory
as state indices and moves, and :func:`rollout_states` turns it into the
corpus's terms (``model.world.State`` objects and ``Action`` values).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from groundlang.inference.planning import TERMINATE, PlanningError, SoftValueResult

__all__ = ["Rollout", "rollout", "rollout_states", "stop_before"]


@dataclass(frozen=True)
class Rollout:
    """A trajectory: ``states`` ``[T + 1]`` indices, ``actions`` ``[T]`` moves, and why it ended
    ("terminated", "goal" or "max_steps")."""

    states: np.ndarray
    actions: np.ndarray
    reason: str


def rollout(
    next_state,
    policy,
    start: int = 0,
    goal_mask=None,
    greedy: bool = True,
    seed: int | None = None,
    max_steps: int = 200,
) -> Rollout:
    """Act from ``start`` until TERMINATE is chosen, the goal holds, or ``max_steps`` moves.

    ``policy`` is a SoftValueResult or a log-policy / Q table ``[S, A(+1)]``
    (argmax or sampling are the same for either when greedy). Sampling
    (``greedy=False``) needs a log-policy and uses ``numpy.random.default_rng(seed)``.
    Raises PlanningError when the table does not have one row per state.
    """
    table = policy.log_policy if isinstance(policy, SoftValueResult) else policy
    table = np.asarray(torch.as_tensor(table).detach().cpu().numpy(), dtype=np.float64)
    ns = np.asarray(next_state)
    if table.ndim != 2 or table.shape[0] != ns.shape[0]:
        raise PlanningError(f"policy must be [{ns.shape[0]}, A], got shape {table.shape}")
    goal = None if goal_mask is None else np.asarray(goal_mask, dtype=bool)
    rng = np.random.default_rng(seed)
    states, actions = [int(start)], []
    reason = "max_steps"
    # A loop over the steps of one trajectory, not over states: each step depends on the last.
    for _ in range(max_steps + 1):
        s = states[-1]
        if goal is not None and goal[s]:
            reason = "goal"
            break
        if greedy:
            a = int(np.argmax(table[s]))
        else:
            p = np.exp(table[s] - table[s].max())
            a = int(rng.choice(len(p), p=p / p.sum()))
        if a == TERMINATE:
            reason = "terminated"
            break
        if len(actions) == max_steps:
            break
        actions.append(a)
        states.append(int(ns[s, a]))
    return Rollout(np.array(states, dtype=np.int64), np.array(actions, dtype=np.int64), reason)


def stop_before(trajectory: Rollout, forbidden, reason: str = "scenery") -> Rollout:
    """The trajectory up to (not including) its first move flagged in ``forbidden`` ``[T]`` bool, ending
    with ``reason``; unchanged when none is flagged (e.g. a move an abstraction blocks but the world
    would make, :func:`groundlang.model.relevance.pushes_scenery`)."""
    flagged = np.flatnonzero(np.asarray(forbidden, dtype=bool))
    if not len(flagged):
        return trajectory
    t = int(flagged[0])
    return Rollout(trajectory.states[: t + 1], trajectory.actions[:t], reason)


def rollout_states(space, trajectory: Rollout):
    """The trajectory in the corpus's terms: ``(list of model.world.State, list of Action)``."""
    from groundlang.model.world import Action

    return [space.state_at(int(i)) for i in trajectory.states], [Action(int(a)) for a in trajectory.actions]
