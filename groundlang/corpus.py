"""Read and write the commands-to-tasks corpus format; replay every demonstration.

One instance per file::

    line 1: the command, free text
    line 2: the actions, comma separated (north, south, east, west; spaces trimmed)
    line 3..: one state per line, one more state than actions

A state line is space-separated objects ``room,COLOUR,LEFT,TOP,RIGHT,BOTTOM``,
``door,LEFT,TOP,RIGHT,BOTTOM``, ``block,COLOUR,SHAPE,X,Y`` (``toy`` is
accepted too) and ``agent,X,Y``; COLOUR and SHAPE index a palette chosen by
name. Every demonstration is replayed through :func:`groundlang.model.world.step`.
Every problem is a :class:`CorpusError` (a ``ValueError``) whose message names
the file, the line and what was expected.
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass, field
from importlib.resources import files
from pathlib import Path

from groundlang.logic.storage import read_limited, write_atomically
from groundlang.model.world import (
    Action,
    Agent,
    Door,
    Layout,
    Palette,
    Room,
    State,
    Toy,
    WorldError,
    get_palette,
    step,
)

__all__ = [
    "CorpusError",
    "InconsistentDemonstration",
    "Instance",
    "Corpus",
    "MAX_COORDINATE",
    "read_instance",
    "read_corpus",
    "write_instance",
    "read_state_file",
    "read_initial_state",
    "parse_state",
    "format_state",
    "example_corpus_path",
    "file_prefix",
]

log = logging.getLogger(__name__)

# Coordinates beyond this are refused: a layout's grids are allocated densely,
# so one absurd number in a file must not become a gigabyte array.
MAX_COORDINATE = 1000
# A corpus or state file: a demonstration of 10^4 steps takes about 1 MB.
MAX_FILE_BYTES = 16 * 2**20

_INTEGER = re.compile(r"-?[0-9]{1,7}")
_NUMBERED = re.compile(r"^(.*_)[0-9]+$")

# kind -> (field names after the kind, format shown in messages)
_FIELDS = {
    "room": (("COLOUR", "LEFT", "TOP", "RIGHT", "BOTTOM"), "room,COLOUR,LEFT,TOP,RIGHT,BOTTOM"),
    "door": (("LEFT", "TOP", "RIGHT", "BOTTOM"), "door,LEFT,TOP,RIGHT,BOTTOM"),
    "block": (("COLOUR", "SHAPE", "X", "Y"), "block,COLOUR,SHAPE,X,Y"),
    "agent": (("X", "Y"), "agent,X,Y"),
}
_KIND_ALIASES = {"toy": "block"}


class CorpusError(ValueError):
    """A corpus file, folder or labels file that cannot be used; the message says where and why."""


class InconsistentDemonstration(CorpusError):
    """A recorded state differs from replaying the recorded actions."""

    def __init__(self, message: str, path: Path, line: int, step: int):
        super().__init__(message)
        self.path = path
        self.line = line
        self.step = step


def file_prefix(stem: str) -> str:
    """``star2teal_3`` -> ``star2teal_``; a stem without a trailing ``_N`` is its own prefix."""
    m = _NUMBERED.match(stem)
    return m.group(1) if m else stem


@dataclass(frozen=True)
class Instance:
    """One (command, demonstration) pair: ``states[i + 1] == step(states[i], actions[i])``."""

    path: Path
    command: str
    actions: tuple[Action, ...]
    states: tuple[State, ...]

    @property
    def initial_state(self) -> State:
        return self.states[0]

    @property
    def final_state(self) -> State:
        return self.states[-1]

    @property
    def name(self) -> str:
        """File stem, e.g. ``star2teal_3``."""
        return Path(self.path).stem

    @property
    def prefix(self) -> str:
        """Stem without the trailing number, e.g. ``star2teal_``; the key of the gold labels."""
        return file_prefix(self.name)


@dataclass
class Corpus:
    """The instances of one folder, plus the files skipped as inconsistent (path, reason)."""

    directory: Path
    palette: Palette
    instances: list[Instance]
    skipped: list[tuple[Path, str]] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.instances)

    def __iter__(self):
        return iter(self.instances)

    def commands(self) -> list[str]:
        """Distinct commands, in first-seen order."""
        return list(dict.fromkeys(i.command for i in self.instances))

    def distinct_layouts(self) -> list[tuple]:
        """Distinct room-and-door geometries (rooms with colours, doors), first-seen order."""
        return list(
            dict.fromkeys((i.initial_state.layout.rooms, i.initial_state.layout.doors) for i in self.instances)
        )

    def distinct_demonstrations(self) -> dict[tuple[State, tuple[Action, ...]], list[Instance]]:
        """Instances grouped by (initial state, actions): one group per demonstration."""
        groups: dict[tuple[State, tuple[Action, ...]], list[Instance]] = {}
        for inst in self.instances:
            groups.setdefault((inst.initial_state, inst.actions), []).append(inst)
        return groups


# ---------------------------------------------------------------- parsing


def _integer(text: str, where: str, name: str, obj: str) -> int:
    if not _INTEGER.fullmatch(text):
        raise CorpusError(f"{where}: field {name} of {obj!r} is {text!r}; expected an integer")
    value = int(text)
    if abs(value) > MAX_COORDINATE:
        raise CorpusError(
            f"{where}: field {name} of {obj!r} is {value}; expected at most {MAX_COORDINATE} in size"
        )
    return value


def parse_state(line: str, palette: str | Palette, where: str = "state", shared_cells_ok: bool = False) -> State:
    """Parse one state line and check it is a valid world; ``where`` prefixes error messages.

    Raises CorpusError naming the object and field that is wrong. ``shared_cells_ok`` lets two objects
    share a cell (a later state of a demonstration: :func:`read_instance` reports it as inconsistent).
    """
    palette = get_palette(palette)
    tokens = line.split()
    if not tokens:
        raise CorpusError(f"{where}: empty state line; expected objects like room,5,0,10,6,4 agent,8,6")
    rooms, doors, toys, agents = [], [], [], []
    for token in tokens:
        parts = token.split(",")
        kind = _KIND_ALIASES.get(parts[0], parts[0])
        if kind not in _FIELDS:
            raise CorpusError(
                f"{where}: unknown object kind {parts[0]!r} in {token!r}; "
                "expected room, door, block (or toy) or agent"
            )
        names, shown = _FIELDS[kind]
        if len(parts) != len(names) + 1:
            raise CorpusError(
                f"{where}: {token!r} has {len(parts)} comma-separated fields; expected "
                f"{len(names) + 1} ({shown})"
            )
        v = {n: _integer(t, where, n, token) for n, t in zip(names, parts[1:])}
        try:
            if kind == "room":
                rooms.append(Room(palette.colour(v["COLOUR"]), v["LEFT"], v["TOP"], v["RIGHT"], v["BOTTOM"]))
            elif kind == "door":
                doors.append(Door(v["LEFT"], v["TOP"], v["RIGHT"], v["BOTTOM"]))
            elif kind == "block":
                toys.append(Toy(palette.colour(v["COLOUR"]), palette.shape(v["SHAPE"]), v["X"], v["Y"]))
            else:
                agents.append(Agent(v["X"], v["Y"]))
        except WorldError as exc:
            raise CorpusError(f"{where}: {token!r}: {exc}") from None
    if len(agents) != 1:
        raise CorpusError(f"{where}: found {len(agents)} agents; expected exactly one agent,X,Y")
    layout = Layout(tuple(rooms), tuple(doors), tuple((t.colour, t.shape) for t in toys), palette)
    state = State(layout, agents[0], tuple(toys))
    try:
        if shared_cells_ok and _shared_cell(state):
            _validate_positions(state)
        else:
            state.validate()
    except WorldError as exc:
        raise CorpusError(f"{where}: {exc}") from None
    return state


def _shared_cell(state: State) -> str | None:
    """Which two objects share a cell, or None."""
    seen: dict[tuple[int, int], str] = {}
    for name, (x, y) in zip(["agent0"] + state.layout.toy_names, state.positions.tolist()):
        if (x, y) in seen:
            return f"{seen[(x, y)]} and {name} share the cell ({x},{y})"
        seen[(x, y)] = name
    return None


def _validate_positions(state: State) -> None:
    """State.validate without its shared-cell check: the layout, and every object on a walkable cell."""
    state.layout.validate()
    walk = state.layout.walkable
    for name, (x, y) in zip(["agent0"] + state.layout.toy_names, state.positions.tolist()):
        if not (0 <= x < walk.shape[0] and 0 <= y < walk.shape[1]) or not walk[x, y]:
            raise WorldError(f"{name} at ({x},{y}) is inside a wall or outside every room")


def format_state(state: State) -> str:
    """Write a state as one corpus line: rooms, doors, blocks, agent (round-trips with parse_state)."""
    lay = state.layout
    pal = lay.palette
    objs = [f"room,{pal.colour_index(r.colour)},{r.left},{r.top},{r.right},{r.bottom}" for r in lay.rooms]
    objs += [f"door,{d.left},{d.top},{d.right},{d.bottom}" for d in lay.doors]
    objs += [
        f"block,{pal.colour_index(t.colour)},{pal.shape_index(t.shape)},{t.x},{t.y}" for t in state.toys
    ]
    objs.append(f"agent,{state.agent.x},{state.agent.y}")
    return " ".join(objs)


def _read_lines(path: Path) -> list[str]:
    """Decode a file as UTF-8 and split it into lines (CRLF and a leading byte-order mark accepted, trailing
    blank lines dropped)."""
    data = read_limited(path, MAX_FILE_BYTES, "a corpus or state file")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise CorpusError(
            f"{path}, line {line}: byte 0x{data[exc.start]:02x} at offset {exc.start} is not UTF-8; "
            "expected a UTF-8 text file"
        ) from None
    text = text.removeprefix("\ufeff")  # a byte-order mark some editors write
    lines = [ln[:-1] if ln.endswith("\r") else ln for ln in text.split("\n")]
    while lines and not lines[-1].strip():
        lines.pop()
    return lines


def _parse_actions(text: str, path: Path) -> tuple[Action, ...]:
    if not text.strip():
        return ()
    actions = []
    for i, word in enumerate(text.split(","), start=1):
        if not word.strip():
            raise CorpusError(
                f"{path}, line 2: action {i} is empty; expected comma-separated north, south, east, west"
            )
        try:
            actions.append(Action.parse(word))
        except WorldError:
            raise CorpusError(
                f"{path}, line 2: action {i} is {word.strip()!r}; expected one of north, south, east, west"
            ) from None
    return tuple(actions)


def _describe(state: State) -> str:
    objs = [f"agent0 at ({state.agent.x},{state.agent.y})"]
    objs += [f"{n} at ({t.x},{t.y})" for n, t in zip(state.layout.toy_names, state.toys)]
    return ", ".join(objs)


def _layout_difference(a: Layout, b: Layout) -> str:
    if len(a.rooms) != len(b.rooms) or len(a.doors) != len(b.doors) or len(a.toy_attributes) != len(b.toy_attributes):
        return (
            f"{len(b.rooms)} rooms, {len(b.doors)} doors, {len(b.toy_attributes)} blocks instead of "
            f"{len(a.rooms)}, {len(a.doors)}, {len(a.toy_attributes)}"
        )
    for kind, xs, ys in (("room", a.rooms, b.rooms), ("door", a.doors, b.doors), ("block", a.toy_attributes, b.toy_attributes)):
        for i, (x, y) in enumerate(zip(xs, ys)):
            if x != y:
                return f"{kind}{i} changed"
    return "the palette changed"


def read_instance(path: str | Path, palette: str | Palette) -> Instance:
    """Read one corpus file and replay its demonstration.

    Raises CorpusError (malformed file) or its subclass InconsistentDemonstration
    (a recorded state differs from the replay); OSError when the file cannot be read.
    """
    path = Path(path)
    palette = get_palette(palette)
    lines = _read_lines(path)
    if not lines:
        raise CorpusError(f"{path}: the file is empty; expected a command line, an action line and state lines")
    if len(lines) < 2:
        raise CorpusError(f"{path}, line 2: missing; expected the actions (comma separated) after the command")
    command = lines[0].strip()
    if not command:
        raise CorpusError(f"{path}, line 1: the command is empty; expected the command's words")
    actions = _parse_actions(lines[1], path)
    state_lines = lines[2:]
    needed = len(actions) + 1
    if len(state_lines) < needed:
        raise CorpusError(
            f"{path}, line {len(lines) + 1}: missing; {len(actions)} actions need {needed} state lines "
            f"(lines 3..{needed + 2}), found {len(state_lines)} (truncated file, or more actions than states)"
        )
    if len(state_lines) > needed:
        raise CorpusError(
            f"{path}, line {needed + 3}: extra state line; {len(actions)} actions need exactly {needed} "
            f"state lines (lines 3..{needed + 2})"
        )
    states: list[State] = []
    for offset, text in enumerate(state_lines):
        lineno = offset + 3
        # Only the first state must be a valid world: a later one with two objects in a cell (six
        # demonstrations of the RSS 2015 expert corpus) cannot come from the actions, and is reported below
        # as an inconsistent demonstration, which --skip-inconsistent skips.
        state = parse_state(text, palette, where=f"{path}, line {lineno}", shared_cells_ok=bool(states))
        if states:
            first = states[0].layout
            if state.layout != first:
                raise CorpusError(
                    f"{path}, line {lineno}: the layout differs from line 3 ({_layout_difference(first, state.layout)}); "
                    "expected only the agent and blocks to move"
                )
            state = State(first, state.agent, state.toys)  # share one Layout and its cached grids
        states.append(state)
    for i, action in enumerate(actions):
        replayed = step(states[i], action)
        if (replayed.positions != states[i + 1].positions).any():
            shared = _shared_cell(states[i + 1])
            raise InconsistentDemonstration(
                f"{path}, line {i + 4}: step {i + 1} ({action.word}) from line {i + 3} gives "
                f"{_describe(replayed)}; the file has {_describe(states[i + 1])}"
                + (f" ({shared}: no move puts two objects in one cell)" if shared else ""),
                path,
                i + 4,
                i + 1,
            )
    return Instance(path, command, actions, tuple(states))


def _file_order(path: Path) -> tuple[str, int, str]:
    m = re.match(r"^(.*_)([0-9]+)$", path.stem)
    return (m.group(1), int(m.group(2)), path.name) if m else (path.stem, -1, path.name)


def read_corpus(directory: str | Path, palette: str | Palette, skip_inconsistent: bool = False) -> Corpus:
    """Read every ``*.txt`` file of a folder, sorted by prefix then number.

    An inconsistent demonstration raises InconsistentDemonstration, or with
    ``skip_inconsistent`` is logged as a warning and listed in ``Corpus.skipped``.
    Malformed files always raise CorpusError.
    """
    directory = Path(directory)
    palette = get_palette(palette)
    if not directory.is_dir():
        raise CorpusError(f"{directory}: not a directory; expected a folder of corpus files (*.txt)")
    paths = sorted(directory.glob("*.txt"), key=_file_order)
    for path in paths:
        if not path.is_file():  # reported, not skipped: the corpus would silently shrink
            kind = "a folder" if path.is_dir() else "a broken link" if path.is_symlink() else "not a regular file"
            raise CorpusError(f"{path}: {kind}, not a corpus file; a corpus folder's *.txt are corpus files")
    if not paths:
        raise CorpusError(f"{directory}: no corpus files; expected files like agent2red_0.txt")
    corpus = Corpus(directory, palette, [])
    for path in paths:
        try:
            corpus.instances.append(read_instance(path, palette))
        except InconsistentDemonstration as exc:
            if not skip_inconsistent:
                raise
            log.warning("skipping inconsistent demonstration: %s", exc)
            corpus.skipped.append((path, str(exc)))
    if corpus.skipped:
        log.warning("skipped %d of %d files as inconsistent", len(corpus.skipped), len(paths))
    return corpus


def write_instance(path: str | Path, instance: Instance) -> None:
    """Write an instance in the corpus format (atomically: tmp file + rename).

    Raises CorpusError when the command spans lines or states and actions do not match in number.
    """
    if "\n" in instance.command or "\r" in instance.command:
        raise CorpusError(f"{path}: the command must be one line")
    if len(instance.states) != len(instance.actions) + 1:
        raise CorpusError(
            f"{path}: {len(instance.actions)} actions need {len(instance.actions) + 1} states, "
            f"got {len(instance.states)}"
        )
    lines = [instance.command, ",".join(a.word for a in instance.actions)]
    lines += [format_state(s) for s in instance.states]
    write_atomically(Path(path), "\n".join(lines) + "\n")


def read_state_file(path: str | Path, palette: str | Palette) -> State:
    """Read a one-line ``.state`` file (a state in the corpus format)."""
    path = Path(path)
    lines = _read_lines(path)
    if not lines:
        raise CorpusError(f"{path}: the file is empty; expected one state line")
    if len(lines) > 1:
        raise CorpusError(f"{path}, line 2: extra line; expected exactly one state line")
    if lines[0].lstrip().startswith("{"):  # a BURLAP state string, as the Williams et al. corpus writes them
        from groundlang.bdm import parse_bdm_state

        return parse_bdm_state(lines[0], palette, where=f"{path}, line 1")[0]
    return parse_state(lines[0], palette, where=f"{path}, line 1")


def read_initial_state(path: str | Path, palette: str | Palette) -> State:
    """The initial state of a corpus file, or the state of a one-line ``.state`` file."""
    if Path(path).suffix in (".state", ".bdm"):
        return read_state_file(path, palette)
    return read_instance(path, palette).initial_state


def example_corpus_path() -> Path:
    """The folder of the small example corpus shipped with groundlang (palette ``sokoban``)."""
    return Path(str(files("groundlang.examples")))
