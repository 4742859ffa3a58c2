"""Time task enumeration for one environment: library load, cell tables, PF tables, groundings + constraints.

Prints milliseconds per call (median and minimum of repeats) for the default library on the
commands-to-tasks layout with one toy and with two toys. Each call builds one
clingo Control, grounds once and enumerates every grounding in one solve
(the per-state caches of groundlang.model are bypassed to time the work itself). PF tables
(every PF of pfs.lp over every placement of its movable arguments, one grounding per layout) are
timed beside the cell tables they replace as what features read, also on a 16x16 layout.

    .venv/bin/python benchmarks/bench_tasks.py [--repeats 20]
"""

from __future__ import annotations

import argparse
import statistics
import time

from groundlang.logic.groundings import enumerate_groundings
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.geometry import cell_tables, state_facts
from groundlang.model.pf_tables import _tables
from groundlang.model.world import Agent, Door, Layout, Room, State, Toy, get_palette


def _state(rooms, doors, toys, agent) -> State:
    """A state of ``toys`` ``(colour, shape, x, y)`` and ``agent`` ``(x, y)`` in a layout of the sokoban palette."""
    layout = Layout(tuple(rooms), tuple(doors), tuple((c, s) for c, s, _, _ in toys), get_palette("sokoban"))
    return State(layout, Agent(*agent), tuple(Toy(c, s, x, y) for c, s, x, y in toys))


def corpus_state(num_toys: int) -> State:
    """The commands-to-tasks corpus's layout with one to three toys."""
    return _state((Room("green", 0, 10, 6, 4), Room("red", 6, 10, 10, 4), Room("blue", 0, 4, 10, 0)),
                  (Door(3, 4, 3, 3), Door(8, 4, 8, 3), Door(6, 6, 6, 6)),
                  [("yellow", "star", 4, 8), ("red", "moon", 8, 8), ("blue", "circle", 2, 2)][:num_toys], (8, 6))


def large_state() -> State:
    """A 16x16 layout of three rooms with three toys, as the Williams et al. 2018 corpus's largest."""
    return _state((Room("green", 0, 15, 8, 7), Room("red", 8, 15, 15, 0), Room("blue", 0, 7, 8, 0)),
                  (Door(8, 11, 8, 11), Door(4, 7, 4, 7), Door(8, 3, 8, 3)),
                  [("yellow", "star", 3, 3), ("red", "moon", 12, 3), ("blue", "circle", 4, 12)], (10, 10))


def median_ms(fn, repeats: int) -> str:
    """``median (min)`` milliseconds; the minimum is the figure least disturbed by other load."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return f"{1000 * statistics.median(times):6.2f} ({1000 * min(times):5.2f})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20)
    args = parser.parse_args()

    print(f"load default task library (parse + ground tasks.lp): "
          f"{median_ms(TaskLibrary.load, args.repeats)} ms")
    library = TaskLibrary.load()
    for num_toys in (1, 2, 3):
        state = corpus_state(num_toys)
        facts = state_facts(state)
        found = enumerate_groundings(library, facts)
        constraints = sum(len(c) for _, c in found)
        ms = median_ms(lambda: enumerate_groundings(library, facts), args.repeats)
        cells = median_ms(lambda: cell_tables.__wrapped__(state.layout), args.repeats)
        tables = median_ms(lambda: _tables.__wrapped__(state.layout, library.tabulation_program, library.time_limit), args.repeats)
        print(f"{num_toys} toy(s): {len(found):3d} groundings, {constraints:5d} binding constraints: "
              f"enumeration {ms} ms; cell tables {cells} ms; PF tables {tables} ms")
    big = large_state()
    cells = median_ms(lambda: cell_tables.__wrapped__(big.layout), max(3, args.repeats // 4))
    tables = median_ms(lambda: _tables.__wrapped__(big.layout, library.tabulation_program, library.time_limit), max(3, args.repeats // 4))
    print(f"16x16, 3 rooms, 3 toys ({int(big.layout.walkable.sum())} walkable cells): cell tables {cells} ms; "
          f"PF tables {tables} ms")
    # The same tasks as a user file: solved in a child process that can be killed at the time limit.
    user = TaskLibrary.from_text(library.to_lp(), "user_tasks.lp")
    facts = state_facts(corpus_state(1))
    assert enumerate_groundings(user, facts) == enumerate_groundings(library, facts)
    ms = median_ms(lambda: enumerate_groundings(user, facts), max(3, args.repeats // 4))
    layout = corpus_state(1).layout
    tables = median_ms(lambda: _tables.__wrapped__(layout, user.tabulation_program, user.time_limit), max(3, args.repeats // 4))
    print(f"1 toy, same library from a user file (isolated child process): enumeration {ms} ms; PF tables {tables} ms")
    # Naming every place of a parse in Python costs ~0.3 ms a statement; ground facts are left as clingo reads them.
    from groundlang.logic.sources import Source, _parsed, _relocate

    facts = "".join(f"fact({i}, red).\n" for i in range(10_000))
    rules = "".join(f"fact({i}, C) :- colour(_, C).\n" for i in range(10_000))
    kept, walked = (median_ms(lambda: _parsed.__wrapped__("f.lp", text, False), 3) for text in (facts, rules))
    statements = _parsed.__wrapped__("f.lp", facts, False)
    every = median_ms(lambda: [_relocate(s, "f.lp") for s in statements], 3)
    print(f"parse 10,000 ground facts: {kept} ms (naming every place as in a rule would add {every} ms); "
          f"10,000 rules: {walked} ms")


if __name__ == "__main__":
    main()
