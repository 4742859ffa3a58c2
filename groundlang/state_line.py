"""One state as a line of the commands-to-tasks corpus: parse it, check it is a valid world, write it.

A state line is space-separated objects ``room,COLOUR,LEFT,TOP,RIGHT,BOTTOM``,
``door,LEFT,TOP,RIGHT,BOTTOM``, ``block,COLOUR,SHAPE,X,Y`` (``toy`` is
accepted too) and ``agent,X,Y``; COLOUR and SHAPE index a palette chosen by
name. Every problem is a :class:`CorpusError` (a ``ValueError``) whose message
names the place and what was expected. :mod:`groundlang.corpus` reads whole
files of them; :mod:`groundlang.bdm` shares the error and the limits.
"""

from __future__ import annotations

import re

from groundlang.logic.atoms import shown
from groundlang.model.world import Agent, Door, Layout, Palette, Room, State, Toy, WorldError, get_palette

__all__ = ["CorpusError", "MAX_COORDINATE", "MAX_FILE_BYTES", "coordinate", "parse_state", "format_state",
           "shown", "text_lines"]

# Coordinates beyond this are refused: a layout's grids are allocated densely,
# so one absurd number in a file must not become a gigabyte array.
MAX_COORDINATE = 1000
# A corpus or state file: a demonstration of 10^4 steps takes about 1 MB.
MAX_FILE_BYTES = 16 * 2**20
_INTEGER = re.compile(r"-?[0-9]+")
_DIGITS = re.compile(r"[0-9]+")

# kind -> (field names after the kind, format shown in messages)
_FIELDS = {
    "room": (("COLOUR", "LEFT", "TOP", "RIGHT", "BOTTOM"), "room,COLOUR,LEFT,TOP,RIGHT,BOTTOM"),
    "door": (("LEFT", "TOP", "RIGHT", "BOTTOM"), "door,LEFT,TOP,RIGHT,BOTTOM"),
    "block": (("COLOUR", "SHAPE", "X", "Y"), "block,COLOUR,SHAPE,X,Y"),
    "agent": (("X", "Y"), "agent,X,Y"),
}
_KIND_ALIASES = {"toy": "block"}


def is_state_line(line: str) -> bool:
    """Whether ``line`` starts as a state line does (``room,5,0,...``), not as a command: a file holding one is
    a corpus file, whose command is its first line."""
    kind, comma, rest = line.strip().partition(",")
    return bool(comma) and (kind in _FIELDS or kind in _KIND_ALIASES) and bool(_INTEGER.match(rest))


class CorpusError(ValueError):
    """A corpus file, folder or labels file that cannot be used; the message says where and why."""


def coordinate(text: str, signed: bool = True) -> int:
    """The integer ``text`` writes (decimal digits, a leading ``-`` if ``signed``); ValueError when it is
    not one, OverflowError when it is larger than ``MAX_COORDINATE`` in size. Without its sign and leading
    zeros, a number of more digits than the bound is too large: its digits are never converted, however
    many a file holds (Python refuses more than 4300)."""
    if not (_INTEGER if signed else _DIGITS).fullmatch(text):
        raise ValueError(text)
    digits = text.lstrip("-").lstrip("0") or "0"
    if len(digits) > len(str(MAX_COORDINATE)) or int(digits) > MAX_COORDINATE:
        raise OverflowError(text)
    return -int(digits) if text.startswith("-") else int(digits)


_LINE_END = re.compile(r"\r\n|\r|\n")


