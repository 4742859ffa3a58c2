"""Read the Williams et al. (ICRA 2018) corpus format: one command, several (start, end) state pairs.

A ``.bdm`` file holds blocks separated by blank lines::

    the command, free text
    start state          (a BURLAP object-oriented state string, one line)
    end state
    true
    ---                  (between pairs)
    ...                  (three pairs per command in the published corpus)

Blank lines beside a ``---`` do not end the command: a ``---`` promises another pair of the same one.

A state is ``{agent0 (agent): [x: {5} y: {6} direction: {south} ] , room0 (room): [top: {4} left: {0}
bottom: {0} right: {8} colour: {red} ] , block0 (block): [x: {6} y: {6} shape: {chair} colour: {blue} ]
, ... , }``: objects ``NAME (CLASS): [attribute: {value} ...]``; colours and shapes are names of the
palette (``logic/palettes/williams2018.lp`` by default), not indices. Attributes that play no part in the
dynamics (an agent's ``direction``, a door's ``locked`` and ``canbelocked``) are read and ignored.
Toys are renamed ``block0, block1, ...`` in the order of their names' numbers (the corpus skips numbers:
``block0, block1, block3``); :attr:`Pair.toy_names` keeps the file's names. Every problem is a
:class:`~groundlang.state_line.CorpusError` naming the file, the line and the object.
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from groundlang.state_line import MAX_COORDINATE, MAX_FILE_BYTES, CorpusError, coordinate, shown, text_lines
from groundlang.grammar.parser import command_fault
from groundlang.logic.storage import FileRefused, as_path, read_limited
from groundlang.model.world import (NAME_PREFIXES, Agent, Door, Layout, Palette, Room, State, Toy, WorldError,
                                   get_palette)

__all__ = ["Pair", "Command", "DEFAULT_PALETTE", "parse_bdm_state", "read_bdm", "is_bdm", "bdm_files",
           "format_bdm_state", "object_names"]

DEFAULT_PALETTE = "williams2018"
# A command's text is one line; a state line of the published corpus is under 1 kB.
_MAX_LINE = 1 << 16

# An object's attributes hold no bracket: two objects run together ("...] ,block3 (block): [...", a space
# missing before the comma) are refused, not read as one whose attributes the second overwrote.
_OBJECT = re.compile(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*\(\s*([A-Za-z_]+)\s*\)\s*:\s*\[([^\[\]]*)\]\s*")
_ATTRIBUTE = re.compile(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*:\s*\{([^{}]*)\}")
# class -> the attributes groundlang reads (lower case); others are allowed and ignored.
_NEEDED = {
    "agent": ("x", "y"),
    "room": ("top", "left", "bottom", "right", "colour"),
    "door": ("top", "left", "bottom", "right"),
    "block": ("x", "y", "shape", "colour"),
}
# The world's class of each .bdm class (a block is a toy), as objects' names say it.
_WORLD_CLASS = dict(NAME_PREFIXES)


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


def _int(text: str, where: str, attribute: str, name: str) -> int:
    text = text.strip()
    try:
        return coordinate(text, signed=False)
    except OverflowError:
        raise CorpusError(f"{where}: {attribute} of {name} is {shown(text, 'digits')}; "
                          f"expected at most {MAX_COORDINATE}") from None
    except ValueError:
        raise CorpusError(f"{where}: {attribute} of {name} is {text!r}; expected a whole number, 0 or more") from None


def _number_order(name: str) -> tuple[int, str]:
    """The number in an object's name as a sort key: its digits compared shortest first, which orders them
    as their values do, with no conversion of a name's thousands of digits."""
    digits = re.sub(r"\D", "", name).lstrip("0")
    return len(digits), digits


