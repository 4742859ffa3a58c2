"""Confidence in a reading of a command, and how well it is calibrated.

The confidence of a reading is the posterior probability of the goal it acts
on, where goals that hold in exactly the same states of the layout count as
one (two names for one outcome are not a doubt). The margin is that
probability less the probability of the next goal that differs in the world.

Calibration is measured the usual way on held-out predictions (pairs of a
confidence and whether acting on it was correct): expected calibration error
over equal-width bins, the risk-coverage curve (accuracy on the commands
acted on when abstaining from the least confident first) and the area under
the ROC curve of confidence as a detector of correct readings.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from groundlang.inference.end_states import distances
from groundlang.logic.atoms import Atom
from groundlang.model.features import atoms_hold, atoms_hold_along
from groundlang.model.pf_tables import library_pf_tables
from groundlang.model.statespace import StateSpace

__all__ = [
    "GoalGroup", "group_goals", "expected_calibration_error", "risk_coverage", "accuracy_at_coverage",
    "auroc", "reliability", "calibration_report", "format_calibration", "choose_threshold", "unachievable_goals",
    "GoalMasks", "given_achievable", "out_of_reach",
]

# Goals below this probability are not compared by their masks: they cannot change the
# confidence or the margin by more than this each.
NEGLIGIBLE = 1e-6


@dataclass(frozen=True)
class GoalGroup:
    """Goals that hold in the same states of a layout, and their total posterior probability."""

    goals: tuple[tuple[Atom, ...], ...]  # most probable first; goals[0] is the one acted on
    probability: float

    @property
    def goal(self) -> tuple[Atom, ...]:
        return self.goals[0]


TIE = 1e-5  # posterior masses closer than this are float32 noise of one value


def most_probable_first(items: Sequence, probability) -> list:
    """``items`` most probable first; masses within float32 noise of each other (1e-5) count as tied
    and keep their given order, so equal readings ("go to the purple room": three rooms at 1/3) are
    offered in the layout's order whatever the rounding of the sums that made them."""
    ranked = sorted(range(len(items)), key=lambda k: -probability(items[k]))
    runs, run = [], []
    for k in ranked:
        if run and probability(items[run[-1]]) - probability(items[k]) > TIE:
            runs.append(run)
            run = []
        run.append(k)
    runs.append(run)
    return [items[k] for run in runs for k in sorted(run)]


class GoalMasks:
    """Where goals hold over the states of ``space``: each atom's column is computed once, for all the
    atoms asked at a time in one pass, and a goal (a conjunction) is the AND of its atoms' columns, so
    the goals of one posterior share the work whoever asks (:func:`unachievable_goals`, :func:`group_goals`)."""

    def __init__(self, space: StateSpace, library=None):
        self.space = space
        self.tables = library_pf_tables(space.layout, library)
        self._columns: dict[Atom, np.ndarray] = {}

    def prepare(self, goals: Iterable[tuple[Atom, ...]]) -> None:
        missing = sorted({atom for goal in goals for atom in goal} - self._columns.keys())
        if missing:
            holds = atoms_hold_along(self.space.layout, self.space.positions, missing, self.tables)
            self._columns.update(zip(missing, holds.T))

    def mask(self, goal: tuple[Atom, ...]) -> np.ndarray:
        """``[S]`` bool: the states where every atom of ``goal`` holds (as ``features.goal_mask``)."""
        self.prepare([goal])
        return np.logical_and.reduce([self._columns[atom] for atom in goal])


def _outcome_key(goal, masks: GoalMasks) -> bytes:
    return hashlib.sha1(np.packbits(masks.mask(goal)).tobytes()).digest()


def _asked(goal: tuple[Atom, ...], masks: GoalMasks, dist: np.ndarray | None) -> tuple[Atom, ...]:
    """What ``goal`` asks beyond what already holds: without its parts that hold at the start when the
    nearest states where the rest holds keep them too (a plan for the rest need not break them, so
    "the bag stays in the red room and the agent goes to the blue room" is "go to the blue room")."""
    if dist is None or len(goal) < 2:
        return goal
    held = [a for a in goal if masks.mask((a,))[0]]
    rest = tuple(a for a in goal if a not in held)
    if not held or not rest:
        return goal
    reach = dist >= 0

    def nearest(mask: np.ndarray) -> int | None:
        hits = dist[mask & reach]
        return int(hits.min()) if hits.size else None

    whole, part = nearest(masks.mask(goal)), nearest(masks.mask(rest))
    return rest if whole is not None and whole == part else goal


