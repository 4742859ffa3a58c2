"""Read and write the commands-to-tasks corpus format; replay every demonstration.

One instance per file::

    line 1: the command, free text
    line 2: the actions, comma separated (north, south, east, west; spaces trimmed)
    line 3..: one state per line, one more state than actions

A state line is read and written by :mod:`groundlang.state_line` (its names
``parse_state``, ``format_state``, ``CorpusError`` and ``MAX_COORDINATE`` are
importable from here too). Every demonstration is replayed through :func:`groundlang.model.world.step`.
Every problem is a :class:`CorpusError` (a ``ValueError``) whose message names
the file, the line and what was expected.
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass, field
from importlib.resources import files
from pathlib import Path

from groundlang.bdm import format_bdm_state, is_bdm, object_names, parse_bdm_state
from groundlang.grammar.parser import command_fault
from groundlang.logic.storage import as_path, read_limited, write_atomically
from groundlang.model.world import Action, Layout, Palette, State, WorldError, get_palette, step
from groundlang.state_line import (MAX_COORDINATE, MAX_FILE_BYTES, CorpusError, format_state, parse_state,
                                   shown, text_lines, utf8_text)

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
    "format_state_like",
    "file_names",
    "example_corpus_path",
    "file_prefix",
]

log = logging.getLogger(__name__)

_NUMBERED = re.compile(r"^(.*_)[0-9]+$")


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


def _read_lines(path: Path, what: str = "a corpus or state file") -> list[str]:
    """Decode a file as UTF-8 and split it into lines (CRLF and a leading byte-order mark accepted, trailing
    blank lines dropped). ``what`` names the file expected, for a folder or a file too large."""
    try:
        data = read_limited(path, MAX_FILE_BYTES, what)
    except IsADirectoryError:  # the OS says only "Is a directory" (an API caller saw "[Errno 21]")
        raise CorpusError(f"{path}: a folder, not a regular file; expected {what}") from None
    lines = text_lines(utf8_text(data, path))
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
                f"{path}, line 2: action {i} is {shown(word.strip())!r}; expected one of north, south, east, west"
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


def read_instance(path: str | Path, palette: str | Palette, what: str = "a corpus file") -> Instance:
    """Read one corpus file and replay its demonstration (``what``: the kind of file a refusal says is expected).

    Raises CorpusError (malformed file) or its subclass InconsistentDemonstration
    (a recorded state differs from the replay); OSError when the file cannot be read.
    """
    path = as_path(path, "read_instance: path")
    if is_bdm(path):  # read as actions, its state line would be named "action 1"
        raise CorpusError(f"{path}: a .bdm file holds (start, end) pairs, no moves; expected a commands-to-tasks "
                          "file (command, actions, states)")
    palette = get_palette(palette)
    lines = _read_lines(path, what)
    if not lines:
        raise CorpusError(f"{path}: the file is empty; expected a command line, an action line and state lines")
    if len(lines) < 2:
        if path.suffix == ".state":  # a layout alone, as follow --env takes: its line is no command
            raise CorpusError(f"{path}: a .state file holds a layout, no demonstration; expected a corpus file "
                              "(a command line, an action line and state lines)")
        raise CorpusError(f"{path}, line 2: missing; expected the actions (comma separated) after the command")
    command = lines[0].strip()
    fault = command_fault(command)
    if fault:
        raise CorpusError(f"{path}, line 1: the command {fault}; expected the command's words")
    actions = _parse_actions(lines[1], path)
    state_lines = lines[2:]
    blank = next((k for k, text in enumerate(state_lines) if not text.strip()), None)
    if blank is not None:  # one state per line: a blank one shifts every count below, so it is named first
        raise CorpusError(f"{path}, line {blank + 3}: a blank line among the state lines; expected one state per "
                          "line from line 3 on")
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
            shared = states[i + 1].shared_cell()
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
    if not isinstance(skip_inconsistent, bool):  # "no" would have counted as true
        raise TypeError(f"read_corpus: skip_inconsistent must be True or False, got {skip_inconsistent!r:.40}")
    directory = as_path(directory, "read_corpus: directory")
    palette = get_palette(palette)
    if not directory.is_dir():
        raise CorpusError(f"{directory}: not a directory; expected a folder of corpus files (*.txt)")
    paths = sorted(directory.glob("*.txt"), key=_file_order)
    for path in paths:
        if not path.is_file():  # reported, not skipped: the corpus would silently shrink
            kind = ("a folder" if path.is_dir() else "a broken link" if not path.exists()
                    else "a device, FIFO or socket")
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

    Raises CorpusError when the command spans lines or states and actions do not match in number;
    TypeError when ``instance`` is not an Instance.
    """
    path = as_path(path, "write_instance: path")
    if not isinstance(instance, Instance):
        raise TypeError(f"write_instance: instance must be an Instance (read_instance, or Instance(path, command, "
                        f"actions, states)), got {type(instance).__name__}")
    if "\n" in instance.command or "\r" in instance.command:
        raise CorpusError(f"{path}: the command must be one line")
    if len(instance.states) != len(instance.actions) + 1:
        raise CorpusError(
            f"{path}: {len(instance.actions)} actions need {len(instance.actions) + 1} states, "
            f"got {len(instance.states)}"
        )
    lines = [instance.command, ",".join(a.word for a in instance.actions)]
    lines += [format_state(s) for s in instance.states]
    write_atomically(path, "\n".join(lines) + "\n")


