"""Soft value iteration, Boltzmann policies with a terminate action, demonstration likelihoods, rollouts.

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

Jacobi sweeps are vectorised gathers over ``next_state``: no loop over
states. Sweeps stop when ``max |V_new - V| <= tol`` (converged) or at
``max_sweeps`` (not converged; reported, never raised). Float32 by default:
the sweep is memory-bound and float32 halves the traffic; pass ``dtype``
float64 for gradient checks.
"""

from __future__ import annotations

import contextlib
import logging
from dataclasses import dataclass

import numpy as np
import torch

__all__ = [
    "TERMINATE",
    "PlanningError",
    "SoftValueResult",
    "TaskSettings",
    "Rollout",
    "as_transitions",
    "threads_for",
    "soft_value_iteration",
    "soft_backup",
    "task_rewards",
    "solve_task",
    "demonstration_log_likelihood",
    "task_log_likelihood",
    "rollout",
    "rollout_states",
]

logger = logging.getLogger(__name__)

TERMINATE = 4
"""Index of the terminate action in Q-values and policies that have one."""

# Sweeps per convergence check: the residual costs a reduction and, in the
# compiled path, a graph break; checking every few sweeps is cheaper.
CHECK_EVERY = 8
# Below this many states a compiled kernel does not repay its start-up cost.
COMPILE_MIN_STATES = 200_000


# Below this many states one thread is faster: each op is a few microseconds
# of work, and waking a second OpenMP thread costs more than it saves (10x
# more when other processes share the cores).
PARALLEL_MIN_STATES = 50_000


@contextlib.contextmanager
def threads_for(num_states: int):
    """Run torch single-threaded inside the block when ``num_states`` is small; restores the setting."""
    before = torch.get_num_threads()
    if num_states >= PARALLEL_MIN_STATES or before == 1:
        yield
        return
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(before)


class PlanningError(ValueError):
    """Arrays of the wrong shape or type for planning; the message names the array and its shape."""


@dataclass(frozen=True)
class SoftValueResult:
    """Output of :func:`soft_value_iteration`.

    values ``[S]``; q_values and log_policy ``[S, A]`` or ``[S, A + 1]`` when
    a terminate action exists (column ``TERMINATE``); ``sweeps`` done;
    ``converged`` when the last residual ``max |dV|`` was ``<= tol``.
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


def move_q(values, next_state, reward, discount):
    """Q-values of the moves ``[S, A]`` given values ``[S]``: one gather over ``next_state``."""
    if reward.ndim == 1:
        # Arrival reward: gather reward + discount * V in one pass.
        return (reward + discount * values)[next_state]
    return reward + discount * values[next_state]


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


def _sweeps_eager(values, next_state, reward, stop_reward, discount, temperature, terminal, count: int):
    for _ in range(count - 1):
        values = soft_backup(values, next_state, reward, stop_reward, discount, temperature, terminal)
    new = soft_backup(values, next_state, reward, stop_reward, discount, temperature, terminal)
    return new, (new - values).abs().max()


_COMPILED = None


def _compiled_sweeps():
    """torch.compile'd block of sweeps, or None where compilation does not work (logged once)."""
    global _COMPILED
    if _COMPILED is None:
        try:
            fn = torch.compile(_sweeps_eager, fullgraph=True)
            S = 64
            ns = torch.randint(0, S, (S, 4))
            fn(torch.zeros(S), ns, torch.zeros(S), torch.zeros(S), 0.9, torch.tensor(1.0), None, 2)
            _COMPILED = fn
        except Exception as exc:  # any failure in the compiler stack: fall back, do not crash
            logger.warning("torch.compile unavailable (%s: %s); using eager sweeps", type(exc).__name__, exc)
            _COMPILED = False
    return _COMPILED or None


def _run_sweeps(values, ns, reward, stop, discount, temperature, terminal, tol, max_sweeps, backend):
    use_compiled = backend == "compiled" or (backend == "auto" and ns.shape[0] >= COMPILE_MIN_STATES)
    sweeps_fn = (_compiled_sweeps() if use_compiled else None) or _sweeps_eager
    sweeps, residual = 0, float("inf")
    with torch.no_grad():
        while sweeps < max_sweeps:
            count = min(CHECK_EVERY, max_sweeps - sweeps)
            values, res = sweeps_fn(values, ns, reward, stop, discount, temperature, terminal, count)
            sweeps += count
            residual = float(res)
            if not np.isfinite(residual):
                raise PlanningError(
                    f"soft value iteration diverged after {sweeps} sweeps (residual {residual}); "
                    "with discount 1 the step cost must exceed temperature * log(number of actions)"
                )
            if residual <= tol:
                break
    return values, sweeps, residual


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
            or "auto" (compiled from ``COMPILE_MIN_STATES`` states).
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
    with threads_for(S):
        values, sweeps, residual = _run_sweeps(v0, ns, r, stop, float(discount), T, term, tol, max_sweeps, backend)
        q, log_policy = policy_from_values(values, ns, r, stop, float(discount), T, term)
    converged = residual <= tol
    if not converged:
        logger.info("soft value iteration: %d sweeps, residual %.3g > tol %.3g", sweeps, residual, tol)
    return SoftValueResult(values, q, log_policy, sweeps, converged, residual)


def policy_from_values(values, ns, reward, stop, discount, temperature, terminal=None):
    """Q-values and Boltzmann log-policy ``[S, A(+1)]`` from values ``[S]``."""
    q = move_q(values, ns, reward, discount)
    if stop is not None:
        q = torch.cat([q, stop[:, None]], dim=1)
    log_policy = torch.log_softmax(q / temperature, dim=1)
    if terminal is not None:
        absorbing = torch.full_like(log_policy[0], float("-inf"))
        absorbing[TERMINATE] = 0.0
        log_policy = torch.where(terminal[:, None], absorbing, log_policy)
    return q, log_policy


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


def rollout_states(space, trajectory: Rollout):
    """The trajectory in the corpus's terms: ``(list of model.world.State, list of Action)``."""
    from groundlang.model.world import Action

    return [space.state_at(int(i)) for i in trajectory.states], [Action(int(a)) for a in trajectory.actions]
