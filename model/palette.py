"""Palettes: the names of the colour and shape indices a corpus file uses, and the attributes a palette
adds to objects (``attribute(Class, Attribute)``), read from ASP files.

Also home of :class:`WorldError`, which :mod:`groundlang.model.world` raises for layouts and states and
re-exports: a palette index out of range is an invalid world too.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

from groundlang.logic.palette_files import read_palette
from groundlang.logic.program import AspError, Program, package_source

__all__ = ["ATTRIBUTED_CLASSES", "Palette", "WorldError", "added_attribute_problem", "get_palette"]


class WorldError(ValueError):
    """A layout or state that is not a valid Cleanup World."""



@dataclass(frozen=True)
class Palette:
    """Names for the colour and shape indices a corpus file uses."""

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
        """What a saved model keeps of the palette (its values; the drawing hints are not meaning).
        The added attributes only where there are some, so a palette of colours and shapes alone is
        recorded as before they could be added."""
        out = {"name": self.name, "colours": list(self.colours), "shapes": list(self.shapes)}
        if self.added:
            out["added"] = [list(pair) for pair in self.added]
            out["added_values"] = {a: list(vs) for a, vs in self.added_values}
        return out

    @classmethod
    def from_record(cls, record: dict) -> "Palette":
        """The palette :meth:`record` wrote (no drawing hints)."""
        return cls(record["name"], tuple(record["colours"]), tuple(record["shapes"]),
                   added=tuple(tuple(pair) for pair in record.get("added", ())),
                   added_values=tuple((a, tuple(vs)) for a, vs in record.get("added_values", {}).items()))

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


def get_palette(name: str | Palette) -> Palette:
    """The palette ``name``: one the package ships (``logic/palettes/NAME.lp``) or the path of a
    ``.lp`` file of ``value(Attribute, Index, Name)`` facts. Raises WorldError naming what is wrong."""
    if isinstance(name, Palette):
        return name
    try:
        label, values, drawing, added = read_palette(str(name))
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
    added_values = tuple((a, values[a]) for a in sorted({a for _, a in added}))
    return Palette(label, values["colour"], values["shape"], tuple(sorted(drawing["glyph"].items())),
                   tuple(sorted(drawing["rgb"].items())), added, added_values)


# The classes whose objects a palette may give attributes; the agent is the one addressed, not described.
ATTRIBUTED_CLASSES = ("room", "door", "toy")


def added_attribute_problem(cls: str, attribute: str) -> str | None:
    """What is wrong with a palette giving objects of ``cls`` ``attribute``; None: nothing."""
    if cls not in ATTRIBUTED_CLASSES:
        return f"{cls} is not a class whose objects a palette describes ({', '.join(ATTRIBUTED_CLASSES)})"
    if attribute in ("colour", "shape"):
        return ("rooms' colour and toys' colour and shape are every palette's, as the corpus formats give them; "
                "attribute/2 adds others")
    if attribute in _domain_predicates():
        return (f"a state writes it as {attribute}(Object, Value), which domain.lp or pfs.lp already defines; "
                "rename the attribute")
    return None


@lru_cache(maxsize=1)
def _domain_predicates() -> frozenset[str]:
    """The names domain.lp and pfs.lp define with two arguments: an attribute's facts must not be one."""
    program = Program((package_source("domain.lp"), package_source("pfs.lp")))
    return frozenset(name for name, arity in program.head_signatures() if arity == 2)
