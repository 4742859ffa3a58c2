"""What a palette's record must be (``Palette.record``; a trained model keeps one per palette trained on):
checked where one is read back, from a model file or given for a palette (``get_palette``)."""

from __future__ import annotations

from groundlang.logic.terms import ASP_CONSTANT
from groundlang.model.palette import ATTRIBUTED_CLASSES, added_attribute_problem

__all__ = ["checked_palettes"]


def checked_palettes(palettes) -> list[dict]:
    """The palettes a model was trained on, as written: a list of {name, colours, shapes} (and the attributes
    a palette added, ``Palette.record``)."""
    if not isinstance(palettes, list) or not palettes:
        raise ValueError("palettes must be a non-empty list")
    for p in palettes:
        if (not isinstance(p, dict) or not isinstance(p.get("name"), str) or not p["name"].strip()
                or not all(isinstance(v, list) and all(isinstance(x, str) for x in v)
                           for v in (p.get("colours"), p.get("shapes")))):
            raise ValueError("each palette must be {name: str (not blank), colours: [str], shapes: [str]}")
        for field in ("colours", "shapes"):  # a state is read with them (follow): each a value, once
            _check_names(p["name"], field, p[field])
        if "added" in p or "added_values" in p:
            _check_added(p)
        if "drawing" in p:
            _check_drawing(p)
        if "value_classes" in p:
            _check_value_classes(p)
    return palettes


def _check_drawing(p: dict) -> None:
    """A palette record's drawing hints, as ``Palette.record`` writes them: ``drawing`` {"glyph": {shape:
    text}, "rgb": {colour: name}}, every key and value a string."""
    drawing = p["drawing"]
    if (not isinstance(drawing, dict) or set(drawing) - {"glyph", "rgb"}
            or not all(isinstance(d, dict) and all(isinstance(k, str) and isinstance(v, str) and v.strip()
                                                   for k, v in d.items())
                       for d in drawing.values())):
        raise ValueError(f"palette {p['name']!r}: drawing must be {{\"glyph\": {{shape: text}}, \"rgb\": "
                         "{colour: name}}, every key a string and every value a string that is not blank")


def _check_names(palette: str, field: str, values) -> None:
    """ValueError unless ``values`` are distinct lowerCamelCase names, at least one (a palette's values of one
    attribute, as a state's facts write them)."""
    if not isinstance(values, list) or not all(isinstance(v, str) for v in values):
        raise ValueError(f"palette {palette!r}: {field} must be a list of names")
    odd = next((v for v in values if not ASP_CONSTANT.match(v)), None)
    if not values or odd is not None or len(set(values)) != len(values):
        raise ValueError(f"palette {palette!r}: {field} must be distinct lowerCamelCase names, at least "
                         f"one" + (f" ({odd!r} is not one)" if odd is not None else ""))


def _check_added(p: dict) -> None:
    """The attributes a palette record adds: ``added`` [[class, attribute], ...], each attribute's values
    under ``added_values`` {attribute: [value, ...]}, as ``Palette.record`` writes them."""
    added, values = p.get("added"), p.get("added_values")
    shape = f"palette {p['name']!r}: added must be [[class, attribute], ...] and added_values {{attribute: [values]}}"
    if (not isinstance(added, list) or not isinstance(values, dict)
            or not all(isinstance(x, list) and len(x) == 2 and all(isinstance(s, str) for s in x) for x in added)):
        raise ValueError(shape)
    if {a for _, a in added} != set(values):
        raise ValueError(f"{shape}, the same attributes in both")
    for cls, attribute in added:
        if problem := added_attribute_problem(cls, attribute):
            raise ValueError(f"palette {p['name']!r}: attribute({cls}, {attribute}): {problem}")
    seen = set(p["colours"]) | set(p["shapes"])
    for attribute, vs in values.items():
        _check_names(p["name"], f"{attribute} values", vs)
        if twice := sorted(seen & set(vs)):  # as a palette file may not: the PFs of the two would be one
            raise ValueError(f"palette {p['name']!r}: {twice[0]} is a value of {attribute} and of another attribute")
        seen |= set(vs)


def _check_value_classes(p: dict) -> None:
    """Which classes may have a value: ``value_classes`` {value: [class, ...]}, classes a palette describes."""
    classes = p["value_classes"]
    if (not isinstance(classes, dict)
            or not all(isinstance(v, str) and isinstance(cs, list) and cs and all(c in ATTRIBUTED_CLASSES for c in cs)
                       for v, cs in classes.items())):
        raise ValueError(f"palette {p['name']!r}: value_classes must be {{value: [class, ...]}}, each class one of "
                         f"{', '.join(ATTRIBUTED_CLASSES)}")
