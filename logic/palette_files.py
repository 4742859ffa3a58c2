"""Palettes as data: the attribute values a corpus file writes as indices, read from ``.lp`` facts.

A palette is a file of facts ``value(Attribute, Index, Name)``
(``logic/palettes/sokoban.lp``: ``value(colour, 10, red).``). The package ships
one file per corpus palette; a user's own is any ``.lp`` file of such facts,
named by its path (``--palette my_palette.lp``) and called by its stem.
Rooms have a colour and toys a colour and a shape in every palette (the corpus
formats give them); ``attribute(Class, Attribute)`` gives the objects of a class
an attribute more (``attribute(toy, material).``), whose values the file lists.
"""

from __future__ import annotations

from functools import lru_cache
from importlib.resources import files
from pathlib import Path

import clingo
from clingo import ast

from .program import AspError, file_source, package_source, Program, term_signature

__all__ = ["PaletteError", "palette_names", "read_palette"]

_PACKAGE_FOLDER = "palettes"


class PaletteError(AspError):
    """A palette that is not known or whose facts are not a palette."""


def palette_names() -> list[str]:
    """The palettes the package ships (the stems of ``logic/palettes/*.lp``), sorted."""
    folder = files("groundlang.logic") / _PACKAGE_FOLDER
    return sorted(p.name[:-3] for p in folder.iterdir() if p.name.endswith(".lp"))


def _is_path(name: str) -> bool:
    return name.endswith(".lp") or "/" in name or "\\" in name


# The facts a palette is made of, as they are written; anything else in the file is a mistake (a value/3 fact
# of two fields had been dropped without a word, and the value it meant refused later by a state that used it).
_FACTS = {("value", 3): "value(Attribute, Index, Name)", ("glyph", 2): 'glyph(Shape, "text")',
          ("rgb", 2): 'rgb(Colour, "colour")', ("attribute", 2): "attribute(Class, Attribute)",
          ("value_class", 2): "value_class(Value, Class)"}


def _check_facts(program: Program, where: str) -> None:
    """PaletteError naming the file and line of a fact or rule head that is none of a palette's facts, nor a
    helper a rule reads (``name(0, red). value(colour, I, N) :- name(I, N).``)."""
    for _, statements in program.statements_by_source():
        for stm in statements:  # what a palette's one solve would not read, or read as nothing
            if stm.ast_type == ast.ASTType.Program and stm.name != "base":
                raise PaletteError(f"{where}, line {stm.location.begin.line}: #program {stm.name}: a palette is read "
                                   "as one program; what follows it would be left out")
    if (call := program.script_call()) is not None:  # a text's "@" is no call ('glyph(moon, "@")')
        raise PaletteError(f"{where}, line {call.location.begin.line}: {call}: a palette calls no script")
    helpers = program.body_signatures()
    for _, term in program.head_atoms():
        signature = term_signature(term)
        if signature is None or (signature not in _FACTS and signature not in helpers):
            raise PaletteError(f"{where}, line {term.location.begin.line}: {term} is none of a palette's facts "
                               f"({', '.join(_FACTS.values())}) nor read by a rule")


def read_palette(name: str) -> tuple:
    """:func:`_read_palette` of ``name``, read again when a palette file changed since it was last read (a
    notebook that edits its palette file reads the new one; the package's own are read once)."""
    stamp = None
    if _is_path(name):
        try:
            info = Path(name).stat()
            stamp = (info.st_mtime_ns, info.st_size)
        except OSError:
            stamp = None  # reading it says what is wrong
    return _read_palette(name, stamp)


