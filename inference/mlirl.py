"""Maximum-likelihood inverse reinforcement learning (MLIRL; Babeş-Vroman et al., ICML 2011).

Find linear reward weights ``theta`` (reward = ``features @ theta``) and,
unless fixed, the Boltzmann temperature that maximise the (weighted)
log-likelihood of demonstrations under the soft-max policy of
:mod:`groundlang.inference.planning`.

Where the reward enters (``reward_on``):

- ``"terminate"`` (default): the features are paid by the TERMINATE action,
  ``Q(s, stop) = features[s] @ theta``, and every move costs ``step_cost``.
  The weights then say which propositions the demonstrator wanted to hold
  *when it stopped*, which is what a goal is; the fixed step cost sets the
  reward's scale, so weights and temperature are both identifiable.
- ``"arrival"``: classic MLIRL, ``r(s, a) = features[next_state[s, a]] @ theta
  - step_cost`` with discount < 1 and no terminate action.

Gradient: implicit differentiation at the fixed point, not autograd through
the sweeps. Autograd through ``n`` sweeps keeps ``n`` copies of the
``[S, A+1]`` intermediates (at 10^6 states and a few hundred sweeps that is
tens of GiB); at the fixed point ``V = B(V, theta)`` the adjoint
``lambda = g + (dB/dV)^T lambda`` is one more linear fixed point whose
iteration moves ``discount * pi(a|s) * lambda(s)`` onto successors. It is
written as a gather over a predecessor table built once per problem
(:func:`~groundlang.inference.sweeps.predecessor_table`; no serial
scatter-add), costs about one sweep per step, stores no history and is
compiled with the forward sweep from ``COMPILE_MIN_STATES`` states. The
gradient is then one vector-Jacobian product of a single backup. Memory is a
handful of ``[S]``, ``[S, A]`` and ``[K, S]`` (K = largest in-degree)
arrays plus the features. The forward solve warm-starts from the previous
evaluation's values, so an optimiser step that moves the weights a little
costs a few sweeps; the adjoint can too (``warm_start_adjoint``, off by
default: see the field's comment).

The optimiser is L-BFGS with a strong-Wolfe line search (default; few steps,
no learning rate to tune, deterministic) or Adam. A small Gaussian prior on
``theta`` (``l2``) keeps the maximum finite when a demonstration is
explained perfectly by ever larger weights; the temperature is kept in
``[MIN_TEMPERATURE, MAX_TEMPERATURE]``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np
import torch

from groundlang.inference.planning import PlanningError, as_transitions, soft_backup
from groundlang.inference.sweeps import (
    policy_from_carry,
    predecessor_table,
    solve_adjoint,
    solve_values,
    threads_for,
    transition_columns,
)

__all__ = ["Demonstration", "MLIRLProblem", "MLIRLResult", "mlirl", "MIN_TEMPERATURE", "MAX_TEMPERATURE"]

logger = logging.getLogger(__name__)

# The L1 prior |theta| is smoothed to sqrt(theta^2 + eps^2) so that L-BFGS sees a smooth objective.
L1_SMOOTHING = 1e-2
MIN_TEMPERATURE = 0.05
MAX_TEMPERATURE = 20.0


@dataclass(frozen=True)
class Demonstration:
    """State indices ``[T + 1]`` and move indices ``[T]`` in one state space."""

    states: np.ndarray
    actions: np.ndarray

    def __post_init__(self):
        s = np.asarray(self.states, dtype=np.int64)
        a = np.asarray(self.actions, dtype=np.int64)
        if s.ndim != 1 or a.ndim != 1 or len(s) != len(a) + 1:
            raise PlanningError(
                f"a demonstration needs T + 1 states and T actions, got {tuple(s.shape)} and {tuple(a.shape)}"
            )
        object.__setattr__(self, "states", s)
        object.__setattr__(self, "actions", a)


class _SoftFixedPoint(torch.autograd.Function):
    """Values ``[S]`` at the soft Bellman fixed point, with the implicit (adjoint) gradient."""

    @staticmethod
    def forward(ctx, reward, stop, temperature, problem):
        if problem.warm_values is None or problem.warm_values.dtype != reward.dtype:
            problem.warm_values = torch.zeros(reward.shape[0], dtype=reward.dtype)
        reward_d, stop_d, t_d = reward.detach(), None if stop is None else stop.detach(), temperature.detach()
        carry, sweeps, residual = solve_values(
            problem.warm_values, problem.columns, reward_d, stop_d, problem.discount, t_d, None,
            problem.tol, problem.max_sweeps, problem.backend,
        )
        values, _, log_policy = policy_from_carry(carry, problem.columns, reward_d, stop_d, t_d)
        problem.warm_values = values
        problem.last_sweeps, problem.last_residual = sweeps, residual
        ctx.problem = problem
        A = problem.next_state.shape[1]
        move_prob = log_policy[:, :A].exp()  # pi(a|s) of the moves, [S, A]
        ctx.save_for_backward(reward, stop if stop is not None else torch.empty(0), temperature, values, move_prob)
        ctx.has_stop = stop is not None
        return values

    @staticmethod
    def backward(ctx, grad_values):
        reward, stop, temperature, values, move_prob = ctx.saved_tensors
        stop = stop if ctx.has_stop else None
        problem = ctx.problem
        with torch.no_grad():
            lam, problem.last_adjoint_steps = solve_adjoint(
                grad_values.contiguous(), move_prob, problem.predecessors(), problem.discount, problem.tol,
                problem.max_sweeps, problem.backend, problem.warm_adjoint if problem.warm_start_adjoint else None,
            )
            problem.warm_adjoint = lam
        with torch.enable_grad():
            inputs = [t.detach().requires_grad_(True) for t in (reward, temperature)]
            stop_in = None if stop is None else stop.detach().requires_grad_(True)
            new_values = soft_backup(values, problem.next_state, inputs[0], stop_in, problem.discount, inputs[1])
            wrt = inputs + ([stop_in] if stop_in is not None else [])
            grads = torch.autograd.grad(new_values, wrt, lam)
        grad_reward, grad_temperature = grads[0], grads[1]
        grad_stop = grads[2] if stop is not None else None
        return grad_reward, grad_stop, grad_temperature, None


@dataclass
class MLIRLProblem:
    """One MDP, its features and weighted demonstrations; evaluates the log-likelihood and its gradient.

    ``next_state`` ``[S, A]``; ``features`` ``[S, F]``; ``demonstrations`` a
    list of :class:`Demonstration` (or ``(states, actions)`` pairs);
    ``demo_weights`` ``[D]`` (default ones). The solver warm-starts every solve
    from the previous one's values.
    """

    next_state: object
    features: object
    demonstrations: list
    demo_weights: object = None
    reward_on: str = "terminate"
    step_cost: float = 1.0
    discount: float = 0.99
    tol: float = 1e-4
    max_sweeps: int = 5000
    dtype: torch.dtype = torch.float32
    backend: str = "auto"
    warm_values: torch.Tensor | None = field(default=None, repr=False)
    # Off by default: a warm-started adjoint meets the stopping rule sooner but with a larger remaining
    # error (about change / (1 - discount)), which moved fitted weights by ~0.02 in the discovery tests.
    warm_start_adjoint: bool = False
    warm_adjoint: torch.Tensor | None = field(default=None, repr=False)
    last_sweeps: int = 0
    last_adjoint_steps: int = 0
    last_residual: float = math.inf

    def __post_init__(self):
        self.next_state = as_transitions(self.next_state)
        self.columns = transition_columns(self.next_state)
        self._predecessors = None
        S, A = self.next_state.shape
        self.features = torch.as_tensor(np.asarray(self.features) if not isinstance(self.features, torch.Tensor)
                                        else self.features, dtype=self.dtype)
        if self.features.ndim != 2 or self.features.shape[0] != S:
            raise PlanningError(f"features must be [{S}, F] (one row per state), got {tuple(self.features.shape)}")
        if self.reward_on not in ("terminate", "arrival"):
            raise PlanningError(f"reward_on must be 'terminate' or 'arrival', got {self.reward_on!r}")
        if self.reward_on == "arrival" and not self.discount < 1:
            raise PlanningError("reward_on='arrival' has no terminate action and needs discount < 1")
        demos = [d if isinstance(d, Demonstration) else Demonstration(*d) for d in self.demonstrations]
        if not demos:
            raise PlanningError("MLIRL needs at least one demonstration")
        for i, d in enumerate(demos):
            if d.states.min() < 0 or d.states.max() >= S or (len(d.actions) and (d.actions.min() < 0 or d.actions.max() >= A)):
                raise PlanningError(f"demonstration {i}: a state index is outside 0..{S - 1} or an action outside 0..{A - 1}")
            if not (self.next_state[d.states[:-1], d.actions].numpy() == d.states[1:]).all():
                t = int(np.flatnonzero(self.next_state[d.states[:-1], d.actions].numpy() != d.states[1:])[0])
                raise PlanningError(f"demonstration {i}, step {t + 1}: action {int(d.actions[t])} from state "
                                    f"{int(d.states[t])} does not lead to state {int(d.states[t + 1])}")
        self.demonstrations = demos
        w = np.ones(len(demos)) if self.demo_weights is None else np.asarray(self.demo_weights, dtype=float)
        if w.shape != (len(demos),) or (w < 0).any():
            raise PlanningError(f"demo_weights must be [{len(demos)}] and non-negative, got shape {w.shape}")
        self.demo_weights = w
        # Flattened transitions of all demonstrations, with the demonstration each belongs to.
        self._move_state = torch.as_tensor(np.concatenate([d.states[:-1] for d in demos]))
        self._move_action = torch.as_tensor(np.concatenate([d.actions for d in demos]))
        self._move_demo = torch.as_tensor(np.concatenate([np.full(len(d.actions), i) for i, d in enumerate(demos)]))
        self._final_state = torch.as_tensor(np.array([d.states[-1] for d in demos]))

    def predecessors(self):
        """:func:`predecessor_table` of this problem's transitions (built on first use)."""
        if self._predecessors is None:
            self._predecessors = predecessor_table(self.next_state)
        return self._predecessors

    @property
    def num_features(self) -> int:
        return int(self.features.shape[1])

    def rewards(self, theta: torch.Tensor):
        """``(arrival reward [S], stop reward [S] or None)`` for weights ``theta`` ``[F]``."""
        linear = self.features @ theta
        cost = torch.full_like(linear, -float(self.step_cost))
        if self.reward_on == "terminate":
            return cost, linear
        return linear + cost, None

    def per_demo_log_likelihood(self, theta: torch.Tensor, temperature: torch.Tensor) -> torch.Tensor:
        """``[D]`` log-likelihood of each demonstration (differentiable in theta and temperature)."""
        reward, stop = self.rewards(theta)
        values = _SoftFixedPoint.apply(reward, stop, temperature, self)
        s, a = self._move_state, self._move_action
        nxt = self.next_state[s, a]
        log_p = (reward[nxt] + self.discount * values[nxt] - values[s]) / temperature
        D = len(self.demonstrations)
        per_demo = torch.zeros(D, dtype=log_p.dtype).index_add(0, self._move_demo, log_p)
        if stop is not None:
            f = self._final_state
            per_demo = per_demo + (stop[f] - values[f]) / temperature
        return per_demo

    def log_likelihood(self, theta: torch.Tensor, temperature: torch.Tensor) -> torch.Tensor:
        """Weighted sum of the demonstrations' log-likelihoods (0-dim, differentiable)."""
        weights = torch.as_tensor(self.demo_weights, dtype=self.dtype)
        return (weights * self.per_demo_log_likelihood(theta, temperature)).sum()