def parse_bdm_state(line: str, palette: str | Palette = DEFAULT_PALETTE,
                    where: str = "state") -> tuple[State, tuple[str, ...]]:
    """One BURLAP state string -> ``(State, the file's toy names in block order)``; raises CorpusError."""
    palette = get_palette(palette)
    objects = _read_objects(line, where)
    ordered = lambda cls: _ordered(objects, cls)  # noqa: E731 (the layout's order of a class)
    try:
        rooms = tuple(Room(_value(a["colour"], palette.colours, where, name, "colour",
                                  palette.worn_by("room", palette.colours)), *(
            _int(a[k], where, k, name) for k in ("left", "top", "right", "bottom"))) for name, a in ordered("room"))
        doors = tuple(Door(*(_int(a[k], where, k, name) for k in ("left", "top", "right", "bottom")))
                      for name, a in ordered("door"))
        blocks = ordered("block")
        toys = tuple(Toy(_value(a["colour"], palette.colours, where, name, "colour"),
                         _value(a["shape"], palette.shapes, where, name, "shape"),
                         _int(a["x"], where, "x", name), _int(a["y"], where, "y", name)) for name, a in blocks)
        (agent_name, a), = objects["agent"].items()
        agent = Agent(_int(a["x"], where, "x", agent_name), _int(a["y"], where, "y", agent_name))
        added = tuple(triple for cls, named in (("room", ordered("room")), ("door", ordered("door")),
                                                ("block", blocks))
                      for triple in _added_values(cls, named, palette, where))
        state = State(Layout(rooms, doors, tuple((t.colour, t.shape) for t in toys), palette, added), agent, toys)
        state.validate()
    except WorldError as exc:
        raise CorpusError(f"{where}: {_by_file_names(str(exc), objects)}") from None
    return state, tuple(name for name, _ in blocks)


def _by_file_names(message: str, objects: dict[str, dict[str, dict[str, str]]]) -> str:
    """A world's message about its objects, with each layout id (``room2``: the layout's third room) as the
    file calls that object (``room3`` where the file's rooms are room0, room1, room3), so the line the
    message names can be found in the file."""
    names = _file_names(objects)
    return re.sub(r"\b(?:agent|room|door|block)\d+\b", lambda m: names.get(m.group(0), m.group(0)), message)


def _read_objects(line: str, where: str) -> dict[str, dict[str, dict[str, str]]]:
    """A BURLAP state line's objects: class -> name -> attribute (lower case) -> value; raises CorpusError."""
    text = line.strip()
    if not (text.startswith("{") and text.endswith("}")):
        raise CorpusError(f"{where}: a state is {{object , object , ... , }}; this line does not start with {{ "
                          "and end with }")
    objects: dict[str, dict[str, dict[str, str]]] = {c: {} for c in _NEEDED}
    for chunk in filter(str.strip, text[1:-1].split(" , ")):
        chunk = chunk.strip().rstrip(",").strip()
        if not chunk:
            continue
        m = _OBJECT.fullmatch(chunk)
        if not m and (joined := re.search(r"\]\s*,?\s*([A-Za-z_][A-Za-z0-9_]*)\s*\(", chunk)):
            raise CorpusError(f"{where}: object {joined.group(1)} runs into the one before it; objects are "
                              "separated by ' , ' (a space on each side of the comma)")
        if not m:
            raise CorpusError(f"{where}: cannot read object {chunk[:60]!r}; expected NAME (CLASS): [attribute: {{value}} ...]")
        name, cls, body = m.groups()
        if cls not in _NEEDED:
            raise CorpusError(f"{where}: object {name} has class {cls!r}; expected one of {', '.join(_NEEDED)}")
        pairs = [(a.lower(), v.strip()) for a, v in _ATTRIBUTE.findall(body)]
        twice = sorted(a for a, n in Counter(a for a, _ in pairs).items() if n > 1)
        if twice:
            raise CorpusError(f"{where}: {cls} {name} gives {', '.join(twice)} more than once")
        attributes = dict(pairs)
        missing = [a for a in _NEEDED[cls] if a not in attributes]
        if missing:
            raise CorpusError(f"{where}: {cls} {name} has no {', '.join(missing)}")
        if any(name in named for named in objects.values()):
            raise CorpusError(f"{where}: two objects are called {name}")
        objects[cls][name] = attributes
    if len(objects["agent"]) != 1:
        raise CorpusError(f"{where}: found {len(objects['agent'])} agents; expected exactly one")
    return objects


def _ordered(objects: dict[str, dict[str, dict[str, str]]], cls: str) -> list[tuple[str, dict[str, str]]]:
    """A class's objects in the layout's order: room10 after room9, by the number a name ends with, then by
    name. The layout names them so (room0, room1, ...): :func:`object_names` says which file name is which."""
    return sorted(objects[cls].items(), key=lambda kv: (*_number_order(kv[0]), kv[0]))


def object_names(line: str, where: str = "state") -> dict[str, str]:
    """The file's name of each object of a BURLAP state line, by its name in the layout ``parse_bdm_state``
    reads (``{"block2": "block3", ...}``: objects are renamed in order, ``block0, block1, block3`` becoming
    ``block0, block1, block2``); raises CorpusError where ``parse_bdm_state`` would."""
    return _file_names(_read_objects(line, where))


