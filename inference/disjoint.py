"""Soft value iteration for many (MDP, goal) blocks at once: one sweep over their disjoint union.

A demonstration scored under many candidate goals in a large world solves many MDPs of tens or
hundreds of thousands of states each (:mod:`groundlang.inference.stepwise`). Swept one by one, each
pays its own loop; swept as one block-diagonal MDP, every block pays for the slowest. Here the union
of the blocks still unconverged is swept, and every ``CHECK_EVERY`` sweeps each block's own residual
decides whether it stops: a block converges after exactly the sweeps :func:`solve_task` alone would
give it, with the same values, and the union shrinks as blocks converge.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np
import torch

from groundlang.inference.planning import TaskSettings, task_rewards
from groundlang.inference.sweeps import (CHECK_EVERY, PlanningError, carry_sweep, policy_from_carry, run_compiled,
                                         threads_for, use_compiled)

__all__ = ["solve_blocks"]

logger = logging.getLogger(__name__)


def solve_blocks(blocks: Sequence[tuple[np.ndarray, np.ndarray]], settings: TaskSettings,
                 policy_states: Sequence[np.ndarray], backend: str = "auto") -> list[torch.Tensor]:
    """``blocks`` of ``(next_state [S_b, 4], goal_mask [S_b])``, each the task "make the goal hold, then
    terminate" (:func:`groundlang.inference.planning.solve_task`); returns, per block, the log-policy
    ``[len(policy_states[b]), 5]`` at its ``policy_states``. Blocks that stop at ``max_sweeps``
    unconverged are logged as warnings."""
    if len(policy_states) != len(blocks):
        raise PlanningError(f"{len(blocks)} blocks but {len(policy_states)} lists of policy states")
    columns = [torch.from_numpy(np.ascontiguousarray(np.asarray(ns).T.astype(np.int32))) for ns, _ in blocks]
    rewards = [task_rewards(mask, settings) for _, mask in blocks]  # (arrival [S], stop [S], terminal or None)
    discount = float(settings.discount)
    temperature = torch.tensor(float(settings.temperature))
    carries = [arrival.clone() for arrival, _, _ in rewards]  # arrival + discount * V with V = 0
    active = list(range(len(blocks)))
    sweeps = 0
    with threads_for(sum(c.shape[1] for c in columns)):
        while active:
            sizes = [columns[b].shape[1] for b in active]
            offsets = np.cumsum([0] + sizes[:-1])
            union = torch.cat([columns[b] + int(o) for b, o in zip(active, offsets)], dim=1)
            arrival = torch.cat([rewards[b][0] for b in active])
            stop = torch.cat([rewards[b][1] for b in active])
            terminal = None if rewards[active[0]][2] is None else torch.cat([rewards[b][2] for b in active])
            carry, spare = torch.cat([carries[b] for b in active]), torch.empty_like(arrival)
            sweep = (lambda *a: run_compiled(carry_sweep, *a)) if use_compiled(len(arrival), backend) else carry_sweep
            while True:
                chunk = min(CHECK_EVERY, settings.max_sweeps - sweeps)
                for _ in range(chunk):
                    sweep(spare, carry, union, arrival, None, stop, discount, temperature, terminal, False)
                    carry, spare = spare, carry
                sweeps += chunk
                # each block's max |dV| over the last sweep (spare holds the sweep before)
                change = np.abs(carry.numpy() - spare.numpy())
                residual = torch.from_numpy(np.maximum.reduceat(change, offsets)) / discount
                if not torch.isfinite(residual).all():
                    raise PlanningError(f"soft value iteration diverged after {sweeps} sweeps")
                done = set((residual <= settings.tol).nonzero().flatten().tolist())
                if sweeps >= settings.max_sweeps:
                    logger.warning("soft value iteration stopped %d of %d blocks after %d sweeps (largest residual "
                                   "%.3g)", len(active) - len(done), len(blocks), sweeps, float(residual.max()))
                    done = set(range(len(active)))
                if done:
                    break
            for i, part in enumerate(carry.split(sizes)):
                carries[active[i]] = part
            active = [b for i, b in enumerate(active) if i not in done]
        out = []
        for b, rows in enumerate(policy_states):
            rows = torch.as_tensor(np.asarray(rows, dtype=np.int64))
            arrival, stop, terminal = rewards[b]
            _, _, log_policy = policy_from_carry(carries[b], columns[b][:, rows].long(), arrival, stop[rows],
                                                 temperature, None if terminal is None else terminal[rows])
            out.append(log_policy)
    return out
