"""State-space enumeration speed: vectorised breadth-first search against pure Python.

Prints states enumerated per second for Cleanup worlds of about 10^4 (one toy),
10^5 and 10^6 (two toys) reachable states, for
``groundlang.model.statespace.enumerate_states`` and for a straightforward
pure-Python breadth-first search (dict + deque over position tuples, the same
push rule as ``world.step``) measured in the same run, and their ratio
(issue 2 asks for >= 20x on the two-toy world of 10^5 states). The 10^6 world
is timed for the vectorised search only, by default; ``--python-large`` times
the pure-Python search there too. The pure-Python search runs with the
garbage collector on, as straightforward code would; with it off it was about
1.3-1.5x faster here. Each figure is the best of ``--repeats`` runs.

``benchmark_layouts()`` gives the worlds, so that other benchmarks (planning)
use the same ones: ``from bench_statespace import benchmark_layouts`` works
when run from this folder.

Usage: python benchmarks/bench_statespace.py [--repeats N] [--python-large]
"""

from __future__ import annotations

import argparse
import time
from collections import deque

import numpy as np

from groundlang.model.statespace import enumerate_states
from groundlang.model.world import Agent, Door, Layout, Room, State, Toy, get_palette

# One move per Action value: NORTH, SOUTH, EAST, WEST.
_DELTAS = ((0, 1), (0, -1), (1, 0), (-1, 0))


def cleanup_world(
    width: int, top: int, bottom: int, split: int, toys: list[tuple[str, str, int, int]]
) -> State:
    """A corpus-style world: two rooms side by side above one wide room, three doors.

    room0 (green) spans x 0..split, room1 (red) split..width, both y bottom..top;
    room2 (blue) spans x 0..width, y 0..bottom. The corpus layout itself is
    ``cleanup_world(10, 10, 4, 6, ...)``. The agent starts at (1, 1).
    """
    rooms = (
        Room("green", 0, top, split, bottom),
        Room("red", split, top, width, bottom),
        Room("blue", 0, bottom, width, 0),
    )
    middle = (top + bottom) // 2
    doors = (
        Door(split // 2, bottom, split // 2, bottom),
        Door((split + width) // 2, bottom, (split + width) // 2, bottom),
        Door(split, middle, split, middle),
    )
    objects = tuple(Toy(colour, shape, x, y) for colour, shape, x, y in toys)
    layout = Layout(rooms, doors, tuple((t.colour, t.shape) for t in objects), get_palette("sokoban"))
    return State(layout, Agent(1, 1), objects)


def benchmark_layouts() -> list[tuple[str, State]]:
    """Named worlds of about 10^4 (one toy), 10^5 and 10^6 (two toys) reachable states.

    Exact counts: 9,312; 103,746; 1,157,490 (the last needs the default
    max_states of 2,000,000 or more; the default is 5,000,000).
    """
    star = ("yellow", "star")
    moon = ("magenta", "moon")
    return [
        ("one toy, 97 cells (~1e4 states)", cleanup_world(12, 11, 5, 6, [(*star, 2, 3)])),
        ("two toys, 48 cells (~1e5 states)", cleanup_world(9, 8, 4, 5, [(*star, 2, 2), (*moon, 7, 6)])),
        ("two toys, 106 cells (~1e6 states)", cleanup_world(13, 11, 5, 7, [(*star, 2, 3), (*moon, 9, 7)])),
    ]


def python_bfs(state: State) -> tuple[list[tuple], list[list[int]]]:
    """The straightforward search: states as tuples of (x, y), a dict for indices, a deque."""
    walk = {(int(x), int(y)) for x, y in zip(*np.nonzero(state.layout.walkable))}
    start = tuple((int(x), int(y)) for x, y in state.positions)
    index = {start: 0}
    order = [start]
    queue = deque([start])
    next_state = []
    while queue:
        current = queue.popleft()
        agent, toys = current[0], current[1:]
        row = []
        for dx, dy in _DELTAS:
            target = (agent[0] + dx, agent[1] + dy)
            if target not in walk:
                successor = current
            elif target in toys:
                beyond = (target[0] + dx, target[1] + dy)
                if beyond not in walk or beyond in toys:
                    successor = current
                else:
                    i = toys.index(target)
                    successor = (target,) + toys[:i] + (beyond,) + toys[i + 1 :]
            else:
                successor = (target,) + toys
            j = index.get(successor)
            if j is None:
                j = len(order)
                index[successor] = j
                order.append(successor)
                queue.append(successor)
            row.append(j)
        next_state.append(row)
    return order, next_state


def best_time(fn, repeats: int) -> tuple[float, object]:
    """Fastest of ``repeats`` wall-clock runs, and the last result."""
    best = float("inf")
    result = None
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - start)
    return best, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="runs per measurement (best is kept)")
    parser.add_argument("--python-large", action="store_true", help="also time pure Python on ~1e6")
    args = parser.parse_args()

    print(f"{'world':36s} {'states':>10s} {'vectorised':>12s} {'states/s':>11s} "
          f"{'pure Python':>12s} {'states/s':>11s} {'ratio':>7s}")
    for i, (name, state) in enumerate(benchmark_layouts()):
        large = i == 2
        vec_time, space = best_time(lambda: enumerate_states(state), args.repeats)
        n = space.num_states
        line = f"{name:36s} {n:10,d} {vec_time:11.4f}s {n / vec_time:11,.0f}"
        if not large or args.python_large:
            py_time, (order, _) = best_time(lambda: python_bfs(state), 1 if large else args.repeats)
            if len(order) != n:
                raise SystemExit(f"{name}: pure Python found {len(order)} states, vectorised {n}")
            line += f" {py_time:11.4f}s {len(order) / py_time:11,.0f} {py_time / vec_time:6.1f}x"
        print(line, flush=True)


if __name__ == "__main__":
    main()
