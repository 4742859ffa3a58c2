"""Palettes: the names of the colour and shape indices a corpus file uses, read from ASP files.

Also home of :class:`WorldError`, which :mod:`groundlang.model.world` raises for layouts and states and
re-exports: a palette index out of range is an invalid world too.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from groundlang.logic.palette_files import read_palette
from groundlang.logic.program import AspError

__all__ = ["Palette", "WorldError", "get_palette"]


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
        label, values, drawing = read_palette(str(name))
    except AspError as exc:
        raise WorldError(str(exc)) from None
    missing = [a for a in ("colour", "shape") if a not in values]
    if missing:
        raise WorldError(f"palette {name}: no {' and no '.join(missing)} values; corpus files index "
                         "the colour of rooms and toys and the shape of toys")
    return Palette(label, values["colour"], values["shape"], tuple(sorted(drawing["glyph"].items())),
                   tuple(sorted(drawing["rgb"].items())))
