"""Evaluation protocols of RSS 2015: leave-one-out, train-set, and novel environments.

A prediction is correct when executing the inferred task from the initial
state reaches the gold goal. Labels are used only to score, never to train.

Leave-one-out trains one model per held-out instance. Behaviour
likelihoods are computed once for the whole corpus (they do not depend on
the language model) and encoded once; each fold refits on its 239 others.
By default a fold's fit is warm-started from the model trained on all
instances and runs EM on the fold's own objective until the relative change
falls below 1e-7. EM climbs to the optimum nearest its start, so a warm
start can keep a fold in the basin the full data chose: a bias toward the
full model that ``warm_start=False`` (CLI ``--cold-folds``) removes, fitting
every fold from scratch like the full model, at about ten times the cost.
"""

from __future__ import annotations

import logging
import math
import time
from collections import Counter, defaultdict
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field

from groundlang.confidence import calibration_report, format_calibration
from groundlang.corpus import Corpus
from groundlang.folds import run_folds
from groundlang.goal_translation import GoalHoldsAtStart, NovelEnvironmentError, describe_goal, translate_goal
from groundlang.labels import label_for
from groundlang.learner import DEFAULT_MIN_CONFIDENCE, Learner
from groundlang.learner_state import check_count, check_threshold
from groundlang.model.language_models import get_language_model
from groundlang.model.world import State

__all__ = [
    "EvaluationResult",
    "NovelEnvironmentError",
    "wilson_interval",
    "translate_goal",
    "describe_goal",
    "evaluate",
]

log = logging.getLogger(__name__)


