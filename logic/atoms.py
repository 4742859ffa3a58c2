"""Ground atoms of propositional functions, written as the gold labels write them.

An atom is a predicate applied to object names: ``toyInRoom(block0, room2)``.
The corpus's labels say ``blockInRoom``; groundlang's own name, from the
paper, is ``toyInRoom``. Parsing accepts either and always yields the
paper's name, so a printed atom can be compared with a label after parsing.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["canonical_predicate", "Atom", "AtomError", "attribute_pf", "parse_atom", "parse_goal", "format_goal", "renamed", "renamed_words", "shown"]

# The commands-to-tasks corpus calls toys blocks, in object and predicate names (blockInRoom,
# agentTouchingBlock): its spelling of the class toy, wherever it is a word of a camelCase name.
_CORPUS_CLASS_SPELLING = ("block", "toy")
_CAMEL_WORD = re.compile(r"[A-Z]?[a-z0-9_]+|[A-Z]+(?![a-z])")


def canonical_predicate(name: str) -> str:
    """The paper's spelling of a predicate the corpus spells its own way: ``blockInRoom`` -> ``toyInRoom``,
    ``agentTouchingBlock`` -> ``agentTouchingToy``; any other name is itself."""
    theirs, ours = _CORPUS_CLASS_SPELLING
    words = _CAMEL_WORD.findall(name)
    if "".join(words) != name or theirs not in (w.lower() for w in words):
        return name
    return "".join((ours if w == theirs else ours.capitalize() if w == theirs.capitalize() else w) for w in words)


_ATOM = re.compile(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*\(([^()]*)\)\s*")
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class AtomError(ValueError):
    """Text that is not an atom or a goal."""


@dataclass(frozen=True, order=True)
class Atom:
    """A propositional function applied to named objects."""

    predicate: str
    args: tuple[str, ...]

    def __str__(self) -> str:
        return f"{self.predicate}({', '.join(self.args)})"

    def to_clingo(self) -> str:
        """The same atom with lower-case predicate, as ASP requires: ``holds(...)`` style."""
        return f"{self.predicate}({','.join(self.args)})"


def parse_atom(text: str) -> Atom:
    """Parse ``pred(a, b)``; corpus aliases map to the paper's predicate names."""
    m = _ATOM.fullmatch(text)
    if not m:
        raise AtomError(f"{text.strip()!r} is not an atom like toyInRoom(block0, room1)")
    pred = canonical_predicate(m.group(1))
    args = tuple(a.strip() for a in m.group(2).split(",")) if m.group(2).strip() else ()
    for a in args:
        if not _NAME.fullmatch(a):
            raise AtomError(f"{text.strip()!r}: argument {a!r} is not an object name")
    return Atom(pred, args)


def shown(text: str, unit: str = "characters", limit: int = 20) -> str:
    """``text`` as an error message quotes it: whole when short, else its start and its length (a goal of
    30,000 characters had made a 30 KB error line)."""
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} {unit})"


def parse_goal(text: str) -> tuple[Atom, ...]:
    """Parse a conjunction of atoms separated by spaces (commas inside atoms only)."""
    text = text.strip()
    if not text:
        raise AtomError("empty goal: expected one or more atoms like agentInRoom(agent0, room1)")
    atoms = []
    pos = 0
    while pos < len(text):
        m = _ATOM.match(text, pos)
        if not m:
            raise AtomError(f"cannot read an atom at {shown(text[pos:], limit=60)!r} in goal {shown(text, limit=60)!r}")
        atoms.append(parse_atom(m.group(0)))
        pos = m.end()
    return tuple(atoms)


def format_goal(atoms: tuple[Atom, ...] | list[Atom], names: dict[str, str] | None = None) -> str:
    """Write a conjunction the way the labels CSV does; ``names`` renames objects (a file's names for the
    layout's, as :func:`renamed`)."""
    return " ".join(str(a) for a in (renamed(atoms, names) if names else atoms))


def renamed_words(text: str, names: dict[str, str] | None) -> str:
    """``text`` with every whole-word object name ``names`` has replaced at once ("the green chair block1"
    -> "the green chair block2"): in one pass, so that a name one object is given and another had is
    never renamed twice."""
    if not names:
        return text
    pattern = re.compile(r"(?<!\w)(" + "|".join(map(re.escape, sorted(names, key=len, reverse=True))) + r")(?!\w)")
    return pattern.sub(lambda m: names[m.group(1)], text)


def renamed(atoms, names: dict[str, str]) -> tuple[Atom, ...]:
    """The atoms with each object named by ``names`` where it has an entry (``block2`` -> ``block3``)."""
    return tuple(Atom(a.predicate, tuple(names.get(x, x) for x in a.args)) for a in atoms)


def attribute_pf(stem: str, value: str) -> str:
    """A colour/shape PF's name as logic/pfs.lp spells it: ``attribute_pf("roomIs", "darkGray")`` -> ``roomIsDarkGray``."""
    return stem + value[:1].upper() + value[1:]