def read_state_file(path: str | Path, palette: str | Palette | dict) -> State:
    """Read a one-line ``.state`` file (a state in the corpus format, or a BURLAP line). ``palette``: a name,
    a ``.lp`` file, a Palette, or a record of one as a trained model keeps it (``learner.palettes[0]``)."""
    path = as_path(path, "read_state_file: path")
    numbered = [(n, line) for n, line in enumerate(_read_lines(path, "a state file"), start=1) if line.strip()]
    if not numbered:
        raise CorpusError(f"{path}: the file is empty; expected one state line")
    (n, line), more = numbered[0], numbered[1:]
    if more and path.suffix == ".bdm" and not line.lstrip().startswith("{"):
        raise CorpusError(f"{path}: a .bdm file of commands (line {n} is not a state line); expected one state "
                          "line: a .state file or a one-line .bdm file")
    if line.lstrip().startswith("#"):
        raise CorpusError(f"{path}, line {n}: a comment; a state file holds its state line alone")
    if more:
        raise CorpusError(f"{path}, line {more[0][0]}: a second line (line {n} is the state); expected exactly one "
                          "state line")
    if line.lstrip().startswith("{"):  # a BURLAP state string, as the Williams et al. corpus writes them
        return parse_bdm_state(line, palette, where=f"{path}, line {n}")[0]
    return parse_state(line, palette, where=f"{path}, line {n}")


def format_state_like(state: State, path: str | Path, names: dict[str, str] | None = None) -> str:
    """``state`` as a line of the format the one-line state file ``path`` was written in (a BURLAP
    string, as :func:`read_state_file` read it, with its objects by ``names``, or a corpus state line)."""
    lines = _read_lines(as_path(path, "format_state_like: path"))
    return format_bdm_state(state, names=names) if lines and lines[0].lstrip().startswith("{") else format_state(state)


def file_names(path: str | Path) -> dict[str, str]:
    """The names a one-line BURLAP state file gives its objects where they differ from the layout's (which
    numbers each class from 0 in order: a file's ``block3`` may be ``block2``), by the layout's name; ``{}``
    for a state in the corpus's format or a corpus file, whose objects are the layout's."""
    path = as_path(path, "file_names: path")
    if path.suffix not in (".state", ".bdm"):
        return {}
    lines = _read_lines(path)
    if not lines or not lines[0].lstrip().startswith("{"):
        return {}
    return {own: name for own, name in object_names(lines[0], where=f"{path}, line 1").items() if own != name}


def read_initial_state(path: str | Path, palette: str | Palette) -> State:
    """The initial state of a corpus file, or the state of a one-line ``.state`` file."""
    if as_path(path, "read_initial_state: path").is_dir():  # the OS says only "Is a directory"
        raise CorpusError(f"{path}: a folder, not a regular file; expected a state file (.state, a one-line .bdm) "
                          "or a corpus file")
    if as_path(path, "read_initial_state: path").suffix in (".state", ".bdm"):
        return read_state_file(path, palette)
    # a device or a FIFO is refused saying what would do here: a state file as well as a corpus file
    return read_instance(path, palette, what="a state file (.state, a one-line .bdm) or a corpus file").initial_state


def example_corpus_path() -> Path:
    """The folder of the small example corpus shipped with groundlang (palette ``sokoban``)."""
    return Path(str(files("groundlang.examples")))
