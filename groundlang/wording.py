"""Objects and goals in words a person reads: "the star in the red room — toyInRoom(block0, room0)".

Nothing here names a colour, shape, PF or task. An object is described from
what clingo says is true of it (:func:`groundlang.model.tasks.attribute_pfs`,
:func:`~groundlang.model.tasks.object_descriptions`): the value of each of its
attribute PFs as the library writes the term (``roomIs(red)`` gives "red"),
the value of a PF of a kind attribute (``kind/1`` of ``domain.lp``: its shape)
as the head noun when it has one, else its class name; viewpoint PFs (``doorWestOfAgent`` gives "west of the agent") only where
two objects would otherwise read alike. A goal atom is read from its
predicate's camel-case words, each class word replaced by its object's
phrase (``toyInRoom`` gives "<the toy> in <the room>"), unless the library
says how a PF reads (``phrase(agentInCornerOfRoom, "{1} in a corner of {2}")``;
``phrase(toyIsShiny, "shiny")`` describes an object). The model's
semantic tokens are explained from the domain's schema the same way
(:func:`token_meanings`: ``roomIsRed`` is "a room's colour is red", read from
its declaration ``pf(colour, roomIs(red), (room,))``).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence

from groundlang.logic.atoms import Atom, format_goal, renamed_words
from groundlang.logic.schema import Domain, PFDeclaration
from groundlang.logic.tasks import LiftedTask, TaskLibrary
from groundlang.model.interpretations import OTHER_ROLES, object_names
from groundlang.model.tasks import attribute_pfs, kind_pfs, object_descriptions, viewpoint_pfs
from groundlang.model.vocabulary import NULL, class_token
from groundlang.model.world import State, object_class

__all__ = ["object_phrase", "goal_phrase", "labelled_goal", "choice_list", "token_meanings", "DASH"]

DASH = "\u2014"  # between words and ids: "the red room — room0"
_TERM = re.compile(r"^[^()]*\((.*)\)$")
_CLASSES = frozenset(r.removeprefix("other:") for r in OTHER_ROLES)
_CAMEL = re.compile(r"[A-Z]?[a-z0-9]+|[A-Z]+(?![a-z])")
_PLACE = re.compile(r"\{(\d+)\}")


def _camel_words(name: str) -> list[str]:
    return [w.lower() for w in _CAMEL.findall(name)]


def _value(term: str) -> str | None:
    """``roomIs(red)`` -> ``red``; ``toyHue("pale peach")`` -> ``pale peach``; a bare name -> None."""
    m = _TERM.match(term)
    return " ".join(_camel_words(m.group(1).strip('"'))) if m else None


def _describing(name: str, library: TaskLibrary) -> str | None:
    """The library's words describing an object a PF of one argument holds of (a phrase/2 without places)."""
    said = library.phrases.get(name)
    return said if said is not None and not _PLACE.search(said) else None


def _plain_phrase(obj: str, state: State, library: TaskLibrary) -> str:
    cls = object_class(obj)
    described = object_descriptions(state, library).get(obj, {})
    heads = set(kind_pfs(described))  # their values give the head noun ("the star")
    modifiers, head = [], None
    for name, term in attribute_pfs(state, library).get(obj, ()):
        value = _describing(name, library) or _value(term)
        if value is None:
            continue
        if name in heads and head is None:
            head = value
        elif name not in heads:
            modifiers.append(value)
    return " ".join(["the", *modifiers, head or cls])


def _spatial(obj: str, state: State, library: TaskLibrary) -> str:
    cls = object_class(obj)
    sides = []
    for name in viewpoint_pfs(object_descriptions(state, library).get(obj, {}), library):
        if said := _describing(name, library):
            sides.append(said)
            continue
        words = _camel_words(name)
        if words and words[0] == cls:
            words = words[1:]
        if words and words[-1] in _CLASSES:  # the other object of a spatial PF is named by its class
            words[-1:] = ["the", words[-1]]
        sides.append(" ".join(words))
    # "east of the agent and south of the agent" reads as "east and south of the agent"
    split = [side.partition(" of ") for side in sides]
    if len(sides) > 1 and all(of for _, of, _ in split) and len({rest for _, _, rest in split}) == 1:
        return f"{' and '.join(way for way, _, _ in split)} of {split[0][2]}"
    return " and ".join(sides)


def object_phrase(obj: str, state: State, library: TaskLibrary) -> str:
    """``room0`` -> "the red room", ``block0`` -> "the yellow star"; "the door west of the agent"
    when another door would read alike; the bare id if two objects still read alike."""
    plain = _plain_phrase(obj, state, library)
    same = [o for o in object_names(state) if o != obj and object_class(o) == object_class(obj)
            and _plain_phrase(o, state, library) == plain]
    if not same:
        return plain
    side = _spatial(obj, state, library)
    if side and all(_spatial(o, state, library) != side for o in same):
        return f"{plain} {side}"
    return f"{plain} {obj}"


def _filled(said: str, words: Sequence[str]) -> str:
    """A phrase/2 with places, ``{k}`` replaced by ``words[k - 1]`` (a place past them is left as written)."""
    return _PLACE.sub(lambda m: words[int(m.group(1)) - 1] if 0 < int(m.group(1)) <= len(words) else m.group(0),
                      said)


