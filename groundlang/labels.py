"""Gold labels (``prefix,goal`` CSV) and the simple per-state check of a goal.

Labels are for evaluation only: training never sees them. A goal is a
conjunction of ground atoms (``agentInRoom(agent0, room1) blockInRoom(block0,
room2)``), all of which must hold. :func:`goal_holds` decides one state at a
time from the objects' coordinates; the tensorised propositional functions
over whole state spaces live in ``groundlang.logic``/``groundlang.model``.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field
from pathlib import Path

from groundlang.corpus import Corpus, CorpusError, Instance, file_prefix
from groundlang.logic.atoms import Atom, AtomError, attribute_pf, parse_goal
from groundlang.model.storage import read_limited
from groundlang.model.world import State

__all__ = [
    "LabelError",
    "Labels",
    "LabelCoverage",
    "read_labels",
    "label_for",
    "goal_holds",
    "check_goal_objects",
    "label_coverage",
]


# The crowd corpus's labels take 10 KB; this bounds what a wrong path (a log, /dev/zero) can cost.
MAX_LABELS_BYTES = 16 * 2**20


class LabelError(CorpusError):
    """A labels file or a goal that cannot be used; the message says where and why."""


class Labels(dict):
    """``prefix -> goal atoms``, remembering the CSV it came from (for messages)."""

    def __init__(self, path: Path, items=()):
        super().__init__(items)
        self.path = Path(path)


def read_labels(csv_path: str | Path) -> Labels:
    """Read a labels CSV with header ``prefix,goal``; goals parse with ``parse_goal``.

    Raises LabelError naming the file and line of a bad header, row, goal or duplicate prefix.
    """
    path = Path(csv_path)
    data = read_limited(path, MAX_LABELS_BYTES, "a labels CSV")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise LabelError(f"{path}, line {line}: not UTF-8 text; expected a CSV file") from None
    rows = csv.reader(io.StringIO(text), strict=True)  # strict: a quote left open at the end is an error
    end = 0  # the line the last row read ended on
    try:
        header = next(rows, None)
        if header is None:
            raise LabelError(f"{path}: the file is empty; expected a header line prefix,goal")
        if [h.strip() for h in header] != ["prefix", "goal"]:
            raise LabelError(f"{path}, line 1: header is {','.join(header)!r}; expected prefix,goal")
        labels = Labels(path)
        end = rows.line_num
        for row in rows:
            line, end = end + 1, rows.line_num  # where the row starts, where it ends
            if end > line and any("\n" in cell for cell in row):
                raise LabelError(f"{path}, line {line}: a quote opened on this line closes only on line {end}; "
                                 "expected the closing quote on the same line")
            if not any(cell.strip() for cell in row):
                continue
            if len(row) != 2:
                raise LabelError(
                    f"{path}, line {line}: {len(row)} fields; expected 2 (prefix,\"goal atoms\")"
                )
            prefix = row[0].strip()
            if not prefix:
                raise LabelError(f"{path}, line {line}: empty prefix; expected a file-name prefix like star2red_")
            if prefix in labels:
                raise LabelError(f"{path}, line {line}: prefix {prefix!r} is labelled twice")
            try:
                labels[prefix] = parse_goal(row[1])
            except AtomError as exc:
                raise LabelError(f"{path}, line {line}: {exc}") from None
    except csv.Error as exc:
        start = end + 1  # the row that failed began here
        quote = "end of data" in str(exc) or "expected after" in str(exc)
        hint = f"; a quote opened on line {start} is not closed there" if quote else ""
        raise LabelError(f"{path}, line {start}: not valid CSV ({exc}, reading line {rows.line_num}){hint}") from None
    return labels


# predicate -> (classes of its arguments); position PFs of the paper plus the corpus's spellings.
_POSITION = {
    "agentInRoom": ("agent", "room"),
    "toyInRoom": ("toy", "room"),
    "agentInDoor": ("agent", "door"),
    "toyInDoor": ("toy", "door"),
    "agentTouchingToy": ("agent", "toy"),
}


def _article(word: str) -> str:
    return "an" if word[:1] in "aeiou" else "a"


def _attribute_predicates(state: State) -> dict[str, tuple[str, str, str]]:
    """``roomIsGreen -> ('room', 'colour', 'green')`` etc. for the state's palette."""
    pal = state.layout.palette
    table: dict[str, tuple[str, str, str]] = {}
    for colour in pal.colours:
        table[attribute_pf("roomIs", colour)] = ("room", "colour", colour)
        for cls in ("toy", "block"):
            table[attribute_pf(f"{cls}Is", colour)] = ("toy", "colour", colour)
    for shape in pal.shapes:
        for cls in ("toy", "block"):
            table[attribute_pf(f"{cls}Is", shape)] = ("toy", "shape", shape)
    return table


