"""MLIRL: implicit gradient against finite differences, weighted demonstrations, recovery of a known goal."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from groundlang.inference.acting import rollout
from groundlang.inference.mlirl import Demonstration, MLIRLProblem, mlirl
from groundlang.inference.planning import PlanningError, soft_value_iteration, solve_task


def _random_problem(reward_on, discount, seed=0, **kwargs):
    rng = np.random.default_rng(seed)
    S = 12
    ns = rng.integers(0, S, (S, 4))
    features = rng.normal(size=(S, 3))
    demos = []
    for _ in range(3):
        states, actions = [int(rng.integers(S))], []
        for _ in range(4):
            a = int(rng.integers(4))
            actions.append(a)
            states.append(int(ns[states[-1], a]))
        demos.append((states, actions))
    return MLIRLProblem(ns, features, demos, kwargs.pop("demo_weights", [1.0, 0.5, 2.0]), reward_on=reward_on,
                        discount=discount, tol=1e-13, max_sweeps=100_000, dtype=torch.float64, step_cost=2.0,
                        **kwargs)


@pytest.mark.parametrize("reward_on, discount", [("terminate", 1.0), ("terminate", 0.9), ("arrival", 0.9)])
def test_implicit_gradient_matches_finite_differences(reward_on, discount):
    problem = _random_problem(reward_on, discount)
    x0 = np.array([0.3, -0.2, 0.5, 0.8])  # three weights, then the temperature
    theta = torch.tensor(x0[:3], requires_grad=True)
    temperature = torch.tensor(x0[3], requires_grad=True)
    problem.log_likelihood(theta, temperature).backward()
    gradient = np.r_[theta.grad.numpy(), temperature.grad.item()]

    def f(x):
        with torch.no_grad():
            return float(problem.log_likelihood(torch.tensor(x[:3]), torch.tensor(x[3])))

    eps = 1e-6
    numeric = np.array([(f(x0 + eps * e) - f(x0 - eps * e)) / (2 * eps) for e in np.eye(4)])
    np.testing.assert_allclose(gradient, numeric, rtol=1e-5, atol=1e-6)
    assert np.abs(gradient).max() > 0.1  # a real test, not zeros against zeros


def test_log_likelihood_equals_the_planner_policy_on_the_demonstrations():
    problem = _random_problem("terminate", 0.9, demo_weights=[1.0, 1.0, 1.0])
    theta = torch.tensor([0.3, -0.2, 0.5], dtype=torch.float64)
    with torch.no_grad():
        per_demo = problem.per_demo_log_likelihood(theta, torch.tensor(0.8, dtype=torch.float64))
    reward, stop = problem.rewards(theta)
    result = soft_value_iteration(problem.next_state, reward, 0.9, 0.8, stop_reward=stop, tol=1e-13,
                                  dtype=torch.float64)
    for d, demo in enumerate(problem.demonstrations):
        expected = float(result.log_policy[demo.states[:-1], demo.actions].sum() + result.log_policy[demo.states[-1], 4])
        assert float(per_demo[d]) == pytest.approx(expected, abs=1e-9)


@pytest.mark.slow
def test_a_weight_of_two_equals_a_duplicated_demonstration():
    rng = np.random.default_rng(1)
    ns = rng.integers(0, 20, (20, 4))
    features = rng.normal(size=(20, 2))
    demo = Demonstration([0, int(ns[0, 2]), int(ns[ns[0, 2], 1])], [2, 1])
    other = Demonstration([5, int(ns[5, 0])], [0])
    weighted = mlirl(ns, features, [demo, other], demo_weights=[2.0, 1.0], temperature=1.0, dtype=torch.float64)
    duplicated = mlirl(ns, features, [demo, demo, other], temperature=1.0, dtype=torch.float64)
    np.testing.assert_allclose(weighted.weights, duplicated.weights, atol=1e-4)
    assert weighted.log_likelihood == pytest.approx(duplicated.log_likelihood, abs=1e-6)


def test_bad_inputs_are_value_errors_naming_the_problem():
    ns = np.array([[1, 0, 0, 0], [1, 0, 1, 1]])
    with pytest.raises(PlanningError, match=r"features must be \[2, F\]"):
        MLIRLProblem(ns, np.zeros((3, 2)), [([0, 1], [0])])
    with pytest.raises(PlanningError, match="step 1"):
        MLIRLProblem(ns, np.zeros((2, 2)), [([0, 0], [0])])
    with pytest.raises(PlanningError, match="demo_weights"):
        MLIRLProblem(ns, np.zeros((2, 2)), [([0, 1], [0])], demo_weights=[1.0, 2.0])
    with pytest.raises(PlanningError, match="discount < 1"):
        MLIRLProblem(ns, np.zeros((2, 2)), [([0, 1], [0])], reward_on="arrival", discount=1.0)


def _one_toy_world():
    from groundlang.model.pf_tables import pf_tables
    from groundlang.model.statespace import enumerate_states
    from groundlang.model.world import Agent, Door, Layout, Room, State, Toy, get_palette

    rooms = (Room("green", 0, 10, 6, 4), Room("red", 6, 10, 10, 4), Room("blue", 0, 4, 10, 0))
    doors = (Door(3, 4, 3, 3), Door(8, 4, 8, 3), Door(5, 6, 6, 6))
    layout = Layout(rooms, doors, (("yellow", "star"),), get_palette("sokoban"))
    space = enumerate_states(State(layout, Agent(6, 2), (Toy("yellow", "star", 4, 6),)))
    return space, pf_tables(layout)


@pytest.mark.slow
def test_mlirl_recovers_the_goal_feature_in_a_cleanup_world_and_its_policy_reaches_the_goal():
    from groundlang.logic.atoms import parse_atom
    from groundlang.model.features import feature_matrix, goal_mask, position_atoms

    space, tables = _one_toy_world()
    atoms = position_atoms(space.layout)
    true_goal = parse_atom("toyInRoom(block0, room1)")
    goal = goal_mask(space, [true_goal], tables)
    expert = solve_task(space.next_state, goal)
    rng = np.random.default_rng(0)
    # Starts from which the expert pursues the goal (a toy in a corner cannot be moved).
    starts = [int(i) for i in rng.permutation(space.num_states) if not goal[i] and expert.values[i] > 50][:14]
    demos = []
    for k, s in enumerate(starts[:6]):
        path = rollout(space.next_state, expert, start=s, greedy=False, seed=k, max_steps=100)
        assert goal[path.states[-1]]
        demos.append((path.states, path.actions))
    features = feature_matrix(space, atoms, tables)
    fit = mlirl(space.next_state, features, demos)
    assert fit.converged
    assert atoms[int(np.argmax(fit.weights))] == true_goal
    assert 0.2 < fit.temperature < 1.0  # the expert's was 0.5
    problem = MLIRLProblem(space.next_state, features, demos)
    reward, stop = problem.rewards(torch.as_tensor(fit.weights))
    fitted = soft_value_iteration(space.next_state, reward, 0.99, fit.temperature, stop_reward=stop)
    for s in starts[6:]:
        path = rollout(space.next_state, fitted, start=s, max_steps=100)
        assert path.reason == "terminated" and goal[path.states[-1]], f"from state {s}"


def test_warm_started_gradients_equal_cold_ones():
    # The second gradient starts its values and adjoint from the first's: same answer as from scratch.
    warm = _random_problem("terminate", 0.9, warm_start_adjoint=True)
    cold = _random_problem("terminate", 0.9)
    grads = []
    for problem, points in ((warm, ([0.9, 0.1, -0.4, 1.3], [0.3, -0.2, 0.5, 0.8])), (cold, ([0.3, -0.2, 0.5, 0.8],))):
        for x in points:
            theta = torch.tensor(x[:3], dtype=torch.float64, requires_grad=True)
            temperature = torch.tensor(x[3], dtype=torch.float64, requires_grad=True)
            problem.log_likelihood(theta, temperature).backward()
        grads.append(np.r_[theta.grad.numpy(), temperature.grad.item()])
    assert warm.last_adjoint_steps <= cold.last_adjoint_steps
    np.testing.assert_allclose(grads[0], grads[1], rtol=1e-8, atol=1e-10)


@pytest.mark.slow
def test_compiled_gradient_agrees_with_eager():
    rng = np.random.default_rng(4)
    S = 2000
    ns = rng.integers(0, S, (S, 4))
    features = rng.normal(size=(S, 3)).astype(np.float32)
    states, actions = [7], []
    for a in (0, 2, 2, 1):
        actions.append(a)
        states.append(int(ns[states[-1], a]))
    results = []
    for backend in ("eager", "compiled"):
        problem = MLIRLProblem(ns, features, [(states, actions)], backend=backend, tol=1e-6, step_cost=2.0)
        theta = torch.tensor([0.5, -0.3, 0.2], requires_grad=True)
        temperature = torch.tensor(0.9, requires_grad=True)
        ll = problem.log_likelihood(theta, temperature)
        ll.backward()
        results.append(np.r_[ll.detach().item(), theta.grad.numpy(), temperature.grad.item()])
    np.testing.assert_allclose(results[1], results[0], rtol=1e-3, atol=1e-3)