@dataclass(frozen=True)
class MLIRLResult:
    """Fitted reward: ``weights`` ``[F]``, ``temperature``, the weighted ``log_likelihood`` (no prior),
    optimiser ``steps``, ``converged``, and the fixed-point ``values`` ``[S]``."""

    weights: np.ndarray
    temperature: float
    log_likelihood: float
    steps: int
    converged: bool
    values: torch.Tensor


def _temperature(log_t: torch.Tensor) -> torch.Tensor:
    return torch.exp(log_t.clamp(math.log(MIN_TEMPERATURE), math.log(MAX_TEMPERATURE)))


def mlirl(
    next_state,
    features,
    demonstrations,
    demo_weights=None,
    temperature: float | None = None,
    initial_temperature: float = 1.0,
    initial_weights=None,
    reward_on: str = "terminate",
    step_cost: float = 1.0,
    discount: float = 0.99,
    l2: float = 1e-3,
    l1: float = 0.0,
    nonnegative: bool = False,
    optimizer: str = "lbfgs",
    lr: float = 0.1,
    max_steps: int = 100,
    tol: float = 1e-6,
    problem: MLIRLProblem | None = None,
    **solver,
) -> MLIRLResult:
    """Fit linear reward weights (and the temperature unless ``temperature`` is given) by maximum likelihood.

    Args:
        next_state: ``[S, A]`` transitions; features: ``[S, F]``.
        demonstrations: list of Demonstration or ``(states [T+1], actions [T])``.
        demo_weights: ``[D]`` non-negative weights (EM responsibilities), default ones.
        temperature: fixed Boltzmann temperature, or None to learn it from ``initial_temperature``.
        l2: Gaussian prior ``l2 / 2 * |theta|^2`` added to the negative log-likelihood.
        l1: Laplace (sparsity) prior ``l1 * |theta|_1``. Propositions that become true together
            at the end of a demonstration are indistinguishable by where the demonstrator
            stopped; the L2 prior splits weight evenly among them, an L1 prior concentrates it on
            the one whose achievement alone best explains the whole path.
        nonnegative: weights constrained >= 0 (softplus parametrisation).
        optimizer: "lbfgs" (``max_steps`` iterations) or "adam" (``max_steps`` steps of size ``lr``).
        tol: converged when the objective per demonstrated step changes less than this.
        problem: reuse an MLIRLProblem (its warm start); then next_state..discount are ignored.
        solver: tol/max_sweeps/dtype/backend for the inner soft value iteration.
    """
    if problem is None:
        problem = MLIRLProblem(next_state, features, demonstrations, demo_weights, reward_on=reward_on,
                               step_cost=step_cost, discount=discount, **solver)
    elif demo_weights is not None:
        problem.demo_weights = np.asarray(demo_weights, dtype=float)
    with threads_for(problem.next_state.shape[0]):
        return _fit(problem, temperature, initial_temperature, initial_weights, l2, l1, nonnegative, optimizer,
                    lr, max_steps, tol)


