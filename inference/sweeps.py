"""The sweep engine under soft value iteration: carried soft Bellman sweeps, eager or torch.compile'd.

One sweep reads the transition table as int32 columns ``[A, S]`` and gathers
from one carried array ``W = arrival_reward + discount * V`` (so the arrival
reward costs no second gather); the log-sum-exp over the moves and the
terminate action runs action by action with a running max, so the compiled
kernel is a single loop over states with no ``[S, A]`` float temporaries.
Sweeps ping-pong between two preallocated buffers (a fresh multi-megabyte
output per sweep would cost page faults) and the residual ``max |dV|`` is
fused into every ``CHECK_EVERY``-th sweep. :mod:`groundlang.inference.planning`
holds the public API on top of it.
"""

from __future__ import annotations

import contextlib
import logging
import warnings

import numpy as np
import torch

__all__ = [
    "TERMINATE",
    "PlanningError",
    "threads_for",
    "transition_columns",
    "carry_sweep",
    "run_compiled",
    "use_compiled",
    "plan_once",
    "solve_values",
    "policy_from_carry",
    "predecessor_table",
    "adjoint_sweep",
    "solve_adjoint",
]

logger = logging.getLogger(__name__)

TERMINATE = 4
"""Index of the terminate action in Q-values and policies that have one."""

# Sweeps per convergence check: the fused residual reads W once more and
# converts to a Python float; every few sweeps is enough.
CHECK_EVERY = 8
# From this many states "auto" compiles: the kernel is 5-10x faster than
# eager there, and one dynamic-shape compilation (a few seconds, once per
# process) serves every state count.
COMPILE_MIN_STATES = 50_000
# ... in a process that plans once (`groundlang follow`: plan_once()), from this many:
# one solve (some 70 sweeps, 250 to 650 ns a state eager) is then worth a compilation
# (3 to 8 s) alone. A rule of the state count and the process's kind, not of what the
# process did before, so that a solve's values do not depend on which solves came first
# (compiled and eager sweeps differ in the last bits). Figures: benchmarks/bench_first_plan.py.
COMPILE_AT_ONCE_STATES = 500_000
_COMPILE_FROM = [COMPILE_MIN_STATES]


def plan_once() -> None:
    """Say that this process plans once (a command-line ``follow``): "auto" compiles only from
    :data:`COMPILE_AT_ONCE_STATES` states, where one solve pays for the compilation."""
    _COMPILE_FROM[0] = COMPILE_AT_ONCE_STATES

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


def transition_columns(next_state: torch.Tensor) -> torch.Tensor:
    """``next_state[S, A]`` as a contiguous int32 ``[A, S]`` table: each action's successors lie in one
    contiguous column, so a sweep streams four plain arrays, at half the bytes of int64."""
    return next_state.t().to(torch.int32).contiguous()


def carry_sweep(out, carry, columns, arrival, action_reward, stop, discount: float, temperature, terminal,
                residual: bool = False):
    """One soft Bellman sweep on the *carried* array ``W = arrival + discount * V``, written into ``out``.

    Carrying ``W`` rather than ``V`` makes the arrival reward part of the one
    gathered array: ``Q(s, a) = W[next_state[s, a]] (+ action_reward[a, s])``,
    so a sweep reads next_state ``[A, S]`` (int32 columns), ``stop``,
    ``arrival`` and gathers from ``W``, and writes ``out``: no ``[S, A]``
    float temporaries once compiled. The log-sum-exp runs action by action
    with a running max. With ``residual`` it also returns ``max |out - W|``
    (``discount * max |dV|``), fused into the same pass.
    """
    q = torch.gather(carry.expand(columns.shape[0], -1), 1, columns)
    if action_reward is not None:
        q = q + action_reward
    cols = list(q.unbind(0)) + ([stop] if stop is not None else [])
    m = cols[0]
    for c in cols[1:]:
        m = torch.maximum(m, c)
    inv = 1.0 / temperature
    total = torch.exp((cols[0] - m) * inv)
    for c in cols[1:]:
        total = total + torch.exp((c - m) * inv)
    values = m + temperature * torch.log(total)
    if terminal is not None:
        values = torch.where(terminal, torch.zeros_like(values), values)
    new = arrival + discount * values
    out.copy_(new)
    return (new - carry).abs().amax() if residual else None