def _file_names(objects: dict[str, dict[str, dict[str, str]]]) -> dict[str, str]:
    # A .bdm class is its layout name's prefix (_NEEDED's keys are NAME_PREFIXES' prefixes).
    return {f"{prefix}{i}": name for prefix, _ in NAME_PREFIXES
            for i, (name, _) in enumerate(_ordered(objects, prefix))}


def _added_values(cls: str, named: list[tuple[str, dict[str, str]]], palette: Palette,
                  where: str) -> list[tuple[str, str, str]]:
    """``(layout name, attribute, value)`` of the attributes the palette adds to ``cls``'s objects (in
    layout order, ``named``: file name and attributes); a missing or unknown value names the file's object."""
    out = []
    for i, (name, a) in enumerate(named):
        for attribute in palette.attributes_of(_WORLD_CLASS[cls]):
            if attribute.lower() not in a:  # attribute names are read in lower case, as canBeLocked varies
                raise CorpusError(f"{where}: {cls} {name} has no {attribute}; palette {palette.name} gives every "
                                  f"{_WORLD_CLASS[cls]} one")
            value = _value(a[attribute.lower()], palette.values_of(attribute), where, name, attribute)
            out.append((f"{cls}{i}", attribute, value))  # the layout's names: room0, door0, block0, ...
    return out


def _value(value: str, values: tuple[str, ...], where: str, name: str, attribute: str,
           offered: tuple[str, ...] | None = None) -> str:
    if value not in values:
        raise CorpusError(f"{where}: {name} has the {attribute} {value!r}, which the palette does not have "
                          f"(it has {', '.join(values if offered is None else offered)})")
    return value


def format_bdm_state(state: State, toy_names: tuple[str, ...] | None = None,
                     names: dict[str, str] | None = None) -> str:
    """A state as a BURLAP state string (what ``parse_bdm_state`` reads back). Objects are written by the
    layout's names, but the toys by ``toy_names`` (in block order) and any object by ``names`` (the layout's
    name -> the file's, :func:`object_names`), so that a state read from a file is written as it named them."""
    lay = state.layout
    names = dict(names or {}) | dict(zip(lay.toy_names, toy_names or ()))
    file_name = lambda own: names.get(own, own)  # noqa: E731

    def more(name: str) -> str:  # the attributes the palette adds, after the fixed ones
        return "".join(f"{a}: {{{v}}} " for a, v in lay.added_values(name).items())

    parts = [f"{file_name('agent0')} (agent): [x: {{{state.agent.x}}} y: {{{state.agent.y}}} ]"]
    parts += [f"{file_name(n)} (door): [top: {{{d.top}}} left: {{{d.left}}} bottom: {{{d.bottom}}} right: {{{d.right}}} "
              f"{more(n)}]" for n, d in zip(lay.door_names, lay.doors)]
    parts += [f"{file_name(n)} (block): [x: {{{t.x}}} y: {{{t.y}}} shape: {{{t.shape}}} colour: {{{t.colour}}} {more(n)}]"
              for n, t in zip(lay.toy_names, state.toys)]
    parts += [f"{file_name(n)} (room): [top: {{{r.top}}} left: {{{r.left}}} bottom: {{{r.bottom}}} right: {{{r.right}}} "
              f"colour: {{{r.colour}}} {more(n)}]" for n, r in zip(lay.room_names, lay.rooms)]
    return "{" + " , ".join(parts) + " , }"


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
    if bad := next(((line, text) for line, text in texts if text.startswith("{") or text in ("true", "---")), None):
        raise CorpusError(f"{path}, line {bad[0]}: expected a command to start the block, got {bad[1][:40]!r}")
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


def _command(path: Path, line: int, block: list[tuple[int, str]], palette,
             states: dict[str, tuple[State, tuple[str, ...]]]) -> Command:
    text = block[0][1]
    if text == "---":
        raise CorpusError(f"{path}, line {line}: --- where a command was expected; --- separates two pairs of one "
                          "command, after its text")
    if text.startswith("{"):
        raise CorpusError(f"{path}, line {line}: a block starts with a state; expected the command first")
    fault = command_fault(text)
    if fault:
        raise CorpusError(f"{path}, line {line}: the command {fault}; expected the command's words")
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