def utf8_text(data: bytes, path) -> str:
    """A text file's bytes as text, a leading byte-order mark (some editors write one) dropped; CorpusError
    naming the line and offset of the first byte that is not UTF-8 (a binary file, a Latin-1 one)."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise CorpusError(
            f"{path}, line {line}: byte 0x{data[exc.start]:02x} at offset {exc.start} is not UTF-8; "
            "expected a UTF-8 text file"
        ) from None
    return text.removeprefix("\ufeff")


def text_lines(text: str) -> list[str]:
    """A corpus file's lines as an editor numbers them: split at the ends of line an editor writes (LF, CRLF,
    and CR alone), not at the other separators ``str.splitlines`` knows (U+2028, form feed, NEL), which a
    command may hold and which would shift every line number an error gives after them."""
    return _LINE_END.split(text)


def _integer(text: str, where: str, name: str, obj: str) -> int:
    """``text`` as a coordinate; ``obj``, the token it is a field of, as :func:`shown` quotes it."""
    try:
        return coordinate(text)
    except OverflowError:
        raise CorpusError(f"{where}: field {name} of {obj!r} is {shown(text, 'digits')}; "
                          f"expected at most {MAX_COORDINATE} in size") from None
    except ValueError:
        raise CorpusError(f"{where}: field {name} of {obj!r} is {shown(text)!r}; expected an integer") from None


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
        quoted = shown(token, limit=60)  # a token of megabytes (a line without spaces) is quoted by its start
        kind = _KIND_ALIASES.get(parts[0], parts[0])
        if kind not in _FIELDS:
            raise CorpusError(
                f"{where}: unknown object kind {shown(parts[0])!r} in {quoted!r}; "
                "expected room, door, block (or toy) or agent"
            )
        names, expected = _FIELDS[kind]
        if len(parts) != len(names) + 1:
            raise CorpusError(
                f"{where}: {quoted!r} has {len(parts)} comma-separated fields; expected "
                f"{len(names) + 1} ({expected})"
            )
        v = {n: _integer(t, where, n, quoted) for n, t in zip(names, parts[1:])}
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
            raise CorpusError(f"{where}: {quoted!r}: {exc}") from None
    if len(agents) != 1:
        raise CorpusError(f"{where}: found {len(agents)} agents; expected exactly one agent,X,Y")
    if palette.added:  # no field of a line gives them: a corpus of such a palette is written as .bdm
        present = {"room": rooms, "door": doors, "toy": toys}
        cls, attribute = next(((c, a) for c, a in palette.added if present[c]), (None, None))
        if cls is not None:
            raise CorpusError(f"{where}: palette {palette.name} gives every {cls} a {attribute}, which this format has "
                              "no field for; write the states as .bdm lines (attribute: {value})")
    layout = Layout(tuple(rooms), tuple(doors), tuple((t.colour, t.shape) for t in toys), palette)
    state = State(layout, agents[0], tuple(toys))
    try:
        if shared_cells_ok and state.shared_cell():
            _validate_positions(state)
        else:
            state.validate()
    except WorldError as exc:
        raise CorpusError(f"{where}: {exc}") from None
    return state



def _validate_positions(state: State) -> None:
    """State.validate without its shared-cell check: the layout, and every object on a walkable cell."""
    state.layout.validate()
    walk = state.layout.walkable
    for name, (x, y) in zip(["agent0"] + state.layout.toy_names, state.positions.tolist()):
        if not (0 <= x < walk.shape[0] and 0 <= y < walk.shape[1]) or not walk[x, y]:
            raise WorldError(f"{name} at ({x},{y}) is inside a wall or outside every room")


def format_state(state: State) -> str:
    """Write a state as one corpus line: rooms, doors, blocks, agent (round-trips with parse_state)."""
    if not isinstance(state, State):
        raise TypeError(f"format_state: state must be a State, got {type(state).__name__}")
    lay = state.layout
    pal = lay.palette
    if lay.added_attributes:
        name, attribute, _ = lay.added_attributes[0]
        raise WorldError(f"{name}'s {attribute} has no field in a commands-to-tasks state line; write the state "
                         "with format_bdm_state")
    objs = [f"room,{pal.colour_index(r.colour)},{r.left},{r.top},{r.right},{r.bottom}" for r in lay.rooms]
    objs += [f"door,{d.left},{d.top},{d.right},{d.bottom}" for d in lay.doors]
    objs += [
        f"block,{pal.colour_index(t.colour)},{pal.shape_index(t.shape)},{t.x},{t.y}" for t in state.toys
    ]
    objs.append(f"agent,{state.agent.x},{state.agent.y}")
    return " ".join(objs)