def unachievable_goals(goals: Sequence[tuple[Atom, ...]], space: StateSpace, library=None,
                       masks: GoalMasks | None = None) -> set[tuple[Atom, ...]]:
    """The ``goals`` that hold in no state of ``space``, when ``space`` holds every state reachable from
    its start (an exact space enumerated from it); none otherwise (a relevance abstraction or a sample
    of placements cannot say a goal is out of reach). ``masks``: a :class:`GoalMasks` of ``space`` to share."""
    from groundlang.model.relevance import AbstractStateSpace

    if getattr(space, "level_sizes", None) is None or isinstance(space, AbstractStateSpace):
        return set()
    masks = masks or GoalMasks(space, library)
    goals = list(goals)
    masks.prepare(goals)
    return {goal for goal in goals if not masks.mask(goal).any()}


def out_of_reach(probabilities: np.ndarray, goals: Sequence[tuple[Atom, ...]],
                 out: set[tuple[Atom, ...]]) -> tuple[float, tuple[Atom, ...] | None]:
    """How much of ``probabilities`` (of readings whose goals are ``goals``) is on the goals ``out`` (those
    :func:`unachievable_goals` found), and the most probable of them (None where there is none)."""
    mass: dict[tuple[Atom, ...], float] = {}
    for goal, p in zip(goals, probabilities):
        if goal in out:
            mass[goal] = mass.get(goal, 0.0) + float(p)
    if not mass:
        return 0.0, None
    # at most 1: float32 masses summed may pass it by a rounding (1.0000001 where every goal is out of reach)
    return min(1.0, float(sum(mass.values()))), most_probable_first(list(mass.items()), lambda kv: kv[1])[0][0]


def given_achievable(probabilities: np.ndarray, goals: Sequence[tuple[Atom, ...]], masks: GoalMasks,
                     out: set[tuple[Atom, ...]] | None = None) -> np.ndarray:
    """``probabilities`` (of readings whose goals are ``goals``, one each) given that the goal can be
    reached in ``masks``' space: a command asks for what can be done, so a goal that holds in no
    reachable state (a chair against the west wall cannot be stood left of) gets none and the others
    share its mass in proportion. Unchanged where no goal is ruled out, or every goal is."""
    if out is None:  # ``out``: the unachievable goals, where the caller found them already
        out = unachievable_goals(set(goals), masks.space, masks=masks)
    keep = np.array([goal not in out for goal in goals], dtype=bool)
    total = float(probabilities[keep].sum()) if out else 0.0
    return np.where(keep, probabilities, 0.0) / total if total > 0 else probabilities


def group_goals(goals: Sequence[tuple[tuple[Atom, ...], float]], space: StateSpace,
                library=None, masks: GoalMasks | None = None) -> list[GoalGroup]:
    """Merge goals (most probable first, as :meth:`Posterior.goals` gives them) whose goal masks
    over ``space`` are equal, a conjunction counted as its rest where its parts that hold at the start
    need not be broken (:func:`_asked`); returns the groups, most probable first (ties: the first goal's order).
    ``library``: the TaskLibrary whose PF rules say what the goals mean (default: the package's).
    ``masks``: a :class:`GoalMasks` of ``space`` to share."""
    masks = masks or GoalMasks(space, library)
    masks.prepare(goal for goal, p in goals if p >= NEGLIGIBLE)
    # From the initial state of an enumerated space (not a sample of placements): how far each state is.
    dist = distances(space) if getattr(space, "level_sizes", None) is not None else None
    by_mask: dict[bytes, list] = {}
    order: list[bytes] = []
    for k, (goal, p) in enumerate(goals):
        if p < NEGLIGIBLE:
            key = f"#{k}".encode()  # kept apart: comparing it could not matter
        else:
            key = _outcome_key(_asked(goal, masks, dist), masks)
        if key not in by_mask:
            by_mask[key] = [[], 0.0]
            order.append(key)
        by_mask[key][0].append(goal)
        by_mask[key][1] += p
    groups = [GoalGroup(tuple(by_mask[k][0]), by_mask[k][1]) for k in order]
    return most_probable_first(groups, lambda g: g.probability)


