"""Reading clingo terms as groundlang names them: PF names, tuple arguments, text, and the natural order of
object names."""

from __future__ import annotations

import re

import clingo

from .atoms import attribute_pf
from .program import AspError

__all__ = ["ASP_CONSTANT", "pf_name", "tuple_args", "symbol_text", "natural_key"]

ASP_CONSTANT = re.compile(r"[a-z][A-Za-z0-9_]*\Z")  # a name as facts write it: an attribute, or its value


def pf_name(term: clingo.Symbol) -> str:
    """groundlang's name for a PF term: ``toyInRoom`` stays, ``roomIs(darkGray)`` -> ``roomIsDarkGray``."""
    if term.type is not clingo.SymbolType.Function or not term.name:
        raise AspError(f"PF name {term} must be a constant or a term like roomIs(green)")
    if term.negative:  # clingo's classical negation: -agentInRoom would otherwise read as agentInRoom
        raise AspError(f"PF name {term} is negated; a goal or description names a PF without '-' (what must not "
                       "hold is a PF of its own)")
    name = term.name
    for arg in term.arguments:
        name = attribute_pf(name, arg.string if arg.type is clingo.SymbolType.String else str(arg))
    return name


def natural_key(name: str) -> tuple:
    """``room2`` before ``room10``."""
    return tuple(int(t) if t.isdigit() else t for t in re.findall(r"\d+|\D+", name))


def tuple_args(term: clingo.Symbol) -> tuple[clingo.Symbol, ...]:
    """The elements of a tuple term, ``(a, b)``; a lone value written without parentheses is one."""
    if term.type is clingo.SymbolType.Function and term.name == "":
        return tuple(term.arguments)
    return (term,)  # a lone value written without parentheses


def symbol_text(term: clingo.Symbol) -> str:
    """A string term's text without its quotes; any other term as clingo writes it."""
    return term.string if term.type is clingo.SymbolType.String else str(term)
