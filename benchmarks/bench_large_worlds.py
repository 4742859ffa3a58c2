"""Worlds too large to enumerate (issue #22): the relevance abstraction beside the exact method, in one run.

Prints:
- in a 16x16 layout of three toys (``tests/fixtures/large/sixteen.state``, about 1.7 x 10^9 states by the
  enumerator's estimate), where only the abstraction can run: the behaviour likelihood of one
  demonstration (every candidate goal of the layout, cache off; goal under 1 s), one MLIRL fit over
  every position PF (goal under 5 s), and ``Learner.follow`` from the call to its plan, i.e. to the
  first action (goal under 1 s), each the first time in the layout (cold: PF tables and groundings
  included) and again (warm);
- in a layout of about 10^6 reachable states (``bench_statespace.benchmark_layouts()``' largest), where
  both run: one demonstration's behaviour likelihoods over every candidate goal, exact and approximate
  (``behaviour_likelihood_table(method=...)``: relevance abstraction or stepwise, inference/stepwise.py),
  their speed ratio (goal at least 10x), whether the top goal agrees and every goal's two values; the
  automatic switch (``GROUNDLANG_MAX_STATES`` just below the exact count); one MLIRL fit, exact and in
  the demonstration's abstraction;
- the top goal of every distinct demonstration of the shipped corpora (and the crowd-sourced corpus when
  present at ``../shared/data/commands-to-tasks``) under both methods: how many agree;
- ``follow`` in the 32x32 five-toy layout (``tests/fixtures/large/thirtytwo.state``);
- the peak resident memory of this process (resource.getrusage; goal under 2 GiB).

The first compiled sweep of soft value iteration (10^6 states) pays a one-off torch.compile; it is
warmed up before the exact figures are timed. No timing asserts. Each figure is the best of
``--repeats`` runs where it says "warm".
Usage: python benchmarks/bench_large_worlds.py [--repeats N] [--skip-32]
"""

from __future__ import annotations

import argparse
import logging
import os
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from bench_statespace import benchmark_layouts  # noqa: E402

from groundlang.corpus import example_corpus_path, read_corpus, read_state_file  # noqa: E402
from groundlang.inference.discovery import DISCOVERY_IRL  # noqa: E402
from groundlang.inference.likelihoods import behaviour_likelihood_table  # noqa: E402
from groundlang.inference.mlirl import mlirl  # noqa: E402
from groundlang.inference.planning import TaskSettings, solve_task  # noqa: E402
from groundlang.inference.acting import rollout, rollout_states  # noqa: E402
from groundlang.learner import Learner  # noqa: E402
from groundlang.logic.atoms import parse_goal  # noqa: E402
from groundlang.logic.tasks import TaskLibrary  # noqa: E402
from groundlang.model.features import feature_matrix, goal_mask, position_atoms  # noqa: E402
from groundlang.model.interpretations import interpretations  # noqa: E402
from groundlang.model.pf_tables import pf_tables  # noqa: E402
from groundlang.model.relevance import state_space_for  # noqa: E402
from groundlang.model.statespace import state_count_bound, trajectory_indices  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
LARGE = ROOT / "tests" / "fixtures" / "large"
CROWD = ROOT.parent / "shared" / "data" / "commands-to-tasks" / "allTurkTrain"
NEAR = 20.0  # nats below the exact top: the candidates a posterior could give weight


class Demo:
    """An instance as behaviour_likelihood_table reads it."""

    def __init__(self, states, actions):
        self.initial_state, self.states, self.actions = states[0], tuple(states), tuple(actions)


def seconds(fn, repeats: int = 1) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - start)
    return best, out


def bound(state) -> int:
    return state_count_bound(int(state.layout.walkable.sum()), len(state.toys))


def candidate_goals(state, library) -> list:
    return sorted({i.goal for i in interpretations(state, library)})


def planned_demo(state, goal, method: str) -> Demo:
    """The greedy plan for ``goal`` as a demonstration (the corpus's demonstrations are such paths)."""
    tables = pf_tables(state.layout)
    space = state_space_for(state, goal, tables=tables, method=method)
    mask = goal_mask(space, goal, tables)
    trajectory = rollout(space.next_state, solve_task(space.next_state, mask, TaskSettings()), 0, goal_mask=mask)
    states, actions = rollout_states(space, trajectory)
    return Demo(states, actions)


def row(demo: Demo, goals, library, method: str) -> np.ndarray:
    """One demonstration's log-likelihood under each goal, by ``method`` (exact or abstraction), cache off."""
    return behaviour_likelihood_table([demo], [goals], cache_dir=False, library=library, method=method)[0]