# ---------------------------------------------------------------- calibration measures

def _arrays(confidence: Sequence[float], correct: Sequence[bool]) -> tuple[np.ndarray, np.ndarray]:
    c = np.asarray(confidence, dtype=float)
    y = np.asarray(correct, dtype=bool)
    if c.shape != y.shape or c.ndim != 1:
        raise ValueError(f"confidence {c.shape} and correct {y.shape} must be two lists of one length")
    return c, y


def reliability(confidence: Sequence[float], correct: Sequence[bool], bins: int = 10) -> list[dict]:
    """Equal-width bins of confidence: each with its count, mean confidence and accuracy
    (the reliability diagram's points; empty bins left out). The last bin includes 1.0."""
    c, y = _arrays(confidence, correct)
    index = np.minimum((c * bins).astype(int), bins - 1)
    rows = []
    for b in range(bins):
        inside = index == b
        if inside.any():
            rows.append({"low": b / bins, "high": (b + 1) / bins, "n": int(inside.sum()),
                         "confidence": float(c[inside].mean()), "accuracy": float(y[inside].mean())})
    return rows


def expected_calibration_error(confidence: Sequence[float], correct: Sequence[bool], bins: int = 10) -> float:
    """Mean over commands of |accuracy - confidence| of their bin (equal-width bins)."""
    c, _ = _arrays(confidence, correct)
    if not len(c):
        return 0.0
    return sum(r["n"] * abs(r["accuracy"] - r["confidence"]) for r in reliability(confidence, correct, bins)) / len(c)


def risk_coverage(confidence: Sequence[float], correct: Sequence[bool]) -> list[tuple[float, float]]:
    """(coverage, accuracy on the commands acted on) as the least confident are abstained from, one
    at a time; commands of equal confidence are dropped together (a threshold cannot split them)."""
    c, y = _arrays(confidence, correct)
    order = np.argsort(-c, kind="stable")
    c, y = c[order], y[order]
    points = []
    for k in range(len(c), 0, -1):
        if k < len(c) and c[k] == c[k - 1]:
            continue  # not a threshold: the k-th and the next have the same confidence
        points.append((k / len(c), float(y[:k].mean())))
    return points


def accuracy_at_coverage(confidence: Sequence[float], correct: Sequence[bool], coverage: float) -> tuple[float, float]:
    """(accuracy, coverage actually reached) acting on at least ``coverage`` of the commands,
    the most confident first: the smallest covering threshold (ties are kept together)."""
    points = [p for p in risk_coverage(confidence, correct) if p[0] >= coverage - 1e-12]
    if not points:
        return (math.nan, 0.0)
    reached, accuracy = min(points)
    return accuracy, reached


def auroc(confidence: Sequence[float], correct: Sequence[bool]) -> float:
    """Probability that a correct reading is more confident than a wrong one (ties count half);
    nan when all are correct or all wrong."""
    c, y = _arrays(confidence, correct)
    pos, neg = c[y], c[~y]
    if not len(pos) or not len(neg):
        return math.nan
    greater = (pos[:, None] > neg[None, :]).sum()
    ties = (pos[:, None] == neg[None, :]).sum()
    return float((greater + 0.5 * ties) / (len(pos) * len(neg)))


def choose_threshold(confidence: Sequence[float], correct: Sequence[bool], target: float) -> float:
    """The lowest confidence threshold whose commands at or above it are at least ``target``
    accurate (the widest coverage reaching it); 1.0 when none does."""
    c, y = _arrays(confidence, correct)
    best = 1.0
    for threshold in sorted(set(c.tolist()), reverse=True):
        if y[c >= threshold].mean() >= target:
            best = threshold
    return float(best)


