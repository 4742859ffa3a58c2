"""Build groundlang's small example corpus (palette ``sokoban``): ``python -m groundlang.examples.build [DIR]``.

Three rooms (green, red, blue) and one yellow star, as in the commands-to-tasks
corpus but placed differently; six tasks (agent or star to each room), four
commands per task in the paper's style, each demonstration a shortest path
found by breadth-first search over ``groundlang.model.world.step`` (actions
tried in the order north, south, east, west, so the output is deterministic).
Also writes ``labels.csv`` and three ``.state`` files of novel layouts (the
same three colours placed differently, agent and star in doorways so no task
holds at the start). Output is byte-identical from run to run.
"""

from __future__ import annotations

import argparse
from collections import deque
from pathlib import Path

from groundlang.corpus import Instance, format_state, parse_state, write_instance
from groundlang.labels import goal_holds
from groundlang.logic.atoms import format_goal, parse_goal
from groundlang.model.world import Action, State, replay, step
from groundlang.logic.storage import write_atomically

PALETTE = "sokoban"

# Training layout: tall green room west, red room north-east, blue room south-east.
# room,COLOUR,LEFT,TOP,RIGHT,BOTTOM with colours green=5, red=10, blue=1; star = block,12,0 (yellow star).
ROOMS = "room,5,0,9,5,0 room,10,5,9,12,4 room,1,5,4,12,0"
DOORS = "door,5,7,5,7 door,5,2,5,2 door,9,4,9,4"


def _state(toy: tuple[int, int], agent: tuple[int, int], rooms: str = ROOMS, doors: str = DOORS) -> State:
    return parse_state(f"{rooms} {doors} block,12,0,{toy[0]},{toy[1]} agent,{agent[0]},{agent[1]}", PALETTE)


ROOM_OF_COLOUR = {"green": "room0", "red": "room1", "blue": "room2"}

# prefix -> (goal, initial state: star position, agent position), none true at the start.
TASKS = {
    "agent2green_": ("agentInRoom(agent0, room0)", _state((8, 2), (9, 7))),
    "agent2red_": ("agentInRoom(agent0, room1)", _state((2, 6), (7, 2))),
    "agent2blue_": ("agentInRoom(agent0, room2)", _state((8, 6), (2, 3))),
    "star2green_": ("blockInRoom(block0, room0)", _state((8, 2), (10, 7))),
    "star2red_": ("blockInRoom(block0, room1)", _state((3, 4), (1, 2))),
    "star2blue_": ("blockInRoom(block0, room2)", _state((8, 7), (2, 5))),
}

COMMANDS = {
    "agent2green_": ["go to the green room", "walk into the green room", "move to the green room",
                     "enter the green room"],
    "agent2red_": ["go to the red room", "walk into the red room", "move to the red room", "enter the red room"],
    "agent2blue_": ["go to the blue room", "walk into the blue room", "move to the blue room",
                    "enter the blue room"],
    "star2green_": ["push the star into the green room", "take the star to the green room",
                    "move the star to the green room", "bring the star into the green room"],
    "star2red_": ["push the star into the red room", "take the star to the red room",
                  "move the star to the red room", "bring the star into the red room"],
    "star2blue_": ["push the star into the blue room", "take the star to the blue room",
                   "move the star to the blue room", "bring the star into the blue room"],
}

# Novel layouts: the same three colours placed differently; agent and star in doorways.
NOVEL = {
    "novel_a.state": (  # blue north-west, green north-east, red along the south
        "room,1,0,10,6,5 room,5,6,10,12,5 room,10,0,5,12,0",
        "door,6,8,6,8 door,3,5,3,5 door,9,5,9,5",
        (6, 8), (9, 5),
    ),
    "novel_b.state": (  # three rooms side by side: red, blue, green
        "room,10,0,8,5,0 room,1,5,8,10,0 room,5,10,8,15,0",
        "door,5,3,5,3 door,10,5,10,5",
        (5, 3), (10, 5),
    ),
    "novel_c.state": (  # green along the south, red north-west, blue north-east
        "room,10,0,10,5,5 room,1,5,10,11,5 room,5,0,5,11,0",
        "door,5,7,5,7 door,2,5,2,5 door,8,5,8,5",
        (2, 5), (5, 7),
    ),
}


def shortest_demonstration(start: State, goal, library=None) -> tuple[Action, ...]:
    """Breadth-first search over ``step`` for the first shortest action sequence reaching ``goal`` (its PFs
    read by ``library``'s rules; None: the package's).

    Raises ValueError when no reachable state satisfies the goal.
    """
    key = lambda s: s.positions.tobytes()  # noqa: E731
    parent: dict[bytes, tuple[bytes, Action] | None] = {key(start): None}
    frontier = deque([start])
    while frontier:
        state = frontier.popleft()
        if goal_holds(goal, state, library):
            actions = []
            k = key(state)
            while parent[k] is not None:
                k, a = parent[k]
                actions.append(a)
            return tuple(reversed(actions))
        for action in Action:
            nxt = step(state, action)
            k = key(nxt)
            if k not in parent:
                parent[k] = (key(state), action)
                frontier.append(nxt)
    raise ValueError(f"no reachable state satisfies {format_goal(goal)}")


def write_tasks(out: Path, tasks, library=None) -> list[Path]:
    """For each ``(prefix, goal text, initial state, commands)``: a shortest demonstration of
    the goal (under ``library``'s PFs) and one corpus file per command; then ``labels.csv``. Returns the
    paths written."""
    written = []
    labels = ["prefix,goal"]
    for prefix, goal_text, start, commands in tasks:
        actions = shortest_demonstration(start, parse_goal(goal_text), library)
        states = replay(start, actions)
        for n, command in enumerate(commands):
            path = out / f"{prefix}{n}.txt"
            write_instance(path, Instance(path, command, actions, states))
            written.append(path)
        labels.append(f'{prefix},"{goal_text}"')
    write_atomically(out / "labels.csv", "\n".join(labels) + "\n")
    return written + [out / "labels.csv"]


def build(out_dir: str | Path) -> list[Path]:
    """Write the example corpus, labels.csv and the novel .state files into ``out_dir``; return the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for prefix, (goal_text, start) in TASKS.items():
        if goal_holds(parse_goal(goal_text), start):
            raise ValueError(f"{prefix}: the goal already holds in the initial state")
    written = write_tasks(out, [(p, g, start, COMMANDS[p]) for p, (g, start) in TASKS.items()])
    for name, (rooms, doors, toy, agent) in NOVEL.items():
        state = _state(toy, agent, rooms, doors)
        for goal_text, _ in TASKS.values():
            goal = parse_goal(goal_text)
            if goal_holds(goal, state):
                raise ValueError(f"{name}: {goal_text} holds at the start")
            shortest_demonstration(state, goal)  # raises when a task cannot be done there
        write_atomically(out / name, format_state(state) + "\n")
        written.append(out / name)
    return written


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", default=str(Path(__file__).parent), help="output folder (default: this one)")
    args = parser.parse_args(argv)
    paths = build(args.out)
    print(f"wrote {len(paths)} files to {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