def fit_mlirl(state, demo: Demo, method: str):
    """One MLIRL fit over every position PF in the space ``method`` gives for the demonstration."""
    tables = pf_tables(state.layout)
    space = state_space_for(state, demonstrations=[demo.states], tables=tables, method=method)
    atoms = position_atoms(state.layout, tables)
    features = feature_matrix(space, atoms, tables)
    path = trajectory_indices(space, list(demo.states))
    result = mlirl(space.next_state, features, [(path, [int(a) for a in demo.actions])], **DISCOVERY_IRL)
    return space, atoms, result


def billion(learner: Learner, library, repeats: int) -> None:
    state = read_state_file(LARGE / "sixteen.state", "sokoban")
    print(f"\n16x16 layout, 3 toys, {int(state.layout.walkable.sum())} cells: up to {bound(state):.2e} states "
          "(exact enumeration refused; relevance abstraction used)")
    command = "take the star to the blue room"
    cold, result = seconds(lambda: learner.follow(command, state))

    def replan():  # the learner's remembered plans and spaces dropped: the solve is timed again
        learner._world.plans.clear()
        learner._world.spaces.clear()
        return learner.follow(command, state)

    warm, _ = seconds(replan, repeats)
    print(f"  follow {command!r}: {len(result.actions)} moves, reached={result.reached}; to the first action "
          f"{cold:.3f} s cold (first time in the layout), {warm:.3f} s warm (interpretations and PF tables "
          "cached, plan not)   goal < 1 s")
    demo = Demo(result.states, result.actions)
    goals = candidate_goals(state, library)
    cold, table = seconds(lambda: behaviour_likelihood_table([demo], [goals], cache_dir=False))
    warm, _ = seconds(lambda: behaviour_likelihood_table([demo], [goals], cache_dir=False), repeats)
    one, _ = seconds(lambda: behaviour_likelihood_table([demo], [[result.goal]], cache_dir=False), repeats)
    top = goals[int(np.argmax(table[0]))]
    print(f"  behaviour likelihood of the demonstration ({len(demo.actions)} moves): one goal {one:.3f} s; all "
          f"{len(goals)} candidate goals {warm:.3f} s ({cold:.3f} s cold)   goal < 1 s; top goal "
          f"{' '.join(map(str, top))}")
    took, (space, atoms, fitted) = seconds(lambda: fit_mlirl(state, demo, "auto"), repeats)
    best = atoms[int(np.argmax(fitted.weights))]
    print(f"  one MLIRL fit over {len(atoms)} position PFs in the demonstration's abstraction ({space.num_states:,} "
          f"states): {took:.3f} s   goal < 5 s; top weight {best}")