def wilson_interval(correct: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95% Wilson score interval for a binomial proportion."""
    if n == 0:
        return (0.0, 1.0)
    p = correct / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return (max(0.0, centre - half), min(1.0, centre + half))


@dataclass
class EvaluationResult:
    protocol: str
    language_model: str
    accuracy: float
    n: int
    correct: int
    ci_low: float
    ci_high: float
    seconds: float
    per_task: dict
    confusion: dict
    skipped: int = 0
    slowest_step: dict = field(default_factory=dict)
    language_model_settings: dict = field(default_factory=dict)  # the settings given (the rest are defaults)
    novel_accuracy: float | None = None
    novel_n: int = 0
    novel_correct: int = 0
    failed_folds: list = field(default_factory=list)
    records: list = field(default_factory=list)
    # confidence against correctness (groundlang.confidence.calibration_report), held-out commands
    # in their own layouts; "novel" the same for the novel layouts
    calibration: dict = field(default_factory=dict)
    novel_calibration: dict = field(default_factory=dict)
    # layout-free goal -> the same goal in words (from the first command with it)
    goal_words: dict = field(default_factory=dict)
    # number of atoms of the gold goal -> n, correct, novel_n, novel_correct (one goal against conjunctions)
    per_goal_size: dict = field(default_factory=dict)
    # novel executions whose label's goal, carried over, already holds at the start (nothing to ask there)
    novel_not_scored: int = 0
    # novel executions in a layout the model could not read or plan in (too many objects, too large): counted wrong
    novel_unfollowed: list = field(default_factory=list)

    def to_json(self) -> dict:
        return asdict(self)

    def summary(self) -> str:
        lines = [
            f"protocol {self.protocol}, language model {self.language_model}"
            + "".join(f", {k}={v!r}" for k, v in self.language_model_settings.items()),
            f"accuracy {self.accuracy:.2%} ({self.correct}/{self.n}), 95% CI [{self.ci_low:.2%}, {self.ci_high:.2%}]",
        ]
        if self.novel_n:
            lines.append(f"novel environments: {self.novel_accuracy:.2%} ({self.novel_correct}/{self.novel_n})")
        if self.novel_unfollowed:
            lines.append(f"novel executions that could not be followed (counted wrong): {len(self.novel_unfollowed)}; "
                         f"first: {self.novel_unfollowed[0]}")
        if self.novel_not_scored:
            lines.append(f"novel executions not scored (the label's goal already holds at the start): "
                         f"{self.novel_not_scored}")
        if self.skipped:
            lines.append(f"skipped inconsistent demonstrations: {self.skipped}")
        lines.append("by size of the gold goal: " + "; ".join(
            f"{size} atom{'s' * (size > 1)} {row['correct']}/{row['n']}"
            + (f" (novel {row['novel_correct']}/{row['novel_n']})" if row["novel_n"] else "")
            for size, row in sorted(self.per_goal_size.items())))
        lines.append("per gold task:")
        for task, row in self.per_task.items():
            lines.append(f"  {task:<32} {row['accuracy']:.2%} ({row['correct']}/{row['n']})")
        lines.append("confusion (gold -> executed goal, in words and layout-free):")
        words = self.goal_words
        for gold, row in self.confusion.items():
            for pred, count in sorted(row.items(), key=lambda kv: -kv[1]):
                lines.append(f"  {count:>4}  {words.get(gold, gold)} -> {words.get(pred, pred)}"
                             f"    ({gold} -> {pred})")
        if self.calibration:
            lines.append(format_calibration(self.calibration, "confidence"))
        if self.novel_calibration:
            lines.append(format_calibration(self.novel_calibration, "confidence in novel environments",
                                            unit="executions"))
        if self.failed_folds:
            lines.append(f"failed folds: {len(self.failed_folds)}")
            for item in self.failed_folds[:5]:
                lines.append(f"  {item['instance']}: {item['error']}")
        for name, secs in self.slowest_step.items():
            lines.append(f"time in {name}: {secs:.2f} s")
        lines.append(f"wall time {self.seconds:.1f} s")
        return "\n".join(lines)


def _checked_inputs(corpus, labels, novel_states) -> list[tuple[str, State]]:
    """``novel_states`` as a list, after a TypeError naming ``evaluate``'s argument of the wrong type (each had
    failed deep inside with an AttributeError, or "cannot unpack non-iterable State object")."""
    if not isinstance(corpus, Corpus):
        raise TypeError(f"evaluate: corpus must be a Corpus (read_corpus), got {type(corpus).__name__}")
    if not isinstance(labels, Mapping):
        raise TypeError(f"evaluate: labels must map file prefixes to goals (read_labels), got {type(labels).__name__}")
    expected = "evaluate: novel_states must be (name, State) pairs, e.g. [('novel_a', state)]"
    if isinstance(novel_states, (str, bytes)) or not isinstance(novel_states, Iterable):
        raise TypeError(f"{expected}, got {type(novel_states).__name__}")
    pairs = list(novel_states)
    for pair in pairs:
        if not (isinstance(pair, (tuple, list)) and len(pair) == 2 and isinstance(pair[1], State)):
            raise TypeError(f"{expected}, got an item that is a {type(pair).__name__}"
                            + (f" of {len(pair)}" if isinstance(pair, (tuple, list)) else ""))
    return pairs


def evaluate(
    corpus: Corpus,
    labels,
    protocol: str = "loo",
    language_model: str = "parse",
    novel_states: list[tuple[str, State]] = (),
    workers: int = 1,
    ray_address: str | None = None,
    progress: bool = False,
    limit: int | None = None,
    learner_options: dict | None = None,
    train_indices: Sequence[int] | None = None,
    warm_start: bool = True,
    language_model_settings: dict | None = None,
    min_confidence: float = DEFAULT_MIN_CONFIDENCE,
) -> EvaluationResult:
    """Run ``loo`` or ``train`` on a corpus; ``limit`` scores only the first N held-out instances.

    ``language_model_settings``: keywords of the language model (``{"mention_phrases": "any"}``),
    see :func:`groundlang.model.language_models.get_language_model`; the result records them.

    ``min_confidence``: the threshold whose coverage and accuracy the calibration report gives
    (commands acted on at or above it); it changes no prediction.

    ``train_indices`` (default: all) trains one model on those instances only
    (learning curves): ``loo`` then scores the held-out remainder, each
    instance unseen in training (reported as protocol ``heldout``), and
    ``train`` scores the training instances.
    """
    novel_states = _checked_inputs(corpus, labels, novel_states)
    if limit is not None:  # -1 had scored all but the last, 0 all of them: silently, by slicing
        check_count("evaluate", "limit", limit)
    check_threshold("evaluate", "min_confidence", min_confidence)
    if min_confidence is None:
        raise ValueError("evaluate: min_confidence must be a number from 0 to 1, got None")
    if protocol not in ("loo", "train"):
        raise ValueError(f"unknown protocol {protocol!r}; expected loo or train")
    started = time.perf_counter()
    instances = list(corpus.instances)
    if len(instances) < 2:
        raise ValueError(f"{corpus.directory}: evaluation needs at least two instances, found {len(instances)}")
    # Labels may name the PFs of the library the learner is given, not only the package's.
    library = (learner_options or {}).get("library")
    golds = []
    for inst in instances:
        gold = label_for(inst, labels, library)
        if gold is None:
            raise ValueError(f"{inst.path}: no gold label for prefix {inst.prefix!r}")
        golds.append(gold)
    for name, state in novel_states:  # reject bad layouts before any work
        for inst, gold in zip(instances, golds):
            # Named by the layout and by the instance whose label it is: the label's goal carried over fails.
            try:
                translate_goal(gold, inst.initial_state, state,
                               f"{name} (the label of {inst.prefix!r}, {inst.path})", library)
            except GoalHoldsAtStart:  # that execution is not scored (counted); the layout serves the others
                pass

    training = list(range(len(instances)))
    if train_indices is not None:
        training = sorted(set(train_indices))
        if not training or training[0] < 0 or training[-1] >= len(instances):
            raise ValueError(f"{corpus.directory}: train_indices must be non-empty and within 0..{len(instances) - 1}")
        if protocol == "loo" and len(training) == len(instances):
            raise ValueError(f"{corpus.directory}: train_indices covers every instance; nothing is held out")

    timings = {}
    lm = get_language_model(language_model, **(language_model_settings or {}))
    learner = Learner(language_model=lm, **(learner_options or {}))
    t = time.perf_counter()
    observations = learner.observe([instances[k] for k in training], progress=progress)
    timings["behaviour likelihoods"] = time.perf_counter() - t
    t = time.perf_counter()
    learner.fit([instances[k] for k in training], observations=observations, progress=progress)
    timings["training on all instances"] = time.perf_counter() - t

    context = {
        "learner": learner,
        "instances": instances,
        "batch": lm.encode(observations, learner.vocab),
        "golds": golds,
        "globals": dict(learner.globals),
        "novel_states": list(novel_states),
        # One model trained on a subset scores every instance as it is: no per-fold refit.
        "protocol": protocol if train_indices is None else "train",
        "warm_start": warm_start,
    }
    if train_indices is not None and protocol == "loo":
        protocol = "heldout"
        indices = sorted(set(range(len(instances))) - set(training))[: limit or None]
    else:
        indices = training[: limit or None]
    t = time.perf_counter()
    records = run_folds(context, indices, workers, ray_address, progress)
    timings["folds" if context["protocol"] == "loo" else "following commands"] = time.perf_counter() - t

    failed = [r for r in records if "error" in r]
    scored = [r for r in records if "error" not in r]
    correct = sum(r["correct"] for r in scored)
    n = len(scored)
    per_task: dict = defaultdict(lambda: {"n": 0, "correct": 0})
    confusion: dict = defaultdict(Counter)
    for r in scored:
        per_task[r["gold_task"]]["n"] += 1
        per_task[r["gold_task"]]["correct"] += int(r["correct"])
        confusion[r["gold_task"]][r["predicted_task"]] += 1
    for row in per_task.values():
        row["accuracy"] = row["correct"] / row["n"]
    per_goal_size: dict = defaultdict(lambda: {"n": 0, "correct": 0, "novel_n": 0, "novel_correct": 0})
    for r in scored:
        row = per_goal_size[r["gold_size"]]
        row["n"] += 1
        row["correct"] += int(r["correct"])
        row["novel_n"] += sum("correct" in x for x in r["novel"])
        row["novel_correct"] += sum(x.get("correct", False) for x in r["novel"])
    novel_scored = [x for r in scored for x in r["novel"] if "correct" in x]  # the others: not scored
    novel = [x["correct"] for x in novel_scored]
    novel_not_scored = sum(len(r["novel"]) for r in scored) - len(novel_scored)
    goal_words: dict = {}
    for r in scored:
        goal_words.setdefault(r["gold_task"], r["gold_words"])
        goal_words.setdefault(r["predicted_task"], r["predicted_words"])
    calibration = calibration_report([r["confidence"] for r in scored], [r["correct"] for r in scored],
                                     threshold=min_confidence) if scored else {}
    # an execution that could not be followed had no confidence to calibrate (it is counted wrong above)
    followed = [x for x in novel_scored if "unfollowed" not in x]
    novel_calibration = calibration_report([x["confidence"] for x in followed], [x["correct"] for x in followed],
                                           threshold=min_confidence) if followed else {}
    low, high = wilson_interval(correct, n)
    if scored:
        slowest = max(scored, key=lambda r: r["seconds"])
        timings[f"slowest fold ({slowest['instance']})"] = slowest["seconds"]
    return EvaluationResult(
        protocol=protocol,
        language_model=language_model,
        language_model_settings=dict(language_model_settings or {}),
        accuracy=correct / n if n else 0.0,
        n=n,
        correct=correct,
        ci_low=low,
        ci_high=high,
        seconds=time.perf_counter() - started,
        per_task=dict(sorted(per_task.items())),
        confusion={k: dict(v) for k, v in sorted(confusion.items())},
        skipped=len(corpus.skipped),
        slowest_step=timings,
        novel_accuracy=(sum(novel) / len(novel)) if novel else None,
        novel_n=len(novel),
        novel_correct=sum(novel),
        failed_folds=failed,
        novel_unfollowed=[x["unfollowed"] for x in novel_scored if "unfollowed" in x],
        records=records,
        calibration=calibration,
        novel_calibration=novel_calibration,
        goal_words=goal_words,
        per_goal_size=dict(sorted(per_goal_size.items())),
        novel_not_scored=novel_not_scored,
    )
