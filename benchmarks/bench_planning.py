"""Soft value iteration and MLIRL speed against the machine's memory bandwidth.

Prints, in one run:
- streaming bandwidth, measured here as a large float32 array copy (bytes read + written per second);
- per Cleanup world of about 10^4 (one toy), 10^5 and 10^6 (two toys) reachable states
  (``bench_statespace.benchmark_layouts()``): the time of one soft value iteration sweep for the
  eager torch kernel, the torch.compile'd kernel (if compilation works here) and a straightforward
  numpy implementation, each also as a multiple of the memory-traffic lower bound of one sweep
  (bytes of ``next_state`` + the reward, stop-reward and value arrays read and the values written,
  divided by the bandwidth);
- one MLIRL gradient step (a full solve, warm-started as in the MLIRL loop, plus its implicit
  gradient) at 10^4 and 10^5 states (goals: 20 ms and 300 ms), and at 10^6 with its peak memory
  (goal: under 4 GiB; peak resident set size of this process, so the figure includes Python and torch).

No timing asserts. Other processes sharing the cores distort the figures: run it on a quiet machine.
Usage: python benchmarks/bench_planning.py [--repeats N] [--skip-large] [--no-compile]
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

from groundlang.inference import planning  # noqa: E402
from groundlang.inference.mlirl import MLIRLProblem, _temperature  # noqa: E402
from groundlang.logic.atoms import Atom  # noqa: E402
from groundlang.model.features import feature_matrix, goal_mask, position_atoms  # noqa: E402
from groundlang.model.geometry import cell_tables  # noqa: E402
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--skip-large", action="store_true", help="skip the 10^6-state world")
    parser.add_argument("--no-compile", action="store_true", help="skip torch.compile")
    args = parser.parse_args()

    bw = bandwidth(args.repeats)
    print(f"torch {torch.__version__}, {torch.get_num_threads()} threads")
    print(f"streaming bandwidth (copy): {bw / 1e9:.1f} GB/s")
    compiled = None
    if not args.no_compile:
        start = time.perf_counter()
        compiled = planning._compiled_sweeps()
        print(f"torch.compile: {'ok' if compiled else 'unavailable'} ({time.perf_counter() - start:.1f} s first use)")
    print()
    worlds = benchmark_layouts()
    if args.skip_large:
        worlds = worlds[:2]
    for size, (name, state) in enumerate(worlds):
        space = enumerate_states(state)
        S = space.num_states
        tables = cell_tables(space.layout)
        goal = goal_mask(space, [Atom("toyInRoom", ("block0", "room1"))], tables)
        ns32 = torch.from_numpy(space.next_state)  # int32 [S, 4]
        ns = ns32.long()
        reward, stop, _ = planning.task_rewards(goal)
        T = torch.tensor(0.5)
        V = torch.zeros(S)
        # One sweep reads next_state, reward, stop and V (streamed; the gather hits V again in cache)
        # and writes V.
        lower_bound = (ns32.numel() * 4 + 4 * S * 4) / bw
        print(f"{name}: {S:,} states; one-sweep memory-traffic bound {lower_bound * 1e3:.3f} ms")
        with planning.threads_for(S):
            per = best(lambda: planning._sweeps_eager(V, ns, reward, stop, 0.995, T, None, 8), args.repeats) / 8
            print(f"  sweep, torch eager:    {per * 1e3:8.3f} ms = {per / lower_bound:6.1f} x bound")
            if compiled:
                compiled(V, ns, reward, stop, 0.995, T, None, 8)  # specialise for this size
                per = best(lambda: compiled(V, ns, reward, stop, 0.995, T, None, 8), args.repeats) / 8
                print(f"  sweep, torch.compile:  {per * 1e3:8.3f} ms = {per / lower_bound:6.1f} x bound")
            nv, nns, nr, nst = V.numpy(), space.next_state, reward.numpy(), stop.numpy()
            per = best(lambda: numpy_sweep(nv, nns, nr, nst, 0.995, 0.5), max(1, args.repeats // 2))
            print(f"  sweep, numpy:          {per * 1e3:8.3f} ms = {per / lower_bound:6.1f} x bound")

            features = feature_matrix(space, position_atoms(space.layout), tables)
            demo_states, demo_actions = _demonstration(space, goal)
            problem = MLIRLProblem(space.next_state, features, [(demo_states, demo_actions)], backend="auto")
            theta = torch.zeros(problem.num_features, requires_grad=True)
            log_t = torch.tensor(0.0, requires_grad=True)

            def step(scale=[1.0]):
                # Change the weights a little each step, as an optimiser would.
                scale[0] += 0.01
                with torch.no_grad():
                    theta.fill_(scale[0])
                theta.grad = None
                problem.log_likelihood(theta, _temperature(log_t)).backward()

            cold_start = time.perf_counter()
            step()
            cold = time.perf_counter() - cold_start
            warm = best(step, max(1, args.repeats if size < 2 else 2))
            goal_ms = {0: " (goal 20 ms)", 1: " (goal 300 ms)"}.get(size, "")
            print(f"  MLIRL step (solve + gradient): {warm * 1e3:.1f} ms warm-started{goal_ms}, "
                  f"{cold * 1e3:.1f} ms cold; {problem.last_sweeps} sweeps in the last solve")
        if size == 2:
            print(f"  peak memory (process RSS) after the 10^6 MLIRL step: {peak_rss_gib():.2f} GiB (goal < 4 GiB)")
        print()


def _demonstration(space, goal):
    """A greedy expert's trajectory to the goal from the initial state (or a short walk if unreachable)."""
    result = planning.solve_task(space.next_state, goal, planning.TaskSettings(max_sweeps=3000))
    path = planning.rollout(space.next_state, result, start=0, max_steps=200)
    if len(path.actions) == 0:
        path = planning.rollout(space.next_state, np.eye(5)[[2] * space.num_states], start=0, max_steps=3)
    return path.states, path.actions


if __name__ == "__main__":
    main()