@lru_cache(maxsize=64)
def _read_palette(name: str, stamp: tuple | None = None) -> tuple[str, dict[str, tuple[str, ...]], dict[str, dict[str, str]],
                                      tuple[tuple[str, str], ...], tuple[tuple[str, tuple[str, ...]], ...]]:
    """``(palette name, {attribute: values by index}, drawing, added, value classes)`` of a shipped palette or
    a palette file; ``drawing`` holds the optional ``glyph(Value, "text")`` and ``rgb(Value, "colour")`` facts
    as ``{"glyph": {value: text}, "rgb": {value: colour}}``; ``added`` the ``attribute(Class, Attribute)``
    facts as sorted ``(class, attribute)`` pairs; value classes the optional ``value_class(Value, Class)``
    facts as sorted ``(value, classes)``: the only classes whose objects may have that value (the Williams
    palette's box sizes, stored in the colour field, are a toy's only).

    Raises PaletteError (one line, naming the file and the fact) for an unknown name, a file that is
    not one, indices that skip or repeat, or a value that is not an ASP constant.
    """
    if _is_path(name):
        path = Path(name)
        try:
            source = file_source(path)
        except OSError as exc:
            raise PaletteError(f"{path}: {exc.strerror or exc}") from None
        label = path.stem
    elif name in palette_names():
        source = package_source(f"{_PACKAGE_FOLDER}/{name}.lp")
        label = name
    else:
        raise PaletteError(f"unknown palette {name!r}; expected one of {', '.join(palette_names())} "
                           "or the path of a .lp file of value(Attribute, Index, Name) facts")
    program = Program((source,), isolated=not source.name.startswith("groundlang."))
    found: dict[str, dict[int, str]] = {}
    drawing: dict[str, dict[str, str]] = {"glyph": {}, "rgb": {}}
    added: set[tuple[str, str]] = set()
    classes: dict[str, set[str]] = {}
    _check_facts(program, source.name)
    shown = " ".join(f"#show {name}/{arity}." for name, arity in _FACTS)
    models = program.solve(shown, models=2)
    if len(models) != 1:  # a choice or a disjunction: the values would be whichever answer clingo gave first
        raise PaletteError(f"{source.name}: " + ("no answer set (a constraint always fails)" if not models else
                           "more than one answer set (a choice, a disjunction): a palette says one set of values"))
    for model in models:
        for sym in model:
            if sym.name == "value_class":
                if not all(a.type is clingo.SymbolType.Function and not a.arguments for a in sym.arguments):
                    raise PaletteError(f"{source.name}: {sym} is not value_class(Value, Class) with two names")
                classes.setdefault(sym.arguments[0].name, set()).add(sym.arguments[1].name)
                continue
            if sym.name == "attribute":
                if not all(a.type is clingo.SymbolType.Function and not a.arguments for a in sym.arguments):
                    raise PaletteError(f"{source.name}: {sym} is not attribute(Class, Attribute) with two names")
                added.add(tuple(a.name for a in sym.arguments))
                continue
            if sym.name in drawing:
                value, text = sym.arguments
                if text.type is not clingo.SymbolType.String:
                    raise PaletteError(f'{source.name}: {sym} is not {sym.name}(Value, "text") with a quoted text')
                if not text.string.strip():  # drawn as a mathtext "$ $": matplotlib's error named no palette
                    raise PaletteError(f"{source.name}: {sym}: the text is empty; write one or more characters "
                                       "(or leave the fact out: a glyph defaults to the value's first letter)")
                if drawing[sym.name].setdefault(str(value), text.string) != text.string:
                    raise PaletteError(f'{source.name}: {sym.name}({value}, ...) is given twice, '
                                       f'"{drawing[sym.name][str(value)]}" and "{text.string}"; keep one')
                continue
            attribute, index, value = sym.arguments
            if (attribute.type is not clingo.SymbolType.Function or attribute.arguments
                    or index.type is not clingo.SymbolType.Number
                    or value.type is not clingo.SymbolType.Function or value.arguments):
                raise PaletteError(f"{source.name}: {sym} is not value(Attribute, Index, Name) with a name, "
                                   "a whole number and a lowerCamelCase constant")
            if index.number < 0:
                raise PaletteError(f"{source.name}: {sym}: an index is 0 or more (the files number values 0, 1, "
                                   "2, ...)")
            by_index = found.setdefault(attribute.name, {})
            if index.number in by_index and by_index[index.number] != value.name:
                raise PaletteError(f"{source.name}: {attribute.name} index {index.number} is both "
                                   f"{by_index[index.number]} and {value.name}")
            by_index[index.number] = value.name
    if not found:
        raise PaletteError(f"{source.name}: no value(Attribute, Index, Name) facts: not a palette")
    values = {}
    for attribute, by_index in sorted(found.items()):
        if sorted(by_index) != list(range(len(by_index))):
            missing = min(set(range(len(by_index) + 1)) - set(by_index))
            raise PaletteError(f"{source.name}: {attribute} indices must run 0, 1, 2, ... without a gap; "
                               f"{missing} is missing")
        names = [by_index[i] for i in range(len(by_index))]
        if len(set(names)) != len(names):
            raise PaletteError(f"{source.name}: {attribute} value {next(n for n in names if names.count(n) > 1)} "
                               "has two indices")
        values[attribute] = tuple(names)
    # A value of two attributes would name two families' PFs alike (a colour's and a shape's): one PF.
    seen: dict[str, str] = {}
    for attribute, names in values.items():
        for value in names:
            if (other := seen.setdefault(value, attribute)) != attribute:
                raise PaletteError(f"{source.name}: {value} is both a {other} and a {attribute}; the PFs of the "
                                   "two would have one name, so rename one of them")
    for cls, attribute in sorted(added):
        if attribute not in values:
            raise PaletteError(f"{source.name}: attribute({cls}, {attribute}) names an attribute of no "
                               f"value/3 fact; list its values as value({attribute}, Index, Name)")
    known = {v for names in values.values() for v in names}
    for value in sorted(classes):
        if value not in known:
            raise PaletteError(f"{source.name}: value_class({value}, ...) names a value no value/3 fact gives")
    # a misspelt value was drawn with the default, without a word: a glyph marks a shape, an rgb fills a colour
    for kind, attribute in (("glyph", "shape"), ("rgb", "colour")):
        for value in sorted(set(drawing[kind]) - set(values.get(attribute, ()))):
            said = f"a value of {next(a for a, names in values.items() if value in names)}" if value in known else \
                "a value no value/3 fact gives"
            raise PaletteError(f"{source.name}: {kind}({value}, ...) names {said}; {'an' if kind == 'rgb' else 'a'} "
                               f"{kind} is of a {attribute} value")
    return label, values, drawing, tuple(sorted(added)), tuple((v, tuple(sorted(c))) for v, c in sorted(classes.items()))