def _atom_phrase(atom: Atom, state: State, library: TaskLibrary) -> str:
    said = library.phrases.get(atom.predicate)
    if said is not None and _PLACE.search(said):  # the library says how the atom reads (phrase/2)
        return _filled(said, [object_phrase(a, state, library) for a in atom.args])
    words = _camel_words(atom.predicate)
    out, used = [], 0
    for word in words:
        if used < len(atom.args) and word == object_class(atom.args[used]):
            out.append(object_phrase(atom.args[used], state, library))
            used += 1
        else:
            out.append(word)
    if used < len(atom.args):  # a predicate that does not spell its classes: say it with phrases as arguments
        return f"{atom.predicate}({', '.join(object_phrase(a, state, library) for a in atom.args)})"
    return " ".join(out)


def goal_phrase(goal: Sequence[Atom], state: State, library: TaskLibrary) -> str:
    """``toyInRoom(block0, room0)`` -> "the yellow star in the red room"; atoms joined by "and"."""
    return " and ".join(_atom_phrase(a, state, library) for a in goal)


def labelled_goal(goal: Sequence[Atom], state: State, library: TaskLibrary, names: dict[str, str] | None = None) -> str:
    """Words, then the ids: "the yellow star in the red room — toyInRoom(block0, room0)" (``names``: the
    state file's names of the layout's objects, ``corpus.file_names``, in the words' ids too)."""
    return renamed_words(f"{goal_phrase(goal, state, library)} {DASH} {format_goal(tuple(goal))}", names)


def choice_list(phrases: Sequence[str]) -> str:
    """"a", "a or b", "a, b or c"."""
    phrases = list(phrases)
    if len(phrases) <= 1:
        return "".join(phrases)
    return ", ".join(phrases[:-1]) + " or " + phrases[-1]


def _a(noun: str) -> str:
    return ("an " if noun[:1] in "aeiou" else "a ") + noun


def _pf_meaning(d: PFDeclaration, classes: Sequence[str], said: str | None = None) -> str:
    """``roomIsRed`` -> "a room's colour is red"; ``agentInRoom`` -> "an agent in a room";
    ``doorWestOfAgent`` -> "a door west of the agent". Where the library says how the PF reads (``said``,
    its phrase/2), that is used: "{1} in a corner of {2}" -> "an agent in a corner of a room"; "large" for a
    PF of one toy -> "a large toy" (a palette may store a size as a colour: the phrase says what it is), and
    a phrase of several words after the noun, as English puts them: "a toy east of where you stand"."""
    if said is not None:
        if _PLACE.search(said):
            return _filled(said, [_a(c) for c in d.signature])
        if len(d.signature) == 1:
            return f"{_a(d.signature[0])} {said}" if len(said.split()) > 1 else _a(f"{said} {d.signature[0]}")
    value = _value(d.term)
    if value is not None and len(d.signature) == 1:
        # A member of a family declared over values (roomIs(C)): the PF class names what the value is of.
        return f"{_a(d.signature[0])}'s {d.pf_class} is {value}"
    out, used = [], 0
    for word in _camel_words(d.name):
        if used < len(d.signature) and word == d.signature[used]:
            out.append(_a(word))
            used += 1
        else:  # a class the name spells but the PF does not take (the agent of doorWestOfAgent): the one there is
            out.append(f"the {word}" if word in classes else word)
    return " ".join(out) if used == len(d.signature) else str(d)


def _task_meaning(task: LiftedTask, phrases: Mapping[str, str]) -> str:
    """``agentToRoom`` -> "a task ending with agent A in room R"; variables named as the task declares them
    (a task of two rooms has two variables, which may be bound to one room). A goal PF the library says
    how to read (its phrase/2 with places, "{1} north of {2}") is read so: "agent A north of toy T"."""
    cls = {v.name: v.cls for v in task.variables}
    atoms = []
    for predicate, args in task.goal:
        said = phrases.get(predicate)
        if said is not None and _PLACE.search(said):
            atoms.append(_filled(said, [f"{cls.get(a, '')} {a}".strip() for a in args]))
            continue
        out, used = [], 0
        for word in _camel_words(predicate):
            if used < len(args) and word == cls.get(args[used]):
                out.append(f"{word} {args[used]}")
                used += 1
            else:
                out.append(word)
        atoms.append(" ".join(out) if used == len(args) else f"{predicate}({', '.join(args)})")
    where = [f"{v} is {_value(term) or term}" for v, term in task.restrictions]
    return "a task ending with " + " and ".join(atoms) + (f", where {' and '.join(where)}" if where else "")


def token_meanings(tokens: Iterable[str], schemas: Iterable[Domain],
                   phrases: Mapping[str, str] | None = None) -> dict[str, str]:
    """What each of ``tokens`` (the model's semantic tokens, as ``Learner.lexicon`` names them) means,
    read from the domain's schemas: ``{"roomIsRed": "a room's colour is red", "CLASS:room": "names a
    room", ...}``, or from ``phrases`` (a library's phrase/2, ``TaskLibrary.phrases``) where it says how a
    PF reads. A token no schema declares is left out rather than guessed at."""
    phrases = phrases or {}
    pfs: dict[str, PFDeclaration] = {}
    tasks: dict[str, LiftedTask] = {}
    classes: list[str] = []
    for schema in schemas:
        pfs.update(schema.pfs)
        tasks.update((t.name, t) for t in schema.tasks)
        classes.extend(c for c in schema.classes if c not in classes)
    known = {NULL: "no meaning in the domain (a word such as \"the\")"}
    known.update((class_token(c), f"names {_a(c)}") for c in classes)
    out = {}
    for token in dict.fromkeys(tokens):
        if token in known:
            out[token] = known[token]
        elif token in tasks:
            out[token] = _task_meaning(tasks[token], phrases)
        elif token in pfs:
            out[token] = _pf_meaning(pfs[token], classes, phrases.get(token))
    return out
