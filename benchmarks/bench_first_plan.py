"""When "auto" compiles the value-iteration sweep: one plan in a fresh process, and many.

Under "auto" a space of ``COMPILE_MIN_STATES`` or more is swept by the compiled kernel; in a process
that plans once (``sweeps.plan_once()``, what ``groundlang follow`` calls) only one of
``COMPILE_AT_ONCE_STATES`` or more, where one solve pays for the compilation. Prints, side by side in
one run, for the ~10^5-state world of ``bench_statespace.benchmark_layouts()`` and the default
library's first grounded goal that moves a toy, the wall time of a fresh Python process (imports excluded: timed inside it) that solves the
task once and one that solves it ``--plans`` times, with the backend "eager" (never compile),
"compiled" (always) and "auto" after ``plan_once()``, the last against the better of the other two.

No timing asserts. Usage: python benchmarks/bench_first_plan.py [--plans N]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).parent

_CHILD = """
import sys, time
sys.path.insert(0, {here!r})
import torch
from bench_statespace import benchmark_layouts
from groundlang.inference import planning, sweeps
if {once}:
    sweeps.plan_once()
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.features import goal_mask
from groundlang.model.pf_tables import pf_tables
from groundlang.model.statespace import enumerate_states
from groundlang.model.tasks import candidate_tasks

name, state = benchmark_layouts()[1]
space = enumerate_states(state)
# the default library's first grounded goal that moves a toy (the planner pushes it through a door)
toys = set(space.layout.toy_names)
atoms = next(g.goal for g, _ in candidate_tasks(state, TaskLibrary.load())
             if toys & set(arg for atom in g.goal for arg in atom.args))
goal = goal_mask(space, list(atoms), pf_tables(space.layout))
start = time.perf_counter()
for _ in range({plans}):
    planning.solve_task(space.next_state, goal, backend={backend!r})
print(space.num_states, time.perf_counter() - start)
"""


def run(backend: str, plans: int, once: bool = False) -> tuple[int, float]:
    code = _CHILD.format(here=str(HERE), plans=plans, backend=backend, once=once)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env=dict(os.environ, PYTHONWARNINGS="ignore"))
    states, seconds = out.stdout.split()
    return int(states), float(seconds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plans", type=int, default=30, help="solves in the second process (default 30)")
    args = parser.parse_args()
    print(f"load average (1, 5, 15 min) at start: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    for plans in (1, args.plans):
        times = {}
        for backend in ("eager", "compiled"):
            states, times[backend] = run(backend, plans)
        _, once = run("auto", plans, once=True)
        better = min(times["eager"], times["compiled"])
        print(f"{plans} solve(s) of {states:,} states in a fresh process: eager {times['eager']:.2f} s, "
              f"compiled {times['compiled']:.2f} s, auto after plan_once() {once:.2f} s "
              f"(against the better of the two: {once / better:.2f})")


if __name__ == "__main__":
    main()
