"""Soft value iteration and MLIRL speed against the machine's memory bandwidth.

Prints, in one run:
- the load average (other processes on the cores distort every figure) and the thread count;
- streaming bandwidth, measured here as a 256 MiB float32 array copy (bytes read + written per second);
- per Cleanup world of about 10^4 (one toy), 10^5 and 10^6 (two toys) reachable states
  (``bench_statespace.benchmark_layouts()``): the time of one soft value iteration sweep for the
  eager torch kernel, the torch.compile'd kernel (if compilation works here) and a straightforward
  numpy implementation, each also as a multiple of the memory-traffic lower bound of one sweep.
  The bound counts the bytes one sweep of this kernel must move, once each: ``next_state`` as int32
  ``[A, S]`` (16 B/state), the arrival-reward, stop-reward and carried-value arrays read and the new
  values written (4 x 4 B/state); the gathers re-read the value array, counted once (as if cached).
  At 10^6 states that is 37 MB, about the size of the last-level cache, so some of it may come
  from cache and the bound (DRAM bandwidth) is not a hard floor there;
- one full solve from zero values (sweeps to tol 1e-4) per world;
- one MLIRL gradient step (a full solve, warm-started as in the MLIRL loop, plus its implicit
  gradient) at 10^4, 10^5 and 10^6 states (goals: 20 ms at 10^4, 300 ms at 10^5), and the peak
  memory of the process after the 10^6 step (goal: under 4 GiB; peak resident set size of this
  process, so the figure includes Python, torch and the earlier benchmarks).

No timing asserts. Each figure is the best of ``--repeats`` runs.
Usage: python benchmarks/bench_planning.py [--repeats N] [--skip-large] [--no-compile] [--threads N]
"""

from __future__ import annotations

import argparse
import resource
import sys
import time
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).parent))
from bench_statespace import benchmark_layouts  # noqa: E402

from groundlang.inference import planning, sweeps  # noqa: E402
from groundlang.inference.acting import rollout  # noqa: E402
from groundlang.inference.mlirl import MLIRLProblem, _temperature, mlirl  # noqa: E402
from groundlang.logic.atoms import Atom  # noqa: E402
from groundlang.model.features import feature_matrix, goal_mask, position_atoms  # noqa: E402
from groundlang.model.pf_tables import pf_tables  # noqa: E402
from groundlang.model.statespace import enumerate_states  # noqa: E402


