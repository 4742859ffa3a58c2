"""Read the Williams et al. (ICRA 2018) corpus format: one command, several (start, end) state pairs.

A ``.bdm`` file holds blocks separated by blank lines::

    the command, free text
    start state          (a BURLAP object-oriented state string, one line)
    end state
    true
    ---                  (between pairs)
    ...                  (three pairs per command in the published corpus)

Blank lines beside a ``---`` do not end the command: a ``---`` promises another pair of the same one.

Each state line is read by :mod:`groundlang.bdm_state` (its format is said there); toys are renamed
``block0, block1, ...`` and :attr:`Pair.toy_names` keeps the file's names. Every problem is a
:class:`~groundlang.state_line.CorpusError` naming the file, the line and the object.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from groundlang.bdm_state import DEFAULT_PALETTE, format_bdm_state, object_names, parse_bdm_state
from groundlang.state_line import MAX_FILE_BYTES, CorpusError, text_lines
from groundlang.grammar.parser import command_fault
from groundlang.logic.storage import FileRefused, as_path, read_limited
from groundlang.model.world import Layout, Palette, State

__all__ = ["Pair", "Command", "DEFAULT_PALETTE", "parse_bdm_state", "read_bdm", "command_texts", "is_bdm",
           "bdm_files", "format_bdm_state", "object_names"]

# A command's text is one line; a state line of the published corpus is under 1 kB.
_MAX_LINE = 1 << 16


@dataclass(frozen=True)
class Pair:
    """One (start, end) pair of a command, with where it is in the file."""

    start: State
    end: State
    line: int  # line of the start state
    toy_names: tuple[str, ...]  # the file's names of block0, block1, ... (e.g. block0, block1, block3)


@dataclass(frozen=True)
class Command:
    """A command and the pairs it was written for, each pair in its own layout."""

    path: Path
    line: int
    text: str
    pairs: tuple[Pair, ...]


def is_bdm(path: str | Path) -> bool:
    return Path(path).suffix.lower() == ".bdm"


def bdm_files(path: str | Path, any_name: bool = False) -> list[Path]:
    """``path`` itself if it is a ``.bdm`` file, the ``.bdm`` files of a folder (sorted), else none.

    ``any_name`` (the format said, ``--format williams2018``): a file is read as one whatever its name, and
    a folder without ``.bdm`` files gives its ``.txt`` files (a copy saved under another extension)."""
    path = Path(path)
    if path.is_dir():
        entries = list(path.iterdir())
        found = sorted(p for p in entries if is_bdm(p))
        if any_name and not found:
            return sorted(p for p in entries if p.suffix.lower() == ".txt" and p.is_file())
        if found and any(p.suffix == ".txt" for p in entries):
            # Which kind the folder is would otherwise be decided by the .bdm files, the rest left unread.
            raise CorpusError(f"{path}: holds both .bdm files and corpus files (*.txt); a folder is one corpus "
                              "of one format, so move one kind out")
        return found
    return [path] if is_bdm(path) or (any_name and path.is_file()) else []


def read_bdm(path: str | Path, palette: str | Palette = DEFAULT_PALETTE) -> list[Command]:
    """Every command of a ``.bdm`` file with its pairs; raises CorpusError naming the file and line."""
    path = as_path(path, "read_bdm: path")
    # The corpus shows one demonstration to several workers: of the Williams training file's 9714 state
    # lines, a few hundred are distinct, so each distinct line is parsed once (a file's lines bound it).
    states: dict[str, tuple[State, tuple[str, ...]]] = {}
    commands = [_command(path, start_line, block, palette, states) for start_line, block in _blocks(path)]
    if not commands:
        raise CorpusError(f"{path}: no command in the file; expected blocks of a command and (start, end) pairs")
    return commands


def command_texts(path: str | Path) -> list[tuple[int, str]]:
    """(line, text) of every command of a ``.bdm`` file, its states left unread (``groundlang parse --file``
    needs the words alone, in whatever palette the states are); CorpusError as :func:`read_bdm`'s."""
    path = as_path(path, "command_texts: path")
    texts = [block[0] for _, block in _blocks(path)]
    for line, text in texts:
        _check_command_line(path, line, text)
    if not texts:
        raise CorpusError(f"{path}: no command in the file; expected blocks of a command and (start, end) pairs")
    return texts


def _blocks(path: Path) -> list[tuple[int, list[tuple[int, str]]]]:
    """The file's blocks, each its first line's number and its (line, text) lines, the file read bounded."""
    try:  # regular files only, of a bounded size: a FIFO or /dev/zero is refused by name
        data = read_limited(path, MAX_FILE_BYTES, "a .bdm corpus file")
    except FileRefused as exc:
        raise CorpusError(str(exc)) from None
    except OSError as exc:
        raise CorpusError(f"{path}: {exc.strerror or exc}") from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise CorpusError(f"{path}, line {line}: not UTF-8 text") from None
    lines = text_lines(text)
    blocks = []
    i = 0
    while i < len(lines):
        if not lines[i].strip():
            i += 1
            continue
        start_line = i + 1
        block = []
        while i < len(lines):
            if not lines[i].strip():
                i = _past_blank_beside_separator(lines, i, block)
                if not lines[i].strip():
                    break
            if len(lines[i]) > _MAX_LINE:
                raise CorpusError(f"{path}, line {i + 1}: a line of {len(lines[i])} characters; expected at most {_MAX_LINE}")
            block.append((i + 1, lines[i].strip()))
            i += 1
        blocks.append((start_line, block))
    return blocks