def calibration_report(confidence: Sequence[float], correct: Sequence[bool],
                       coverages: Sequence[float] = (0.85, 0.9, 0.95), threshold: float | None = None) -> dict:
    """What ``evaluate`` prints and writes: ECE, AUROC, accuracy at the given coverages, the
    reliability bins and, with ``threshold``, what acting only at or above it does."""
    c, y = _arrays(confidence, correct)
    report = {
        "n": int(len(c)),
        "ece": expected_calibration_error(c, y),
        "auroc": auroc(c, y),
        "mean_confidence": float(c.mean()) if len(c) else math.nan,
        "at_coverage": [],
        "reliability": reliability(c, y),
        "risk_coverage": risk_coverage(c, y),
    }
    for wanted in coverages:
        accuracy, reached = accuracy_at_coverage(c, y, wanted)
        report["at_coverage"].append({"coverage": wanted, "reached": reached, "accuracy": accuracy})
    if threshold is not None:
        acted = c >= threshold
        report["threshold"] = {"min_confidence": threshold, "acted": int(acted.sum()),
                               "coverage": float(acted.mean()) if len(c) else math.nan,
                               "accuracy": float(y[acted].mean()) if acted.any() else math.nan}
    return report


def format_calibration(report: dict, title: str = "confidence", unit: str = "commands") -> str:
    """A few lines of :func:`calibration_report` for a person: ECE, AUROC, accuracy at coverages
    (``unit``: what the report counts)."""
    auroc = report["auroc"]
    separation = ("- (every reading right, or every one wrong)" if math.isnan(auroc) else f"{auroc:.3f}")
    counted = unit.removesuffix("s") if report["n"] == 1 else unit
    lines = [f"{title} ({report['n']} {counted}): expected calibration error {report['ece']:.3f}, "
             f"AUROC for correctness {separation}, mean confidence {report['mean_confidence']:.3f}"]
    for row in report["at_coverage"]:
        lines.append(f"  acting on the {row['reached']:.1%} most confident (target {row['coverage']:.0%}): "
                     f"accuracy {row['accuracy']:.2%}")
    if "threshold" in report:
        t = report["threshold"]
        accuracy = f"accuracy {t['accuracy']:.2%}" if t["acted"] else "none acted on"
        lines.append(f"  acting at confidence >= {t['min_confidence']:g} (--min-confidence): "
                     f"{t['acted']} of {report['n']} ({t['coverage']:.1%}), {accuracy}")
    return "\n".join(lines)


def goals_held_at_start(held) -> set[tuple[Atom, ...]]:
    """The goals of ``held`` (a posterior with goals that hold at the start offered, ``Learner.posterior(...,
    held=True)``) that hold there as a whole: their groundings found every atom holding."""
    return {i.goal for i in held.interpretations if i.task.holds_wholly}


def held_goals_success(held, success: float, end, library) -> float:
    """The confidence of following (``success``: the share of what was meant its end satisfies, goals that hold
    at the start set aside) counting what the words say of those goals: ``held`` is the command's posterior
    with them offered and conditioned on nothing (``Learner.posterior(..., held=True)``). Following sets them
    aside, since they ask nothing, so their share counts for the end only where such a goal still holds there::

        (1 - share) * success + sum_{g holds at the start} P(g | words) [g holds at the end]

    ("go to the blue room" said in it, 0.95 the blue room: walking to the only other room is not 0.99 sure).
    Counted only where the words' most probable goal is one of them: where they most probably name another
    goal, the share left on what holds is the reading's spread, not what was named."""
    wholly = goals_held_at_start(held)
    at_start = [(goal, p) for goal, p in held.goals() if goal in wholly]
    if not at_start or held.best_goal not in wholly:
        return success
    share = sum(p for _, p in at_start)
    tables = library_pf_tables(end.layout, library)
    kept = sum(p for goal, p in at_start if atoms_hold(end, goal, tables).all())
    return min(1.0, max(0.0, (1.0 - share) * success + kept))