def best(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def bandwidth(repeats: int) -> float:
    a = torch.ones(64 * 2**20)  # 256 MiB, far beyond any cache
    b = torch.empty_like(a)
    seconds = best(lambda: b.copy_(a), repeats)
    return 2 * a.numel() * 4 / seconds


def numpy_sweep(V, ns, reward, stop, discount, temperature):
    """The textbook version: gather, concatenate, logsumexp."""
    q = np.concatenate([(reward + discount * V)[ns], stop[:, None]], axis=1)
    m = q.max(axis=1)
    return m + temperature * np.log(np.exp((q - m[:, None]) / temperature).sum(axis=1))


def peak_rss_gib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20


def load_average() -> str:
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "unknown"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--skip-large", action="store_true", help="skip the 10^6-state world")
    parser.add_argument("--no-compile", action="store_true", help="skip torch.compile")
    parser.add_argument("--threads", type=int, default=None, help="torch threads (default: torch's)")
    args = parser.parse_args()
    if args.threads:
        torch.set_num_threads(args.threads)

    print(f"load average (1, 5, 15 min) at start: {load_average()}")
    bw = bandwidth(args.repeats)
    print(f"torch {torch.__version__}, {torch.get_num_threads()} threads")
    print(f"streaming bandwidth (copy): {bw / 1e9:.1f} GB/s")
    backend = "eager" if args.no_compile else "compiled"
    print()
    worlds = benchmark_layouts()
    if args.skip_large:
        worlds = worlds[:2]
    for size, (name, state) in enumerate(worlds):
        space = enumerate_states(state)
        S = space.num_states
        tables = pf_tables(space.layout)
        goal = goal_mask(space, [Atom("toyInRoom", ("block0", "room1"))], tables)
        columns = sweeps.transition_columns(torch.from_numpy(space.next_state))  # int32 [A, S]
        reward, stop, _ = planning.task_rewards(goal)
        reward = reward.contiguous()  # a real [S] array, as the bound counts it
        T = torch.tensor(0.5)
        W = torch.zeros(S)
        out = torch.empty(S)
        lower_bound = (columns.numel() * 4 + 4 * S * 4) / bw
        print(f"{name}: {S:,} states; one-sweep memory-traffic bound {lower_bound * 1e3:.3f} ms")
        with sweeps.threads_for(S):
            def eager():
                sweeps.carry_sweep(out, W, columns, reward, None, stop, 0.995, T, None)

            per = best(eager, args.repeats)
            print(f"  sweep, torch eager:    {per * 1e3:8.3f} ms = {per / lower_bound:6.1f} x bound")
            if not args.no_compile:
                start = time.perf_counter()
                sweeps.run_compiled(sweeps.carry_sweep, out, W, columns, reward, None, stop, 0.995, T, None)
                first = time.perf_counter() - start
                usable = sweeps.compiled(sweeps.carry_sweep) is not None

                def fast():
                    sweeps.run_compiled(sweeps.carry_sweep, out, W, columns, reward, None, stop, 0.995, T, None)

                per = best(fast, 3 * args.repeats)
                status = f"first call {first:.1f} s" if usable else "UNAVAILABLE, eager fallback"
                print(f"  sweep, torch.compile:  {per * 1e3:8.3f} ms = {per / lower_bound:6.1f} x bound ({status})")
            nv, nns, nr, nst = W.numpy(), space.next_state, reward.numpy(), stop.numpy()
            per = best(lambda: numpy_sweep(nv, nns, nr, nst, 0.995, 0.5), max(1, args.repeats // 2))
            print(f"  sweep, numpy:          {per * 1e3:8.3f} ms = {per / lower_bound:6.1f} x bound")

            planning.solve_task(space.next_state, goal, planning.TaskSettings(max_sweeps=16), backend=backend)
            start = time.perf_counter()  # timed after the warm-up above compiled the kernels it uses
            solved = planning.solve_task(space.next_state, goal, backend=backend)
            print(f"  full solve from zero ({backend}): {time.perf_counter() - start:.3f} s, "
                  f"{solved.sweeps} sweeps, converged {solved.converged}")

            features = feature_matrix(space, position_atoms(space.layout), tables)
            demo_states, demo_actions = _demonstration(space, goal, solved)
            step_backend = "eager" if (args.no_compile or size == 0) else "compiled"
            problem = MLIRLProblem(space.next_state, features, [(demo_states, demo_actions)], backend=step_backend)
            theta = torch.zeros(problem.num_features, requires_grad=True)
            log_t = torch.tensor(0.0, requires_grad=True)

            def step(scale=[1.0]):
                # Change the weights a little each step, as an optimiser would.
                scale[0] += 0.01
                with torch.no_grad():
                    theta.fill_(scale[0])
                theta.grad = None
                problem.log_likelihood(theta, _temperature(log_t)).backward()

            start = time.perf_counter()
            step()
            first = time.perf_counter() - start
            warm = best(step, max(1, args.repeats if size < 2 else 3))
            warm_counts = problem.last_sweeps, problem.last_adjoint_steps

            def cold():
                problem.warm_values = problem.warm_adjoint = None
                step()

            cold_time = best(cold, 1 if size == 2 else 2)
            goal_ms = {0: " (goal 20 ms)", 1: " (goal 300 ms)"}.get(size, "")
            print(f"  MLIRL step (solve + gradient, {step_backend}, {problem.num_features} features):")
            print(f"    warm-started values (weights moved by 0.01): {warm * 1e3:8.1f} ms{goal_ms}; "
                  f"{warm_counts[0]} sweeps + {warm_counts[1]} adjoint steps")
            print(f"    cold (values and adjoint from zero):  {cold_time * 1e3:8.1f} ms; "
                  f"{problem.last_sweeps} sweeps + {problem.last_adjoint_steps} adjoint steps")
            print(f"    first call (+ predecessor table, compilation): {first:.2f} s")
            problem.warm_start_adjoint = True
            warm_both = best(step, max(1, args.repeats if size < 2 else 3))
            print(f"    warm-started values and adjoint (warm_start_adjoint=True): {warm_both * 1e3:8.1f} ms; "
                  f"{problem.last_sweeps} sweeps + {problem.last_adjoint_steps} adjoint steps")
            problem.warm_start_adjoint = False
            if size < 2:
                evaluations = []
                problem.warm_values = problem.warm_adjoint = None
                original = problem.log_likelihood

                def counted(*a):
                    evaluations.append(1)
                    return original(*a)

                problem.log_likelihood = counted
                start = time.perf_counter()
                fit = mlirl(None, None, None, problem=problem, max_steps=10)
                seconds = time.perf_counter() - start
                print(f"    real MLIRL fit (L-BFGS, 10 iterations max): {seconds:.2f} s, {len(evaluations)} "
                      f"evaluations = {seconds / len(evaluations) * 1e3:.1f} ms per solve + gradient; "
                      f"{fit.steps} iterations")
        if size == 2:
            print(f"  peak memory (process RSS) after the 10^6 MLIRL step: {peak_rss_gib():.2f} GiB (goal < 4 GiB)")
        print()
    print(f"load average (1, 5, 15 min) at end: {load_average()}")


def _demonstration(space, goal, solved):
    """A greedy expert's trajectory to the goal from the initial state (or a short walk if unreachable)."""
    path = rollout(space.next_state, solved, start=0, max_steps=200)
    if len(path.actions) == 0:
        path = rollout(space.next_state, np.eye(5)[[2] * space.num_states], start=0, max_steps=3)
    return path.states, path.actions


if __name__ == "__main__":
    main()