_COMPILED: dict = {}


def _quiet_inductor_imports() -> None:
    """Import torch's own ``torch/utils/mkldnn.py`` once, without its warnings. Compiling imports it
    through inductor, and it still decorates with the deprecated ``torch.jit.script_method``: one
    DeprecationWarning per method (14 in a test run), about torch's file, not ours; a warning our
    own use of torch raised would still show."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="`torch.jit.script_method` is", category=DeprecationWarning)
        try:
            import torch.utils.mkldnn  # noqa: F401
        except ImportError:  # a torch without it: nothing to quieten
            pass


def compiled(fn):
    """``torch.compile(fn)`` with dynamic shapes (one compilation serves every state count), or None where
    compilation does not work here (logged once, then eager)."""
    if fn not in _COMPILED:
        _quiet_inductor_imports()
        try:
            _COMPILED[fn] = torch.compile(fn, fullgraph=True, dynamic=True)
        except Exception as exc:  # any failure in the compiler stack: fall back, do not crash
            logger.warning("torch.compile unavailable (%s: %s); using eager sweeps", type(exc).__name__, exc)
            _COMPILED[fn] = None
    return _COMPILED[fn]


def run_compiled(fn, *args, **kwargs):
    """Call the compiled ``fn`` if it works, else ``fn`` itself; a compiler failure is logged once."""
    kernel = compiled(fn)
    if kernel is not None:
        try:
            return kernel(*args, **kwargs)
        except Exception as exc:  # e.g. no C++ compiler: remember, fall back to eager
            logger.warning("torch.compile failed (%s: %s); using eager sweeps", type(exc).__name__, exc)
            _COMPILED[fn] = None
    return fn(*args, **kwargs)


def use_compiled(num_states: int, backend: str) -> bool:
    if backend not in ("auto", "eager", "compiled"):
        raise PlanningError(f"backend must be 'auto', 'eager' or 'compiled', got {backend!r}")
    return backend == "compiled" or (backend == "auto" and num_states >= _COMPILE_FROM[0])


def _split_reward(reward):
    """``(arrival [S] or 0-dim, action_reward [A, S] or None)`` for a reward ``[S]``, ``[S, A]`` or scalar."""
    if reward.ndim == 2:
        return torch.zeros((), dtype=reward.dtype), reward.t().contiguous()
    if reward.ndim == 1 and reward.stride(0) == 0:
        return reward[0], None  # a broadcast scalar: do not stream S copies of it
    return reward, None


def solve_values(values, columns, reward, stop, discount, temperature, terminal, tol, max_sweeps, backend):
    """Sweep from ``values [S]`` until ``max |dV| <= tol`` (checked every CHECK_EVERY sweeps) or ``max_sweeps``.

    Returns ``(carry [S], sweeps, residual)`` where ``carry = arrival + discount * V``
    (see :func:`carry_sweep`); :func:`policy_from_carry` turns it into values and a policy.
    Raises PlanningError when the values diverge.
    """
    arrival, action_reward = _split_reward(reward)
    fast = use_compiled(columns.shape[1], backend)
    step = (lambda *a, **k: run_compiled(carry_sweep, *a, **k)) if fast else carry_sweep
    carry = (arrival + discount * values).expand(columns.shape[1]).contiguous()
    spare = torch.empty_like(carry)
    sweeps, residual = 0, float("inf")
    with torch.no_grad():
        while sweeps < max_sweeps:
            sweeps += 1
            check = sweeps % CHECK_EVERY == 0 or sweeps == max_sweeps
            res = step(spare, carry, columns, arrival, action_reward, stop, discount, temperature, terminal, check)
            carry, spare = spare, carry
            if not check:
                continue
            residual = float(res) / discount
            if not np.isfinite(residual):
                raise PlanningError(
                    f"soft value iteration diverged after {sweeps} sweeps (residual {residual}); "
                    "with discount 1 the step cost must exceed temperature * log(number of actions)"
                )
            if residual <= tol:
                break
    return carry, sweeps, residual


def policy_from_carry(carry, columns, reward, stop, temperature, terminal=None):
    """``(values [S], q_values [S, A(+1)], log_policy [S, A(+1)])`` from a carried array (one more backup)."""
    q = carry[columns].t()
    if reward.ndim == 2:
        q = q + reward
    if stop is not None:
        q = torch.cat([q, stop[:, None]], dim=1)
    values = temperature * torch.logsumexp(q / temperature, dim=1)
    log_policy = (q - values[:, None]) / temperature
    if terminal is not None:
        values = torch.where(terminal, torch.zeros_like(values), values)
        absorbing = torch.full_like(log_policy[0], float("-inf"))
        absorbing[TERMINATE] = 0.0
        log_policy = torch.where(terminal[:, None], absorbing, log_policy)
    return values, q, log_policy


def predecessor_table(next_state: torch.Tensor):
    """The reverse of ``next_state [S, A]`` as a padded gather table, built once per state space.

    Returns ``(slots [K, S] int64, states [K, S] int32)`` with K the largest
    in-degree: ``slots[k, t]`` is the flat index ``s * A + a`` of the k-th
    transition into ``t`` (``S * A`` for padding) and ``states[k, t] = s``
    (0 for padding). The adjoint iteration then gathers instead of
    scatter-adding: no atomics, no serial index_add_, deterministic.
    """
    ns = next_state.numpy().reshape(-1)
    S, A = next_state.shape
    order = np.argsort(ns, kind="stable")
    degree = np.bincount(ns, minlength=S)
    first = np.cumsum(degree) - degree
    target = ns[order]
    rank = np.arange(S * A) - first[target]
    slots = np.full((int(degree.max()), S), S * A, dtype=np.int64)
    slots[rank, target] = order
    states = np.where(slots < S * A, slots // A, 0).astype(np.int32)
    return torch.from_numpy(slots), torch.from_numpy(states)


def adjoint_sweep(out, lam, grad, weights, states, discount: float):
    """One step of ``lam = grad + discount * P^T lam`` into ``out``; returns ``(max |dlam|, max |lam|)``.

    ``weights [K, S]`` are ``pi(a|s)`` of the transitions into each state and
    ``states [K, S]`` where they come from (:func:`predecessor_table`).
    """
    spread = (weights * torch.gather(lam.expand(states.shape[0], -1), 1, states)).sum(0)
    new = grad + discount * spread
    out.copy_(new)
    return torch.stack([(new - lam).abs().amax(), new.abs().amax()])


def solve_adjoint(grad, move_prob, predecessors, discount: float, tol: float, max_steps: int, backend: str,
                  initial=None):
    """``(lam [S], steps)`` with ``lam = grad + discount * P^T lam``, ``P[s, t] = sum of pi(a|s) over a with
    next_state[s, a] = t``: the adjoint of the soft Bellman fixed point, by Jacobi steps.

    ``move_prob [S, A]``; ``predecessors`` from :func:`predecessor_table`;
    ``initial`` a warm start (e.g. the previous gradient's ``lam``).
    Stops when a step changes ``lam`` by at most ``tol * (1 + max |lam|)``; the
    remaining error can be about ``1 / (1 - discount)`` times that.
    """
    slots, states = predecessors
    flat = torch.cat([move_prob.reshape(-1), move_prob.new_zeros(1)])
    weights = flat[slots]  # [K, S]
    lam = grad.clone() if initial is None or initial.dtype != grad.dtype else initial.clone()
    spare = torch.empty_like(lam)
    fast = use_compiled(grad.shape[0], backend)
    step = 0
    while step < max_steps:
        step += 1
        if fast:
            stats = run_compiled(adjoint_sweep, spare, lam, grad, weights, states, discount)
        else:
            stats = adjoint_sweep(spare, lam, grad, weights, states, discount)
        lam, spare = spare, lam
        # The stopping rule of the original implementation, checked every step (a CPU reduction fused
        # into the step; the float conversion costs microseconds). Fitted weights in the tests were
        # calibrated with it: along the flat directions of the likelihood, a more accurate adjoint
        # moves L-BFGS to a different, equally likely optimum.
        change, size = stats.tolist()
        if change <= tol * (1.0 + size):
            break
    return lam, step