def _objects(state: State) -> dict[str, tuple[str, object]]:
    """Object name -> (class, object) for the names a goal may use."""
    objs: dict[str, tuple[str, object]] = {"agent0": ("agent", state.agent)}
    objs.update({n: ("room", r) for n, r in zip(state.layout.room_names, state.layout.rooms)})
    objs.update({n: ("door", d) for n, d in zip(state.layout.door_names, state.layout.doors)})
    objs.update({n: ("toy", t) for n, t in zip(state.layout.toy_names, state.toys)})
    return objs


def _resolve(atom: Atom, state: State, context: str) -> tuple[str, list]:
    """Check an atom's predicate, arity and objects against a state; return (kind, objects)."""
    objs = _objects(state)
    attributes = _attribute_predicates(state)
    if atom.predicate in _POSITION:
        classes = _POSITION[atom.predicate]
    elif atom.predicate in attributes:
        classes = (attributes[atom.predicate][0],)
    else:
        raise LabelError(
            f"{context}: unknown predicate {atom.predicate!r} in {atom}; expected a position PF "
            f"({', '.join(_POSITION)}) or a colour/shape PF like roomIsGreen, toyIsStar"
        )
    if len(atom.args) != len(classes):
        raise LabelError(f"{context}: {atom} has {len(atom.args)} arguments; expected {len(classes)} ({', '.join(classes)})")
    found = []
    for name, cls in zip(atom.args, classes):
        if name not in objs:
            have = ", ".join(objs)
            raise LabelError(f"{context}: {atom} names {name}, which does not exist (objects: {have})")
        if objs[name][0] != cls:
            raise LabelError(f"{context}: {atom}: {name} is a {objs[name][0]}; expected {_article(cls)} {cls} there")
        found.append(objs[name][1])
    return atom.predicate, found


def check_goal_objects(goal: tuple[Atom, ...], state: State, context: str = "goal") -> None:
    """Raise LabelError when a goal uses an unknown predicate or an object the state lacks."""
    for atom in goal:
        _resolve(atom, state, context)


def _holds(atom: Atom, state: State) -> bool:
    pred, objs = _resolve(atom, state, "goal")
    if pred in ("agentInRoom", "toyInRoom", "agentInDoor", "toyInDoor"):
        return bool(objs[1].contains(objs[0].x, objs[0].y))
    if pred == "agentTouchingToy":
        # Touching: the toy is on one of the agent's four neighbouring cells.
        return abs(objs[0].x - objs[1].x) + abs(objs[0].y - objs[1].y) == 1
    _, attribute, value = _attribute_predicates(state)[pred]
    return getattr(objs[0], attribute) == value


def goal_holds(goal: tuple[Atom, ...] | list[Atom], state: State) -> bool:
    """True when every atom of the goal holds in ``state``.

    Position PFs: agentInRoom/toyInRoom (blockInRoom), agentInDoor/toyInDoor,
    agentTouchingToy; colour/shape PFs: roomIsGreen(room0), toyIsYellow(block0),
    toyIsStar(block0), ... Raises LabelError for unknown predicates or objects.
    """
    return all(_holds(atom, state) for atom in goal)


def label_for(instance: Instance, labels: Labels | dict) -> tuple[Atom, ...] | None:
    """The gold goal of an instance (by file prefix), or None when it is unlabelled.

    Raises LabelError when the goal names an object the instance does not have.
    """
    goal = labels.get(instance.prefix)
    if goal is not None:
        source = getattr(labels, "path", "labels")
        check_goal_objects(goal, instance.initial_state, f"{source}: goal of {instance.prefix!r} for {instance.path}")
    return goal


@dataclass
class LabelCoverage:
    """How many instances have a label and whether each label's goal holds at the end."""

    total: int
    labelled: int
    holding: int
    unlabelled: list[Instance] = field(default_factory=list)
    failing: list[tuple[Instance, tuple[Atom, ...]]] = field(default_factory=list)


def label_coverage(corpus: Corpus, labels: Labels | dict) -> LabelCoverage:
    """Match labels to a corpus and check each goal in the instance's final state.

    Raises LabelError when a labelled prefix has no files in the corpus or a goal names a missing object.
    """
    prefixes = {inst.prefix for inst in corpus.instances} | {file_prefix(p.stem) for p, _ in corpus.skipped}
    source = getattr(labels, "path", "labels")
    missing = sorted(p for p in labels if p not in prefixes)
    if missing:
        shown = ", ".join(missing[:5]) + (f", ... ({len(missing)} in all)" if len(missing) > 5 else "")
        raise LabelError(
            f"{source}: prefixes {shown} name no files in {corpus.directory}; "
            "expected every labelled prefix to have corpus files"
        )
    cov = LabelCoverage(total=len(corpus.instances), labelled=0, holding=0)
    for inst in corpus.instances:
        goal = label_for(inst, labels)
        if goal is None:
            cov.unlabelled.append(inst)
            continue
        cov.labelled += 1
        if goal_holds(goal, inst.final_state):
            cov.holding += 1
        else:
            cov.failing.append((inst, goal))
    return cov