def _past_blank_beside_separator(lines: list[str], i: int, block: list[tuple[int, str]]) -> int:
    """Where the block continues past the blank line ``i``: a ``---`` only ever separates two pairs of one
    command, so blank lines before it, or between it and the start state after it, are read through (a
    stray blank line there is not a new command whose text is ``---``). Else ``i`` itself: the block ends."""
    j = i
    while j < len(lines) and not lines[j].strip():
        j += 1
    if j == len(lines):
        return i
    after = lines[j].strip()
    if after == "---" or (block[-1][1] == "---" and after.startswith("{")):
        return j
    return i


def _in_layout_of(first: State, names: tuple[str, ...], last: State, end_names: tuple[str, ...]) -> State | None:
    """``last`` in ``first``'s layout: the corpus numbers rooms and doors afresh in each state line (the
    same rooms, listed in another order), so objects are matched by what they are; toys by name. None
    when the two states do not share one layout."""
    if last.layout == first.layout and end_names == names:
        return last
    a, b = first.layout, last.layout
    if (sorted(map(repr, a.rooms)) != sorted(map(repr, b.rooms)) or sorted(map(repr, a.doors)) != sorted(map(repr, b.doors))
            or sorted(names) != sorted(end_names)):
        return None
    toys = {n: t for n, t in zip(end_names, last.toys)}
    moved = tuple(toys[n] for n in names)
    if tuple((t.colour, t.shape) for t in moved) != a.toy_attributes:
        return None
    if (a.added_attributes or b.added_attributes) and _added_by_object(a, names) != _added_by_object(b, end_names):
        return None
    return State(a, last.agent, moved)


def _added_by_object(layout: Layout, toy_names: tuple[str, ...]) -> dict:
    """The added attributes' values of each object, keyed by what the object is (a room or door by its
    rectangle, a toy by its name in the file), so two lines listing one layout in two orders compare."""
    keys = [("room", repr(r)) for r in layout.rooms] + [("door", repr(d)) for d in layout.doors]
    keys += [("block", n) for n in toy_names]
    names = layout.room_names + layout.door_names + layout.toy_names
    return {key: layout.added_values(name) for key, name in zip(keys, names)}


def _check_command_line(path: Path, line: int, text: str) -> None:
    """A block's first line is its command: not a separator, a state or the word true, and words."""
    if text == "---":
        raise CorpusError(f"{path}, line {line}: --- where a command was expected; --- separates two pairs of one "
                          "command, after its text")
    if text.startswith("{"):
        raise CorpusError(f"{path}, line {line}: a block starts with a state; expected the command first")
    if text.lower() == "true":
        raise CorpusError(f"{path}, line {line}: a block starts with the word true; expected the command first")
    if fault := command_fault(text):
        raise CorpusError(f"{path}, line {line}: the command {fault}; expected the command's words")


def _command(path: Path, line: int, block: list[tuple[int, str]], palette,
             states: dict[str, tuple[State, tuple[str, ...]]]) -> Command:
    text = block[0][1]
    _check_command_line(path, line, text)
    pairs = []
    rest = block[1:]
    k = 0
    while k < len(rest):
        chunk = rest[k:k + 3]
        if len(chunk) < 3:
            raise CorpusError(f"{path}, line {chunk[0][0]}: a pair needs a start state, an end state and the word "
                              "true; the block ends first")
        (start_no, start), (end_no, end), (true_no, true) = chunk
        for number, text_there, which in ((start_no, start, "start"), (end_no, end, "end")):
            if not text_there.lstrip().startswith("{"):  # a state left out: say which, not that true is late
                raise CorpusError(f"{path}, line {number}: expected the {which} state of a pair (a state in braces), "
                                  f"found {text_there[:40]!r}")
        if true.lower() != "true":
            raise CorpusError(f"{path}, line {true_no}: expected the word true after the end state, found {true[:40]!r}")
        for number, text_there in ((start_no, start), (end_no, end)):
            if text_there not in states:
                states[text_there] = parse_bdm_state(text_there, palette, f"{path}, line {number}")
        first, names = states[start]
        last, end_names = states[end]
        last = _in_layout_of(first, names, last, end_names)
        if last is None:
            raise CorpusError(f"{path}, line {end_no}: the end state's rooms, doors or blocks differ from the start "
                              f"state's (line {start_no}); a pair shares one layout")
        pairs.append(Pair(first, last, start_no, names))
        k += 3
        if k < len(rest):
            if rest[k][1] != "---":
                text = rest[k][1].strip()
                # the next command's text, written with no blank line before it: say where a block ends
                after = ("" if text.startswith("{") or text.lower() in ("true", "false") or set(text) <= {"-"}
                         else " (a command's block ends with a blank line)")
                raise CorpusError(f"{path}, line {rest[k][0]}: expected --- between pairs, found "
                                  f"{rest[k][1][:40]!r}{after}")
            k += 1
            # A file cut off after a separator would otherwise lose the pair it promised silently.
            if k == len(rest) or not rest[k][1].startswith("{"):
                found = f" (line {rest[k][0]} is {rest[k][1][:40]!r}, not a start state)" if k < len(rest) else ""
                raise CorpusError(f"{path}, line {rest[k - 1][0]}: --- at line {rest[k - 1][0]} is followed by no "
                                  f"pair{found}; --- separates two pairs of one command (remove it, or add the pair)")
    if not pairs:
        raise CorpusError(f"{path}, line {line}: the command {text[:40]!r} has no (start, end) pair (its pairs "
                          f"follow it with no blank line between: a blank line ends a command)")
    return Command(path, line, text, tuple(pairs))
