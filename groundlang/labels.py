"""Gold labels (``prefix,goal`` CSV) and the simple per-state check of a goal.

Labels are for evaluation only: training never sees them. A goal is a
conjunction of ground atoms (``agentInRoom(agent0, room1) blockInRoom(block0,
room2)``), all of which must hold. :func:`goal_holds` decides one state at a
time with the PF tables planning uses (``groundlang.model.pf_tables``): what a
PF means is written once, in ASP.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field
from pathlib import Path

from groundlang.corpus import Corpus, CorpusError, Instance, file_prefix
from groundlang.logic.atoms import Atom, AtomError, parse_goal
from groundlang.logic.program import AspError
from groundlang.model.features import atoms_hold
from groundlang.model.pf_tables import library_pf_tables
from groundlang.logic.storage import as_path, read_limited
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
    "check_label_prefixes",
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
    path = as_path(csv_path, "read_labels: csv_path")
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


def _check_state_and_library(method: str, state, library) -> None:
    """TypeError naming ``method``'s argument for a state that is not a State or a library that is not a
    TaskLibrary (either had failed deep inside with an AttributeError)."""
    from groundlang.logic.tasks import TaskLibrary

    if not isinstance(state, State):
        raise TypeError(f"{method}: state must be a State (read_state_file, read_initial_state), "
                        f"got {type(state).__name__}")
    if library is not None and not isinstance(library, TaskLibrary):
        raise TypeError(f"{method}: library must be a TaskLibrary (TaskLibrary.load(path)) or None, got "
                        f"{type(library).__name__}")


def check_goal_objects(goal: tuple[Atom, ...], state: State, context: str = "goal", library=None) -> None:
    """Raise LabelError when a goal uses a predicate the domain does not declare (``logic/pfs.lp``, or
    ``library``'s own PF rules), the wrong number of arguments or an object the state lacks."""
    _check_state_and_library("check_goal_objects", state, library)
    tables = library_pf_tables(state.layout, library)
    for atom in goal:
        try:
            tables.check(atom)
        except AspError as exc:
            raise LabelError(f"{context}: {exc}") from None


def goal_holds(goal: tuple[Atom, ...] | list[Atom] | str, state: State, library=None) -> bool:
    """True when every atom of the goal holds in ``state``, as the PF rules of the domain (or of
    ``library``, a TaskLibrary with PF rules of its own) define it: the tables planning uses. A goal may
    be written as the labels CSV writes it, ``"agentInRoom(agent0, room1)"``.
    Raises LabelError for unknown predicates or objects, or a goal that is neither atoms nor their text;
    TypeError for a state or library of the wrong type."""
    _check_state_and_library("goal_holds", state, library)
    if isinstance(goal, str):
        try:
            goal = parse_goal(goal)
        except AtomError as exc:
            raise LabelError(f"goal {goal!r}: {exc}") from None
    elif not isinstance(goal, (tuple, list)) or not all(isinstance(a, Atom) for a in goal):
        raise LabelError(f"goal: expected Atoms or their text such as 'agentInRoom(agent0, room1)', got {goal!r:.60}")
    if not goal:
        return True
    tables = library_pf_tables(state.layout, library)
    try:
        return bool(atoms_hold(state, list(goal), tables).all())
    except AspError as exc:
        raise LabelError(f"goal: {exc}") from None


def label_for(instance: Instance, labels: Labels | dict, library=None) -> tuple[Atom, ...] | None:
    """The gold goal of an instance (by file prefix), or None when it is unlabelled.

    ``library``: a TaskLibrary whose own PF rules a goal may use (a user's ``agentAboveToy``).
    Raises LabelError when the goal names an object the instance does not have.
    """
    goal = labels.get(instance.prefix)
    if goal is not None:
        source = getattr(labels, "path", "labels")
        check_goal_objects(goal, instance.initial_state, f"{source}: goal of {instance.prefix!r} for {instance.path}",
                           library)
    return goal


@dataclass
class LabelCoverage:
    """How many instances have a label and whether each label's goal holds at the end."""

    total: int
    labelled: int
    holding: int
    unlabelled: list[Instance] = field(default_factory=list)
    failing: list[tuple[Instance, tuple[Atom, ...]]] = field(default_factory=list)


def check_label_prefixes(corpus: Corpus, labels: Labels | dict) -> None:
    """Raise LabelError (one line, at most five prefixes named) when a labelled prefix has no files in
    the corpus: labels of another corpus, or of another folder of it."""
    prefixes = {inst.prefix for inst in corpus.instances} | {file_prefix(p.stem) for p, _ in corpus.skipped}
    source = getattr(labels, "path", "labels")
    missing = sorted(p for p in labels if p not in prefixes)
    if missing:
        shown = ", ".join(missing[:5]) + (f", ... ({len(missing)} in all)" if len(missing) > 5 else "")
        raise LabelError(
            f"{source}: prefixes {shown} name no files in {corpus.directory}; "
            "expected every labelled prefix to have corpus files"
        )


def label_coverage(corpus: Corpus, labels: Labels | dict, library=None) -> LabelCoverage:
    """Match labels to a corpus and check each goal in the instance's final state (as ``library``'s PF
    rules define it, when given).

    Raises LabelError when a labelled prefix has no files in the corpus or a goal names a missing object.
    """
    check_label_prefixes(corpus, labels)
    cov = LabelCoverage(total=len(corpus.instances), labelled=0, holding=0)
    for inst in corpus.instances:
        goal = label_for(inst, labels, library)
        if goal is None:
            cov.unlabelled.append(inst)
            continue
        cov.labelled += 1
        if goal_holds(goal, inst.final_state, library):
            cov.holding += 1
        else:
            cov.failing.append((inst, goal))
    return cov
