"""Read and write one state of the Williams et al. (ICRA 2018) corpus format (groundlang.bdm reads its files).

A state is ``{agent0 (agent): [x: {5} y: {6} direction: {south} ] , room0 (room): [top: {4} left: {0}
bottom: {0} right: {8} colour: {red} ] , block0 (block): [x: {6} y: {6} shape: {chair} colour: {blue} ]
, ... , }``: objects ``NAME (CLASS): [attribute: {value} ...]``; colours and shapes are names of the
palette (``logic/palettes/williams2018.lp`` by default), not indices. Attributes that play no part in the
dynamics (an agent's ``direction``, a door's ``locked`` and ``canbelocked``) are read and ignored.
Toys are renamed ``block0, block1, ...`` in the order of their names' numbers (the corpus skips numbers:
``block0, block1, block3``). Every problem is a :class:`~groundlang.state_line.CorpusError` naming the
line and the object.
"""

from __future__ import annotations

import re
from collections import Counter

from groundlang.state_line import MAX_COORDINATE, CorpusError, coordinate, shown
from groundlang.model.world import (NAME_PREFIXES, Agent, Door, Layout, Palette, Room, State, Toy, WorldError,
                                   get_palette)

__all__ = ["DEFAULT_PALETTE", "parse_bdm_state", "format_bdm_state", "object_names"]

DEFAULT_PALETTE = "williams2018"

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
    for chunk in filter(str.strip, re.split(r"\s+,\s+", text[1:-1])):  # a tab or a no-break space around it as well
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
