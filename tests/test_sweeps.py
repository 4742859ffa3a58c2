"""The sweep engine: carried sweeps against the textbook backup, the predecessor table against a scatter-add."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from groundlang.inference.planning import soft_backup
from groundlang.inference.sweeps import (
    adjoint_sweep,
    carry_sweep,
    policy_from_carry,
    predecessor_table,
    solve_adjoint,
    transition_columns,
)


def _random_mdp(S=40, A=4, seed=0):
    rng = np.random.default_rng(seed)
    ns = torch.as_tensor(rng.integers(0, S, (S, A)))
    return ns, torch.as_tensor(rng.normal(size=S)), torch.as_tensor(rng.normal(size=S)), torch.as_tensor(rng.normal(size=S))


@pytest.mark.parametrize("state_action", [False, True])
def test_a_carried_sweep_is_the_soft_backup_of_the_carried_values(state_action):
    ns, values, arrival, stop = _random_mdp()
    S, A = ns.shape
    reward = torch.as_tensor(np.random.default_rng(1).normal(size=(S, A))) if state_action else arrival
    T, discount = torch.tensor(0.7, dtype=torch.float64), 0.9
    terminal = torch.zeros(S, dtype=torch.bool)
    terminal[3] = True
    carry = (0 if state_action else arrival) + discount * values
    out = torch.empty(S, dtype=torch.float64)
    action_reward = reward.t().contiguous() if state_action else None
    base = torch.zeros((), dtype=torch.float64) if state_action else arrival
    res = carry_sweep(out, carry, transition_columns(ns), base, action_reward, stop, discount, T, terminal, True)
    expected = soft_backup(values, ns, reward, stop, discount, T, terminal)
    torch.testing.assert_close(out, base + discount * expected)
    assert float(res) == pytest.approx(float((out - carry).abs().max()))
    # One more backup from the carried array gives the same values and a normalised policy.
    new_values, q, log_policy = policy_from_carry(out, transition_columns(ns), reward, stop, T, terminal)
    torch.testing.assert_close(new_values, soft_backup(expected, ns, reward, stop, discount, T, terminal))
    assert q.shape == (S, A + 1) and float(log_policy[3, 4]) == 0.0
    torch.testing.assert_close(log_policy.exp().sum(1), torch.ones(S, dtype=torch.float64))


def test_predecessor_gather_equals_a_scatter_add_and_the_adjoint_solves_its_linear_system():
    ns, lam, grad, _ = _random_mdp(S=50, seed=2)
    S, A = ns.shape
    prob = torch.softmax(torch.as_tensor(np.random.default_rng(3).normal(size=(S, A))), 1) * 0.8
    slots, states = predecessor_table(ns)
    assert slots.shape[0] == int(np.bincount(ns.reshape(-1).numpy()).max())
    flat = torch.cat([prob.reshape(-1), prob.new_zeros(1)])
    out = torch.empty(S, dtype=torch.float64)
    adjoint_sweep(out, lam, grad, flat[slots], states, 0.9)
    scatter = torch.zeros(S, dtype=torch.float64).index_add_(0, ns.reshape(-1), (prob * lam[:, None]).reshape(-1))
    torch.testing.assert_close(out, grad + 0.9 * scatter)
    solved, steps = solve_adjoint(grad, prob, (slots, states), 0.9, 1e-13, 10_000, "eager")
    P = torch.zeros(S, S, dtype=torch.float64).index_put_((torch.arange(S)[:, None].expand(S, A), ns), prob,
                                                           accumulate=True)
    direct = torch.linalg.solve(torch.eye(S, dtype=torch.float64) - 0.9 * P.t(), grad)
    torch.testing.assert_close(solved, direct, atol=1e-10, rtol=1e-10)
    # A warm start from the answer stops at the first check.
    _, warm_steps = solve_adjoint(grad, prob, (slots, states), 0.9, 1e-10, 10_000, "eager", initial=solved)
    assert warm_steps < steps and warm_steps == 1