def _fit(problem, temperature, initial_temperature, initial_weights, l2, l1, nonnegative, optimizer, lr, max_steps,
         tol):
    F = problem.num_features
    theta = torch.zeros(F, dtype=problem.dtype) if initial_weights is None else \
        torch.as_tensor(np.asarray(initial_weights), dtype=problem.dtype).clone()
    if theta.shape != (F,):
        raise PlanningError(f"initial_weights must be [{F}], got {tuple(theta.shape)}")
    if nonnegative:
        # theta = softplus(u): weights stay >= 0 (goals are propositions wanted true, not avoided).
        # Zero weights would sit where softplus is flat; start unknown weights at softplus(0) = 0.69.
        theta = torch.zeros_like(theta) if initial_weights is None else \
            torch.where(theta > 20, theta, torch.log(torch.expm1(theta.clamp_min(1e-3))))
    raw = theta.requires_grad_(True)

    def weights_of(u):
        return torch.nn.functional.softplus(u) if nonnegative else u

    learn_t = temperature is None
    log_t = torch.tensor(math.log(initial_temperature if learn_t else temperature), dtype=problem.dtype,
                         requires_grad=learn_t)
    params = [raw] + ([log_t] if learn_t else [])
    # Normalise by the weighted number of decisions (moves + final stop) so that tolerances and the
    # prior's strength do not depend on how many demonstrations there are or how they are weighted.
    decisions = np.array([len(d.actions) + 1 for d in problem.demonstrations])
    scale = max(float((problem.demo_weights * decisions).sum()), 1e-12)

    def objective():
        theta = weights_of(raw)
        ll = problem.log_likelihood(theta, _temperature(log_t))
        penalty = 0.5 * l2 * (theta * theta).sum()
        if l1:
            penalty = penalty + l1 * torch.sqrt(theta * theta + L1_SMOOTHING**2).sum()
        return (-ll + penalty) / scale, ll

    steps, converged = 0, False
    if optimizer == "lbfgs":
        opt = torch.optim.LBFGS(params, lr=1.0, max_iter=max_steps, tolerance_grad=tol, tolerance_change=tol * 1e-3,
                                history_size=20, line_search_fn="strong_wolfe")

        def closure():
            opt.zero_grad()
            loss, _ = objective()
            loss.backward()
            return loss

        opt.step(closure)
        steps = int(opt.state[opt._params[0]]["n_iter"])
        converged = steps < max_steps
    elif optimizer == "adam":
        opt = torch.optim.Adam(params, lr=lr)
        previous = math.inf
        for steps in range(1, max_steps + 1):
            opt.zero_grad()
            loss, _ = objective()
            loss.backward()
            opt.step()
            if abs(previous - float(loss)) < tol:
                converged = True
                break
            previous = float(loss)
    else:
        raise PlanningError(f"optimizer must be 'lbfgs' or 'adam', got {optimizer!r}")
    with torch.no_grad():
        theta = weights_of(raw)
        ll = problem.log_likelihood(theta, _temperature(log_t))
    result = MLIRLResult(theta.detach().numpy().copy(), float(_temperature(log_t).detach()), float(ll), steps, converged,
                         problem.warm_values)
    logger.debug("mlirl: %d steps, log-likelihood %.4f, temperature %.3f", steps, result.log_likelihood,
                 result.temperature)
    return result
