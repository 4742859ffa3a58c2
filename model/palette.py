"""Palettes: the names of the colour and shape indices a corpus file uses, and the attributes a palette
adds to objects (``attribute(Class, Attribute)``), read from ASP files.

Also home of :class:`WorldError`, which :mod:`groundlang.model.world` raises for layouts and states and
re-exports: a palette index out of range is an invalid world too.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from functools import lru_cache

from groundlang.logic.palette_files import read_palette
from groundlang.logic.program import AspError, Program, package_source
from groundlang.logic.terms import ASP_CONSTANT

__all__ = ["ATTRIBUTED_CLASSES", "Palette", "WorldError", "added_attribute_problem", "check_attribute_clash",
           "get_palette"]


class WorldError(ValueError):
    """A layout or state that is not a valid Cleanup World."""



@dataclass(frozen=True)
class Palette:
    """Names for the colour and shape indices a corpus file uses, and the attributes it adds to objects."""

    name: str
    colours: tuple[str, ...]
    shapes: tuple[str, ...]
    # How pictures draw values (glyph/2, rgb/2 of the palette file); not part of what a palette means.
    glyphs: tuple[tuple[str, str], ...] = field(default=(), compare=False)
    rgb: tuple[tuple[str, str], ...] = field(default=(), compare=False)
    # The attributes the palette adds (attribute/2 of its file): ``(class, attribute)`` pairs, sorted, and
    # each added attribute's values by index. A state gives every object of such a class one of the values.
    added: tuple[tuple[str, str], ...] = ()
    added_values: tuple[tuple[str, tuple[str, ...]], ...] = ()
    # value_class/2 of its file: (value, the only classes whose objects may have it), sorted; a value not
    # listed may be any class's. What states may say, not what a value means: a model saved before a palette
    # said it reads the palette's states as before.
    value_classes: tuple[tuple[str, tuple[str, ...]], ...] = field(default=(), compare=False)

    def worn_by(self, cls: str, values: tuple[str, ...]) -> tuple[str, ...]:
        """``values`` an object of ``cls`` may have (``value_class/2`` gives some to other classes only)."""
        only = dict(self.value_classes)
        return tuple(v for v in values if v not in only or cls in only[v])

    def check_values(self, objects) -> None:
        """WorldError for the first object (``(class, name, facts)`` as ``Layout.objects`` gives them) with a
        value ``value_class/2`` gives to other classes only."""
        if not self.value_classes:
            return
        allowed = dict(self.value_classes)
        for cls, name, facts in objects:
            for attribute, args in facts:
                if args and args[0] in allowed and cls not in allowed[args[0]]:
                    raise WorldError(f"{name} has the {attribute} {args[0]}, which palette {self.name} gives to "
                                     f"{' and '.join(c + 's' for c in allowed[args[0]])} only (value_class/2)")

    def attributes_of(self, cls: str) -> tuple[str, ...]:
        """The attributes the palette adds to objects of class ``cls`` (``("material",)``), sorted."""
        return tuple(a for c, a in self.added if c == cls)

    def values_of(self, attribute: str) -> tuple[str, ...]:
        """The values of ``attribute`` by index: colour, shape or an added one; KeyError otherwise."""
        return dict(self.all_values)[attribute]

    @property
    def all_values(self) -> tuple[tuple[str, tuple[str, ...]], ...]:
        """``(attribute, values)`` of every attribute: colour, shape, then the added ones."""
        return (("colour", self.colours), ("shape", self.shapes)) + self.added_values

    def record(self) -> dict:
        """What a saved model keeps of the palette: its values, and its drawing hints under ``drawing``
        (not meaning: two records that differ only there are one palette, :meth:`from_record` compares
        equal). The added attributes and the hints only where there are some, so a palette of colours and
        shapes alone is recorded as before they could be added."""
        out = {"name": self.name, "colours": list(self.colours), "shapes": list(self.shapes)}
        if self.added:
            out["added"] = [list(pair) for pair in self.added]
            out["added_values"] = {a: list(vs) for a, vs in self.added_values}
        if self.value_classes:
            out["value_classes"] = {v: list(cs) for v, cs in self.value_classes}
        if self.glyphs or self.rgb:  # a model's own palette file is drawn as it was, with no --palette
            out["drawing"] = {"glyph": dict(self.glyphs), "rgb": dict(self.rgb)}
        return out

    @classmethod
    def from_record(cls, record: dict) -> "Palette":
        """The palette :meth:`record` wrote (a record of a model saved before the drawing hints: none)."""
        drawing = record.get("drawing", {})
        return cls(record["name"], tuple(record["colours"]), tuple(record["shapes"]),
                   tuple(sorted(drawing.get("glyph", {}).items())), tuple(sorted(drawing.get("rgb", {}).items())),
                   added=tuple(tuple(pair) for pair in record.get("added", ())),
                   added_values=tuple((a, tuple(vs)) for a, vs in record.get("added_values", {}).items()),
                   value_classes=tuple((v, tuple(cs)) for v, cs in sorted(record.get("value_classes", {}).items())))

    def colour(self, index: int) -> str:
        if not 0 <= index < len(self.colours):
            raise WorldError(
                f"colour index {index} is outside palette {self.name!r} "
                f"(0..{len(self.colours) - 1})"
            )
        return self.colours[index]

    def shape(self, index: int) -> str:
        if not 0 <= index < len(self.shapes):
            raise WorldError(
                f"shape index {index} is outside palette {self.name!r} "
                f"(0..{len(self.shapes) - 1})"
            )
        return self.shapes[index]

    def colour_index(self, name: str) -> int:
        try:
            return self.colours.index(name)
        except ValueError:
            raise WorldError(f"colour {name!r} is not in palette {self.name!r}") from None

    def shape_index(self, name: str) -> int:
        try:
            return self.shapes.index(name)
        except ValueError:
            raise WorldError(f"shape {name!r} is not in palette {self.name!r}") from None


def get_palette(name: str | Palette | dict) -> Palette:
    """The palette ``name``: one the package ships (``logic/palettes/NAME.lp``), the path of a
    ``.lp`` file of ``value(Attribute, Index, Name)`` facts, or a palette's record as a trained model keeps
    it (``Learner.palettes``: a model trained on a file of your own reads states without the file).
    Raises WorldError naming what is wrong."""
    if isinstance(name, Palette):
        return name
    if isinstance(name, dict):
        from groundlang.model.palette_records import checked_palettes  # (it reads this module's names)

        try:
            return Palette.from_record(checked_palettes([name])[0])
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise WorldError(f"palette record {str(name)[:60]}: not a palette's record as Learner.palettes keeps "
                             f"it ({exc})") from None
    if not isinstance(name, (str, os.PathLike)):
        raise TypeError(f"palette must be a name, the path of a .lp file, a Palette or a palette's record (a dict), "
                        f"got {type(name).__name__}")
    try:
        label, values, drawing, added, value_classes = read_palette(str(name))
    except AspError as exc:
        raise WorldError(str(exc)) from None
    missing = [a for a in ("colour", "shape") if a not in values]
    if missing:
        raise WorldError(f"palette {name}: no {' and no '.join(missing)} values; corpus files index "
                         "the colour of rooms and toys and the shape of toys")
    for cls, attribute in added:
        problem = added_attribute_problem(cls, attribute)
        if problem:
            raise WorldError(f"palette {name}: attribute({cls}, {attribute}): {problem}")
    alike = sorted({a for _, a in added}, key=lambda a: (a.lower(), a))
    for a, b in zip(alike, alike[1:]):
        if a.lower() == b.lower():  # a .bdm line's attribute names are read in lower case
            raise WorldError(f"palette {name}: attributes {a} and {b} differ in case only; a .bdm line could not "
                             "tell them apart")
    added_values = tuple((a, values[a]) for a in sorted({a for _, a in added}))
    for value, classes in value_classes:
        if unknown := [c for c in classes if c not in ATTRIBUTED_CLASSES]:
            raise WorldError(f"palette {name}: value_class({value}, {unknown[0]}): {unknown[0]} is not a class whose "
                             f"objects a palette describes ({', '.join(ATTRIBUTED_CLASSES)})")
    return Palette(label, values["colour"], values["shape"], tuple(sorted(drawing["glyph"].items())),
                   tuple(sorted(drawing["rgb"].items())), added, added_values, value_classes)


# The classes whose objects a palette may give attributes; the agent is the one addressed, not described.
ATTRIBUTED_CLASSES = ("room", "door", "toy")
# The world's own attributes of its objects (where they are), which a state line writes beside a palette's.
WORLD_ATTRIBUTES = ("x", "y", "left", "top", "right", "bottom")


def added_attribute_problem(cls: str, attribute: str) -> str | None:
    """What is wrong with a palette giving objects of ``cls`` ``attribute``; None: nothing. A clash with a
    task library's own predicates is checked where the two meet (:func:`check_attribute_clash`)."""
    if cls not in ATTRIBUTED_CLASSES:
        return f"{cls} is not a class whose objects a palette describes ({', '.join(ATTRIBUTED_CLASSES)})"
    if not ASP_CONSTANT.match(attribute):  # a state's facts write it as a predicate
        return "an attribute is a lowerCamelCase name"
    if attribute in ("colour", "shape"):
        return ("colour and shape are the corpus formats' own fields (a room's colour, a toy's colour and shape); "
                "attribute/2 adds attributes of other names")
    if attribute.lower() in WORLD_ATTRIBUTES:
        return f"{attribute} is where an object is ({', '.join(WORLD_ATTRIBUTES)} are the world's); rename the attribute"
    defined = _package_predicates().get(attribute)
    if defined:
        return f"a state writes it as {attribute}(Object, Value), which {defined} already defines; rename the attribute"
    return None


def check_attribute_clash(palette: Palette, program: Program) -> None:
    """AspError (one line) when ``program`` defines a predicate of two arguments named like an attribute
    ``palette`` adds: a state's facts of the attribute would add to it (a library's ``area(R, A)`` and a
    room's ``area``: every room the largest)."""
    if not palette.added:
        return
    definitions = _definitions(program)
    for cls, attribute in palette.added:
        if (attribute, 2) in definitions:
            raise AspError(f"palette {palette.name}: attribute({cls}, {attribute}): a state writes it as "
                           f"{attribute}(Object, Value), which {definitions[(attribute, 2)]} defines too; rename "
                           "the attribute")


@lru_cache(maxsize=32)
def _definitions(program: Program) -> dict[tuple[str, int], str]:
    return program.definitions()


@lru_cache(maxsize=1)
def _package_predicates() -> dict[str, str]:
    """The names the package's ASP files define with two arguments, each with its file: an attribute's facts
    must not be one."""
    names = ("domain.lp", "pfs.lp", "groundings.lp", "tabulate.lp", "tasks.lp")
    program = Program(tuple(package_source(n) for n in names))
    return {name: source for (name, arity), source in program.definitions().items() if arity == 2}
