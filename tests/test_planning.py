"""Soft value iteration against brute force, the terminate action, demonstration likelihoods."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import torch

from groundlang.inference import sweeps
from groundlang.inference.planning import (
    TERMINATE,
    PlanningError,
    TaskSettings,
    demonstration_log_likelihood,
    soft_value_iteration,
    solve_task,
    task_log_likelihood,
)

# A 4-state corridor 0-1-2-3 with the four moves of Cleanup World: 0 (north) and
# 1 (south) bump into walls, 2 = east, 3 = west; walls bounce back.
CORRIDOR = np.array([[0, 0, 1, 0], [1, 1, 2, 0], [2, 2, 3, 1], [3, 3, 3, 2]])


def _paths_value(next_state, step_reward, stop_reward, temperature, start, horizon):
    """Brute force at discount 1: T * log of the sum over every path that ends by terminating
    of exp(return / T), enumerating all action sequences up to ``horizon`` moves."""
    total = 0.0
    A = next_state.shape[1]
    for length in range(horizon + 1):
        for seq in itertools.product(range(A), repeat=length):
            s, ret = start, 0.0
            for a in seq:
                s = next_state[s, a]
                ret += step_reward[s]
            total += math.exp((ret + stop_reward[s]) / temperature)
    return temperature * math.log(total)


def test_soft_values_equal_brute_force_path_sums_at_discount_one():
    step = np.full(4, -4.0)
    stop = np.array([0.0, 0.0, 0.0, 5.0])
    result = soft_value_iteration(
        CORRIDOR, step, discount=1.0, temperature=1.0, stop_reward=stop, tol=1e-10, dtype=torch.float64
    )
    assert result.converged
    assert result.has_terminate and result.q_values.shape == (4, 5)
    # Each extra move multiplies a path's weight by e^-4 and there are 4 moves: truncating at
    # 7 moves leaves a tail below (4 e^-4)^8 ~ 1e-9 of the sum.
    for s in range(4):
        reference = _paths_value(CORRIDOR, step, stop, 1.0, s, horizon=7)
        assert float(result.values[s]) == pytest.approx(reference, abs=1e-5)
    # The policy is normalised and is the Boltzmann distribution over Q.
    probs = result.log_policy.exp()
    assert torch.allclose(probs.sum(1), torch.ones(4, dtype=torch.float64))
    assert torch.allclose(result.log_policy, torch.log_softmax(result.q_values, 1))


def _loop_reference(next_state, reward_sa, discount, temperature, terminal, sweeps=3000):
    """Plain Python loops over states and actions, float64."""
    S, A = next_state.shape
    V = [0.0] * S
    for _ in range(sweeps):
        new = []
        for s in range(S):
            if terminal[s]:
                new.append(0.0)
                continue
            qs = [reward_sa[s][a] + discount * V[next_state[s][a]] for a in range(A)] + [0.0]
            m = max(qs)
            new.append(m + temperature * math.log(sum(math.exp((q - m) / temperature) for q in qs)))
        V = new
    return np.array(V)


def test_state_action_reward_discount_and_absorbing_states_match_a_loop_reference():
    rng = np.random.default_rng(3)
    ns = rng.integers(0, 6, size=(6, 4))
    reward = rng.normal(size=(6, 4))
    terminal = np.array([False, False, True, False, False, False])
    result = soft_value_iteration(
        ns, reward, discount=0.8, temperature=0.7, terminal=terminal, tol=1e-12, dtype=torch.float64
    )
    reference = _loop_reference(ns, reward, 0.8, 0.7, terminal)
    np.testing.assert_allclose(result.values.numpy(), reference, atol=1e-9)
    # Absorbing states terminate with probability one.
    assert float(result.log_policy[2, TERMINATE]) == 0.0
    assert torch.isneginf(result.log_policy[2, :4]).all()


def test_float32_default_agrees_with_float64():
    rng = np.random.default_rng(0)
    ns = rng.integers(0, 50, size=(50, 4))
    reward = rng.normal(size=50)
    v32 = soft_value_iteration(ns, reward, 0.9, 0.5, tol=1e-6).values
    v64 = soft_value_iteration(ns, reward, 0.9, 0.5, tol=1e-12, dtype=torch.float64).values
    assert v32.dtype == torch.float32
    np.testing.assert_allclose(v32.numpy(), v64.numpy(), atol=1e-3)


def test_sweep_limit_reports_not_converged():
    result = soft_value_iteration(CORRIDOR, -1.0, discount=0.99, temperature=1.0, max_sweeps=3)
    assert result.sweeps == 3 and not result.converged and result.residual > 1e-4


@pytest.mark.parametrize(
    "kwargs, shape",
    [
        (dict(next_state=np.zeros((4,), int), reward=np.zeros(4)), "(4,)"),
        (dict(next_state=CORRIDOR, reward=np.zeros(5)), "(5,)"),
        (dict(next_state=CORRIDOR, reward=np.zeros((4, 3))), "(4, 3)"),
        (dict(next_state=CORRIDOR, reward=np.zeros(4), stop_reward=np.zeros(3)), "(3,)"),
        (dict(next_state=CORRIDOR, reward=np.zeros(4), terminal=np.zeros((4, 1), bool)), "(4, 1)"),
        (dict(next_state=CORRIDOR + 1, reward=np.zeros(4)), "index 4"),
        (dict(next_state=CORRIDOR.astype(float), reward=np.zeros(4)), "dtype"),
    ],
)
def test_wrong_shapes_raise_value_errors_naming_the_shape(kwargs, shape):
    with pytest.raises(PlanningError, match=shape.replace("(", r"\(").replace(")", r"\)")):
        soft_value_iteration(**kwargs)
    assert issubclass(PlanningError, ValueError)


def test_unbounded_values_are_reported_as_not_converged():
    # Discount 1, no step cost: the entropy bonus of wandering (T log 4 per move) grows without bound.
    result = soft_value_iteration(CORRIDOR, 0.0, discount=1.0, temperature=1.0, max_sweeps=200)
    assert not result.converged
    assert float(result.values.min()) == pytest.approx(200 * math.log(4), rel=0.01)


class _Space:
    def __init__(self, next_state):
        self.next_state = next_state


def test_terminate_action_separates_go_to_red_from_go_through_red():
    # Corridor: room "red" is state 1, room "blue" state 3. Start at 0.
    space = _Space(CORRIDOR)
    red = np.array([False, True, False, False])
    blue = np.array([False, False, False, True])
    to_red = ([0, 1], [2])
    through_red_to_blue = ([0, 1, 2, 3], [2, 2, 2])
    settings = TaskSettings(goal_reward=10.0)
    ll = {
        (goal, name): task_log_likelihood(space, mask, *demo, settings)
        for goal, mask in (("red", red), ("blue", blue))
        for name, demo in (("to_red", to_red), ("through", through_red_to_blue))
    }
    assert ll["red", "to_red"] > ll["blue", "to_red"] + 5
    assert ll["blue", "through"] > ll["red", "through"] + 5
    # Without the final stop, stopping at red would say nothing against blue.
    result = solve_task(CORRIDOR, red, settings)
    without_stop = float(demonstration_log_likelihood(result.log_policy, *to_red, terminate=False))
    assert without_stop > ll["red", "to_red"]
    assert ll["red", "to_red"] > math.log(0.4)


def test_absorbing_goal_makes_walking_through_the_goal_impossible():
    red = np.array([False, True, False, False])
    settings = TaskSettings(goal_reward=10.0, absorbing_goal=True)
    assert task_log_likelihood(_Space(CORRIDOR), red, [0, 1], [2], settings) > math.log(0.4)
    assert task_log_likelihood(_Space(CORRIDOR), red, [0, 1, 2], [2, 2], settings) == -math.inf


def test_demonstration_shapes_are_checked():
    result = solve_task(CORRIDOR, np.array([0, 0, 0, 1], bool))
    with pytest.raises(PlanningError, match="T \\+ 1 states"):
        demonstration_log_likelihood(result.log_policy, [0, 1, 2], [2])
    with pytest.raises(PlanningError, match="move indices"):
        demonstration_log_likelihood(result.log_policy, [0, 1], [4])


@pytest.mark.slow
def test_compiled_sweeps_agree_with_eager():
    rng = np.random.default_rng(1)
    ns = rng.integers(0, 3000, size=(3000, 4))
    goal = np.zeros(3000, bool)
    goal[:5] = True
    eager = solve_task(ns, goal, backend="eager")
    compiled = solve_task(ns, goal, backend="compiled")
    assert compiled.sweeps == eager.sweeps
    np.testing.assert_allclose(compiled.values.numpy(), eager.values.numpy(), rtol=1e-5, atol=1e-4)


def test_a_process_that_plans_once_compiles_only_where_one_solve_pays_for_it(monkeypatch):
    monkeypatch.setattr(sweeps, "_COMPILE_FROM", [sweeps.COMPILE_MIN_STATES])
    big = sweeps.COMPILE_MIN_STATES
    assert not sweeps.use_compiled(big - 1, "auto") and sweeps.use_compiled(big, "auto")
    sweeps.plan_once()  # groundlang follow
    assert not sweeps.use_compiled(big, "auto") and not sweeps.use_compiled(sweeps.COMPILE_AT_ONCE_STATES - 1, "auto")
    assert sweeps.use_compiled(sweeps.COMPILE_AT_ONCE_STATES, "auto")
    assert sweeps.use_compiled(1, "compiled") and not sweeps.use_compiled(10**9, "eager")
    with pytest.raises(PlanningError, match="backend must be 'auto', 'eager' or 'compiled', got 'bogus'"):
        solve_task(np.zeros((3, 4), dtype=np.int64), np.array([True, False, False]), backend="bogus")


@pytest.mark.parametrize("absorbing", [False, True])
def test_the_policy_at_some_states_is_those_rows_of_the_whole_policy(absorbing):
    rng = np.random.default_rng(3)
    ns = rng.integers(0, 300, size=(300, 4))
    goal = rng.random(300) < 0.05
    settings = TaskSettings(absorbing_goal=absorbing)
    whole = solve_task(ns, goal, settings)
    rows = np.array([5, 0, 299, 5, 17])
    some = solve_task(ns, goal, settings, policy_states=rows)
    assert some.log_policy.shape == (5, 5) and some.sweeps == whole.sweeps
    assert torch.equal(some.log_policy, whole.log_policy[rows])
    assert torch.equal(some.values, whole.values[rows])
    with pytest.raises(PlanningError, match="policy_states must be state indices 0..299"):
        solve_task(ns, goal, settings, policy_states=[300])