def million(library, repeats: int) -> None:
    name, state = benchmark_layouts()[-1]
    goal = parse_goal("toyInRoom(block0, room1)")
    demo = planned_demo(state, goal, "exact")
    goals = candidate_goals(state, library)
    row(demo, goals[:1], library, "exact")  # one-off torch.compile of the large sweep, not timed
    row(demo, goals, library, "abstraction")  # and of the union's sweep (another shape), not timed
    size = state_space_for(state, method="exact").num_states
    print(f"\n{name}: {size:,} reachable states, {len(goals)} candidate goals, a demonstration of "
          f"{len(demo.actions)} moves pushing block0 (exact and approximate in this run, best of {repeats})")
    one_exact, _ = seconds(lambda: row(demo, [goal], library, "exact"), repeats)
    one_approx, _ = seconds(lambda: row(demo, [goal], library, "abstraction"), repeats)
    print(f"  its goal {' '.join(map(str, goal))} alone: exact {one_exact:.3f} s, approximate {one_approx:.3f} s, "
          f"ratio {one_exact / one_approx:.1f}x")
    exact_s, exact = seconds(lambda: row(demo, goals, library, "exact"), repeats)
    approx_s, approx = seconds(lambda: row(demo, goals, library, "abstraction"), repeats)
    top = int(np.argmax(exact))
    near = exact >= exact[top] - NEAR
    lower = approx < exact - 1
    below = (f" (approximate lower by more than 1 nat: {int(lower.sum())} goals, all at least "
             f"{exact[top] - exact[lower].max():.0f} nats below the top)") if lower.any() else ""
    print(f"  every candidate goal (behaviour_likelihood_table): exact {exact_s:.3f} s, approximate {approx_s:.3f} s, "
          f"ratio {exact_s / approx_s:.1f}x   goal >= 10x; same top goal: {top == int(np.argmax(approx))}; "
          f"largest |difference| within {NEAR:.0f} nats of the top {np.abs(exact - approx)[near].max():.3f} nats; "
          f"over all goals {np.abs(exact - approx).max():.1f} nats{below}")
    for g, e, a in zip(goals, exact, approx):
        print(f"    {' '.join(map(str, g)):55s} exact {e:9.3f}  approximate {a:9.3f}")
    # the automatic switch: with the limit below the exact bound, the table chooses the approximation
    limit = str(size - 1)
    before, os.environ["GROUNDLANG_MAX_STATES"] = os.environ.get("GROUNDLANG_MAX_STATES"), limit
    try:
        table_s, (table,) = seconds(lambda: behaviour_likelihood_table([demo], [goals], cache_dir=False), repeats)
    finally:
        if before is None:
            del os.environ["GROUNDLANG_MAX_STATES"]
        else:
            os.environ["GROUNDLANG_MAX_STATES"] = before
    print(f"  the same table with method auto and GROUNDLANG_MAX_STATES={limit}: {table_s:.3f} s, "
          f"{exact_s / table_s:.1f}x; same values as the forced approximation: {np.allclose(table, approx)}")
    fit_mlirl(state, demo, "exact")  # the adjoint's compiled sweep, not timed
    exact_s, (space_e, atoms, fit_e) = seconds(lambda: fit_mlirl(state, demo, "exact"), repeats)
    approx_s, (space_a, _, fit_a) = seconds(lambda: fit_mlirl(state, demo, "abstraction"), repeats)
    best_e, best_a = atoms[int(np.argmax(fit_e.weights))], atoms[int(np.argmax(fit_a.weights))]
    print(f"  one MLIRL fit over {len(atoms)} position PFs: exact ({space_e.num_states:,} states) {exact_s:.3f} s, "
          f"approximate ({space_a.num_states:,} states) {approx_s:.3f} s, ratio {exact_s / approx_s:.1f}x; top "
          f"weight exact {best_e}, approximate {best_a}")


def agreement(library) -> None:
    shipped = ROOT / "tests" / "fixtures"
    folders = [(example_corpus_path(), "sokoban"), (shipped / "sokoban2_corpus", "sokoban2"),
               (shipped / "sokoban2", "sokoban2"), (shipped / "sokoban", "sokoban")]
    if CROWD.is_dir():
        folders.append((CROWD, "sokoban"))
    else:
        print(f"\n(crowd-sourced corpus not found at {CROWD}: left out)")
    print("\ntop goal, exact against abstraction, every distinct demonstration:")
    for folder, palette in folders:
        demos = {}
        for inst in read_corpus(folder, palette).instances:
            demos.setdefault((inst.initial_state, tuple(inst.actions)), inst)
        same, worst = 0, 0.0
        for inst in demos.values():
            goals = candidate_goals(inst.initial_state, library)
            exact, approx = row(inst, goals, library, "exact"), row(inst, goals, library, "abstraction")
            top = int(np.argmax(exact))
            same += top == int(np.argmax(approx))
            worst = max(worst, abs(exact[top] - approx[top]))
        print(f"  {folder.name}: {same}/{len(demos)} agree; largest difference of the top goal's "
              f"log-likelihood {worst:.3f} nats")


def thirty_two(learner: Learner) -> None:
    state = read_state_file(LARGE / "thirtytwo.state", "sokoban")
    took, result = seconds(lambda: learner.follow("take the star to the blue room", state))
    print(f"\n32x32 layout, 5 toys, {int(state.layout.walkable.sum())} cells: up to {bound(state):.2e} states; "
          f"follow 'take the star to the blue room': reached={result.reached} in {len(result.actions)} moves, "
          f"{took:.1f} s (first time in the layout: PF tables of six movable objects and groundings included; "
          "torch.compile already done above)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--skip-32", action="store_true", help="leave out the 32x32 layout")
    args = parser.parse_args()
    logging.basicConfig(level=logging.WARNING)
    print(f"load average {os.getloadavg()[0]:.2f} (other processes slow every figure)")
    library = TaskLibrary.load()
    learner = Learner(cache_dir=False).fit(read_corpus(example_corpus_path(), "sokoban").instances)
    billion(learner, library, args.repeats)
    million(library, args.repeats)
    agreement(library)
    if not args.skip_32:
        thirty_two(learner)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"\npeak resident memory of this process: {peak:.0f} MiB   goal < 2048 MiB")


if __name__ == "__main__":
    main()
