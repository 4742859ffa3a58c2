"""Soft value iteration, Boltzmann policies with a terminate action, demonstration likelihoods.

The MDP is deterministic and given as a gather table ``next_state[S, A]``
(``A = 4`` moves in ``Action`` order). Rewards come in two parts:

- ``reward``: per move. ``[S]`` means *arrival* reward, ``r(s, a) =
  reward[next_state[s, a]]`` (BURLAP's convention for state features, and it
  lets one sweep gather ``reward + discount * V`` in a single pass);
  ``[S, A]`` is a reward per state-action.
- ``stop_reward``: ``[S]`` or None. When given, the MDP has a fifth action
  ``TERMINATE`` (index 4) that ends the episode and pays ``stop_reward[s]``.
  This is the RSS 2015 terminate action: a demonstration ends with an
  explicit stop, so its likelihood says not only where the agent went but
  also that it chose to stop there ("go to red" differs from "go to blue
  through red": under the former, walking on from red is improbable).

The backup is the soft-max (Boltzmann) one,
``V(s) = T * logsumexp_a(Q(s, a) / T)``, whose greedy limit ``T -> 0`` is
ordinary value iteration; the policy is ``pi(a|s) = exp((Q(s, a) - V(s)) / T)``.
States in the optional ``terminal`` mask absorb: their value is 0 and their
only action is TERMINATE (probability 1), so a demonstration that walks on
from a terminal state has log-likelihood -inf.

Jacobi sweeps (:mod:`groundlang.inference.sweeps`) are vectorised gathers
over ``next_state``: no loop over states. Sweeps stop when ``max |V_new - V| <= tol`` (converged) or at
``max_sweeps`` (not converged; reported, never raised). Float32 by default:
the sweep is memory-bound and float32 halves the traffic; pass ``dtype``
float64 for gradient checks.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import torch

from groundlang.inference.sweeps import (
    TERMINATE,
    PlanningError,
    policy_from_carry,
    solve_values,
    threads_for,
    transition_columns,
)

__all__ = [
    "TERMINATE",
    "PlanningError",
    "SoftValueResult",
    "TaskSettings",
    "as_transitions",
    "threads_for",
    "soft_value_iteration",
    "soft_backup",
    "task_rewards",
    "solve_task",
    "demonstration_log_likelihood",
    "task_log_likelihood",
]

logger = logging.getLogger(__name__)

@dataclass(frozen=True)
class SoftValueResult:
    """Output of :func:`soft_value_iteration`.

    values ``[S]``; q_values and log_policy ``[S, A]`` or ``[S, A + 1]`` when
    a terminate action exists (column ``TERMINATE``); ``sweeps`` done;
    ``converged`` when the last residual ``max |dV|`` was ``<= tol``. Solved with
    ``policy_states`` (n indices), all three hold those states' rows only, in that order.
    """

    values: torch.Tensor
    q_values: torch.Tensor
    log_policy: torch.Tensor
    sweeps: int
    converged: bool
    residual: float

    @property
    def has_terminate(self) -> bool:
        return self.q_values.shape[1] > TERMINATE


def as_transitions(next_state) -> torch.Tensor:
    """Validate ``next_state[S, A]`` (numpy or torch, integer) and return it as a torch int64 tensor.

    Callers that solve many times on one MDP convert once and pass the tensor.
    """
    ns = torch.as_tensor(np.asarray(next_state) if not isinstance(next_state, torch.Tensor) else next_state)
    if ns.ndim != 2 or ns.shape[0] == 0 or ns.shape[1] == 0:
        raise PlanningError(f"next_state must be [S, A] with S, A > 0, got shape {tuple(ns.shape)}")
    if ns.dtype.is_floating_point or ns.dtype == torch.bool or ns.dtype.is_complex:
        raise PlanningError(f"next_state must hold integer state indices, got dtype {ns.dtype}")
    ns = ns.to(torch.int64)
    lo, hi = int(ns.min()), int(ns.max())
    if lo < 0 or hi >= ns.shape[0]:
        raise PlanningError(
            f"next_state of shape {tuple(ns.shape)} holds index {lo if lo < 0 else hi}, outside 0..{ns.shape[0] - 1}"
        )
    return ns


def _vector(x, name: str, size: int, dtype: torch.dtype) -> torch.Tensor:
    t = torch.as_tensor(x, dtype=dtype)
    if t.shape != (size,):
        raise PlanningError(f"{name} must have shape [{size}] (one entry per state), got {tuple(t.shape)}")
    return t


def _reward(reward, S: int, A: int, dtype: torch.dtype) -> torch.Tensor:
    r = torch.as_tensor(reward, dtype=dtype)
    if r.ndim == 0:
        return r.expand(S)
    if r.shape not in ((S,), (S, A)):
        raise PlanningError(f"reward must have shape [{S}] or [{S}, {A}], got {tuple(r.shape)}")
    return r


def _check_scalars(discount: float, temperature) -> None:
    if not 0.0 < float(discount) <= 1.0:
        raise PlanningError(f"discount must be in (0, 1], got {float(discount)}")
    if not float(temperature) > 0.0:
        raise PlanningError(f"temperature must be > 0, got {float(temperature)}")


def _q_columns(values, next_state, reward, discount):
    """The move Q-values as A separate ``[S]`` columns (lets a compiler fuse a whole sweep)."""
    if reward.ndim == 1:
        w = reward + discount * values
        return [w[next_state[:, a]] for a in range(next_state.shape[1])]
    return [reward[:, a] + discount * values[next_state[:, a]] for a in range(next_state.shape[1])]


def soft_backup(values, next_state, reward, stop_reward, discount, temperature, terminal=None):
    """One soft-max Bellman backup ``T * logsumexp(Q / T)``; returns new values ``[S]``.

    Written column by column with an explicit max shift rather than
    ``torch.logsumexp`` over a concatenated ``[S, A+1]`` tensor: the result is
    the same, but eager mode allocates no ``[S, A+1]`` temporaries and
    torch.compile fuses the sweep into one loop over states. Differentiable in
    every tensor argument (MLIRL differentiates it at the fixed point).
    """
    cols = _q_columns(values, next_state, reward, discount)
    if stop_reward is not None:
        cols.append(stop_reward)
    m = cols[0]
    for c in cols[1:]:
        m = torch.maximum(m, c)
    # The max is a constant shift: detaching it leaves value and gradient unchanged.
    m = m.detach()
    total = torch.exp((cols[0] - m) / temperature)
    for c in cols[1:]:
        total = total + torch.exp((c - m) / temperature)
    new = m + temperature * torch.log(total)
    if terminal is not None:
        new = torch.where(terminal, torch.zeros_like(new), new)
    return new


def soft_value_iteration(
    next_state,
    reward,
    discount: float = 0.99,
    temperature: float | torch.Tensor = 1.0,
    terminal=None,
    stop_reward=None,
    tol: float = 1e-4,
    max_sweeps: int = 10_000,
    initial_values=None,
    dtype: torch.dtype = torch.float32,
    backend: str = "auto",
    policy_states=None,
) -> SoftValueResult:
    """Soft-max value iteration on a deterministic MDP.

    Args:
        next_state: ``[S, A]`` integer successor indices (numpy or torch).
        reward: ``[S]`` arrival reward, ``[S, A]`` state-action reward, or a scalar.
        discount: in (0, 1]; with 1 the step cost must keep values bounded.
        temperature: Boltzmann temperature T > 0 (float or 0-dim tensor).
        terminal: ``[S]`` bool, absorbing states (value 0, only TERMINATE), or None.
        stop_reward: ``[S]`` reward of the TERMINATE action, or None for no such action.
        tol: converged when ``max |V_new - V| <= tol`` (checked every few sweeps).
        initial_values: ``[S]`` warm start (default zeros).
        backend: "eager", "compiled" (torch.compile; falls back to eager if it fails)
            or "auto" (compiled from ``COMPILE_MIN_STATES`` states; in a process that plans once,
            ``sweeps.plan_once()``, from ``COMPILE_AT_ONCE_STATES``).
        policy_states: indices of the states whose values, Q-values and policy are wanted (default
            all): a demonstration's likelihood needs its own states' only, and the last backup over
            every state of a large space costs as much as a few sweeps.
    Raises PlanningError (a ValueError) naming any array of the wrong shape.
    """
    _check_scalars(discount, temperature)
    ns = as_transitions(next_state)
    S, A = ns.shape
    r = _reward(reward, S, A, dtype)
    stop = None if stop_reward is None else _vector(stop_reward, "stop_reward", S, dtype)
    term = None if terminal is None else _vector(terminal, "terminal", S, torch.bool)
    if term is not None and stop is None:
        stop = torch.zeros(S, dtype=dtype)  # absorbing states need an action: terminate
    T = torch.as_tensor(temperature, dtype=dtype)
    v0 = torch.zeros(S, dtype=dtype) if initial_values is None else _vector(initial_values, "initial_values", S, dtype)
    columns = transition_columns(ns)
    with threads_for(S):
        carry, sweeps, residual = solve_values(v0, columns, r, stop, float(discount), T, term, tol, max_sweeps,
                                               backend)
        if policy_states is None:
            values, q, log_policy = policy_from_carry(carry, columns, r, stop, T, term)
        else:
            rows = torch.as_tensor(np.asarray(policy_states, dtype=np.int64))
            if rows.ndim != 1 or (len(rows) and (int(rows.min()) < 0 or int(rows.max()) >= S)):
                raise PlanningError(f"policy_states must be state indices 0..{S - 1}, got shape {tuple(rows.shape)}")
            values, q, log_policy = policy_from_carry(
                carry, columns[:, rows], r[rows] if r.ndim == 2 else r, None if stop is None else stop[rows], T,
                None if term is None else term[rows])
    converged = residual <= tol
    if not converged:
        logger.info("soft value iteration: %d sweeps, residual %.3g > tol %.3g", sweeps, residual, tol)
    return SoftValueResult(values, q, log_policy, sweeps, converged, residual)


def demonstration_log_likelihood(log_policy, states, actions, terminate: bool = True) -> torch.Tensor:
    """``sum_t log pi(a_t | s_t) + log pi(TERMINATE | s_T)`` of one demonstration (0-dim tensor).

    ``states`` are ``T + 1`` state indices, ``actions`` ``T`` move indices
    (0..3). With ``terminate`` (default) the final stop is part of the
    demonstration; the log-policy must then have a TERMINATE column.
    """
    lp = torch.as_tensor(log_policy)
    s = torch.as_tensor(np.asarray(states, dtype=np.int64))
    a = torch.as_tensor(np.asarray(actions, dtype=np.int64))
    if s.ndim != 1 or a.ndim != 1 or len(s) != len(a) + 1:
        raise PlanningError(
            f"a demonstration needs T + 1 states and T actions, got states {tuple(s.shape)} and actions {tuple(a.shape)}"
        )
    if len(a) and (int(a.min()) < 0 or int(a.max()) >= min(lp.shape[1], TERMINATE)):
        raise PlanningError(f"actions must be move indices 0..3, got {a.tolist()}")
    total = lp[s[:-1], a].sum()
    if terminate:
        if lp.shape[1] <= TERMINATE:
            raise PlanningError(
                f"log_policy of shape {tuple(lp.shape)} has no TERMINATE column; solve with a stop_reward"
            )
        total = total + lp[s[-1], TERMINATE]
    return total


@dataclass(frozen=True)
class TaskSettings:
    """Reward and solver settings for a grounded goal (part of every cache key).

    Moves cost ``step_cost``; TERMINATE pays ``goal_reward`` where the goal
    holds and 0 elsewhere (giving up). Goal states do not absorb by default:
    the episode ends only by terminating, so a demonstration that walks on
    through a goal state is improbable but not impossible, which keeps
    likelihood tables finite for noisy demonstrations. With
    ``absorbing_goal`` the goal ends the episode on arrival (paying
    ``goal_reward`` then) and walking on has likelihood -inf.

    The defaults keep the soft values bounded even at discount 1
    (``step_cost > temperature * log 5``) and make a goal up to about 80 steps
    away worth pursuing (``goal_reward * 0.995**d > sum of discounted step
    costs``); a temperature of half a step cost makes a move that wastes two
    steps about e^-4 times as likely as the best one.
    """

    goal_reward: float = 100.0
    step_cost: float = 1.0
    discount: float = 0.995
    temperature: float = 0.5
    absorbing_goal: bool = False
    tol: float = 1e-4
    max_sweeps: int = 5000

    def __post_init__(self):
        # Checked here, not by each reader: a saved model's planning settings come from a file, and
        # step_cost=-1e308 overflowed deep inside the solver instead of being refused.
        for name, low, high in (("goal_reward", -1e6, 1e6), ("step_cost", 0.0, 1e6), ("discount", 0.0, 1.0),
                                ("temperature", 0.0, 1e6), ("tol", 0.0, 1e3)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= high:
                raise PlanningError(f"planning setting {name}={value!r}: expected a number from {low:g} to {high:g}")
        for name in ("discount", "temperature", "tol"):
            if not getattr(self, name) > 0:
                raise PlanningError(f"planning setting {name}={getattr(self, name)!r}: expected a number above 0")
        if not isinstance(self.absorbing_goal, bool):
            raise PlanningError(f"planning setting absorbing_goal={self.absorbing_goal!r}: expected true or false")
        if isinstance(self.max_sweeps, bool) or not isinstance(self.max_sweeps, int) or not 1 <= self.max_sweeps <= 10**6:
            raise PlanningError(f"planning setting max_sweeps={self.max_sweeps!r}: expected an integer from 1 to 1000000")

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def task_rewards(goal_mask, settings: TaskSettings = TaskSettings()):
    """``(reward [S], stop_reward [S], terminal [S] or None)`` for a goal mask ``[S]`` bool."""
    goal = torch.as_tensor(np.asarray(goal_mask, dtype=bool))
    if goal.ndim != 1:
        raise PlanningError(f"goal_mask must be [S] bool, got shape {tuple(goal.shape)}")
    reward = torch.full(goal.shape, -float(settings.step_cost))
    if settings.absorbing_goal:
        reward = reward + float(settings.goal_reward) * goal
        return reward, torch.zeros(goal.shape), goal
    return reward, float(settings.goal_reward) * goal.float(), None


def solve_task(next_state, goal_mask, settings: TaskSettings = TaskSettings(), **kwargs) -> SoftValueResult:
    """Soft value iteration for the task "make the goal hold, then terminate"."""
    reward, stop, terminal = task_rewards(goal_mask, settings)
    if len(reward) != np.shape(next_state)[0]:
        raise PlanningError(
            f"goal_mask has {len(reward)} entries but next_state has {np.shape(next_state)[0]} states"
        )
    return soft_value_iteration(
        next_state, reward, settings.discount, settings.temperature, terminal, stop,
        tol=settings.tol, max_sweeps=settings.max_sweeps, **kwargs,
    )


def task_log_likelihood(space, goal_mask, demo_states, demo_actions, settings: TaskSettings = TaskSettings()) -> float:
    """Log-likelihood of one demonstration (state indices ``[T+1]``, moves ``[T]``) under a grounded goal."""
    result = solve_task(space.next_state, goal_mask, settings)
    return float(demonstration_log_likelihood(result.log_policy, demo_states, demo_actions))
