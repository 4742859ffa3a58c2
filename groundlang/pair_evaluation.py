"""Evaluation on a corpus of (start, end) pairs with a test file (Williams et al. 2018).

Train on every usable pair of the training commands (``pair_corpus``), then follow every test command
from each of its start states, the others given as the states it was also given in (the language model's
``other_starts``: a task already holding in one of them is not what it asks). An execution is correct when its final state satisfies the task the
test command's pairs show (``pair_tasks.pair_task``: the relations that hold in all its end states and
not in all its start states, the data README's rule); a command is correct when all its executions
are. A test command whose pairs show no task cannot be scored and is counted apart, and so is an
execution from a start state that admits no task of the library (nothing to follow). A layout too large
to enumerate is followed in its relevance abstraction; one too large even for that is counted as
skipped (and wrong), never dropped silently, and so is one in a layout too large to tabulate (a command
none of whose layouts can be is counted wrong in each). Training skips pairs too large to enumerate or
tabulate (counted).
"""

from __future__ import annotations

import logging
import time
from collections import defaultdict
from dataclasses import asdict, dataclass, field

from groundlang.bdm import Command, format_bdm_state
from groundlang.bdm_check import is_corpus_library
from groundlang.confidence import calibration_report, format_calibration
from groundlang.evaluation import wilson_interval
from groundlang.learner import DEFAULT_MIN_CONFIDENCE, Learner
from groundlang.learner_state import check_threshold
from groundlang.logic.tasks import TaskLibrary
from groundlang.logic.atoms import Atom, format_goal
from groundlang.model.interpretations import NoTaskError
from groundlang.model.relevance import STATE_SOURCE, reading_states
from groundlang.model.statespace import StateSpaceError
from groundlang.pair_corpus import skipped_text, training_instances
from groundlang.model.pf_tables import TabulationError
from groundlang.pair_tasks import REACHABILITY_MAX_STATES, command_task, lifted_facts

__all__ = ["PairEvaluation", "evaluate_pairs", "calibration_of_rows", "failure_kind", "FAILURE_KINDS", "PUBLISHED_F1"]

log = logging.getLogger(__name__)

# Williams et al. 2018, Table II: F1 of validated parses on their held-out test split, pruned data,
# three pairs per command (0.75 with two pairs, 0.71 with one).
PUBLISHED_F1 = 0.82

# Why an execution failed, told from the goal acted on, what the pairs show and the final state alone
# (no word is read), so that the kinds are counted the same way on any corpus of pairs.
FAILURE_KINDS = {
    "skipped": "too large to follow, even in the relevance abstraction, or its layout too large to tabulate",
    "unreached": "the goal acted on was not reached",
    "more than the goal": "the goal was met; the pairs also show a relation it does not ask for",
    "another relation": "a relation the pairs do not show was acted on",
    "another object": "the relation the pairs show, met with another object than they show",
}


@dataclass
class PairEvaluation:
    """Figures of one ``evaluate --test`` run; ``executions`` has one row per (test command, pair)."""

    train_commands: int
    train_pairs: int
    train_skipped: dict
    test_commands: int
    scored_commands: int
    no_task_commands: int
    executions_n: int
    executions_correct: int
    commands_correct: int
    unseen_n: int
    unseen_correct: int
    skipped_executions: int
    per_task: dict
    failures: dict  # kind (FAILURE_KINDS) -> the relations left unmet ("agentInRoom+toyInRoom") -> executions
    seconds_training: float
    seconds_following: float
    demonstrations: str
    layouts: str
    no_task_executions: int = 0  # from a start state that admits no task: not scored
    executions: list[dict] = field(default_factory=list)
    # Confidence (the posterior probability of the goal acted on) against correctness
    # (groundlang.confidence.calibration_report): per execution, and per command with the least
    # confident of its executions (acting on a command means acting in every layout it comes with).
    calibration: dict = field(default_factory=dict)
    command_calibration: dict = field(default_factory=dict)
    # Whether the tasks scored are the corpus's own (the Williams library, ``is_corpus_library``): only then is
    # the published figure set beside the run's (a domain author's library scores other tasks).
    published: bool = True
    # The library the test pairs were judged with where it is not the learner's (``judge``): its files' names.
    judged_by: str | None = None

    @property
    def accuracy(self) -> float:
        return self.executions_correct / self.executions_n if self.executions_n else 0.0

    def to_json(self) -> dict:
        data = asdict(self)
        data["accuracy"] = self.accuracy
        data["interval"] = wilson_interval(self.executions_correct, self.executions_n)
        data["command_accuracy"] = self.commands_correct / self.scored_commands if self.scored_commands else 0.0
        data["command_interval"] = wilson_interval(self.commands_correct, self.scored_commands)
        data["unseen_accuracy"] = self.unseen_correct / self.unseen_n if self.unseen_n else None
        data["published_f1"] = PUBLISHED_F1 if self.published else None
        return data

    def summary(self) -> str:
        skipped = skipped_text(self.train_skipped) or "none"
        return "\n".join([
            f"trained on {self.train_commands} commands, {self.train_pairs} pairs ({self.demonstrations}, "
            f"layouts {self.layouts}); pairs skipped: {skipped}",
            *self.figure_lines(),
            *([f"judged with the library of {self.judged_by} (not the learner's)"] if self.judged_by else []),
            f"wall time: training {self.seconds_training:.1f} s, following {self.seconds_following:.1f} s"])

    def figure_lines(self) -> list[str]:
        """What was scored: accuracy per execution and per command, by task, failures by kind, confidence
        and the published figure (no line on training or time: a pooled cross-validation has its own)."""
        lines = [
            f"test: {self.test_commands} commands; {self.no_task_commands} whose pairs show no task (not scored)",
            f"per execution: {share(self.executions_correct, self.executions_n)}",
            f"per command (every pair right): {share(self.commands_correct, self.scored_commands)}",
            f"commands whose text is not in training, per execution: {share(self.unseen_correct, self.unseen_n)}",
        ]
        if self.no_task_executions:
            lines.append(f"executions not scored (their start state admits no task of the library): "
                         f"{self.no_task_executions}")
        if self.skipped_executions:
            lines.append(f"executions skipped (too large even for the relevance abstraction, or to tabulate; counted wrong "
                         f"above): {self.skipped_executions}")
        lines.append("per task (relations the pairs show), per execution:")
        for task, (k, n) in sorted(self.per_task.items(), key=lambda item: -item[1][1]):
            lines.append(f"  {task:<40} {k / n:.2%} ({k}/{n})")
        if self.failures:
            total = sum(sum(of_kind.values()) for of_kind in self.failures.values())
            lines.append(f"failed executions by kind ({total}; then by the relations left unmet):")
            for kind in FAILURE_KINDS:
                of_kind = self.failures.get(kind, {})
                if of_kind:
                    detail = ", ".join(f"{k} {unmet}" for unmet, k in sorted(of_kind.items(), key=lambda item: -item[1]))
                    lines.append(f"  {sum(of_kind.values()):>4} {kind}: {detail}")
        if self.calibration:
            lines.append(format_calibration(self.calibration, "confidence", unit="executions"))
        if self.command_calibration:
            lines.append(format_calibration(self.command_calibration, "confidence per command (its least "
                                            "confident layout)"))
        if self.published:
            lines.append(f"published (Williams et al. 2018, Table II): F1 {PUBLISHED_F1:.2f} of validated parses, "
                         f"three pairs per command")
        return lines


def share(k: int, n: int) -> str:
    """``k`` of ``n`` as a percentage with its count and 95% (Wilson) interval."""
    if not n:
        return "- (none)"
    lo, hi = wilson_interval(k, n)
    return f"{k / n:.2%} ({k}/{n}; 95% interval {lo:.1%}-{hi:.1%})"


def _task_kind(task) -> str:
    """The relations a task is made of, without what is said of their arguments: ``agentInRoom``."""
    if task is None:  # no layout of the command could be tabulated
        return "(unknown: too large to tabulate)"
    return "+".join(sorted({atom.predicate for atom in task})) or "(none)"


def failure_kind(goal, task: frozenset[Atom], missing: frozenset[Atom], reached: bool) -> str:
    """Why following failed (a key of :data:`FAILURE_KINDS`), from the goal acted on, what the pairs show
    (``task``) and the part of it the final state lacks (``missing``).

    Told apart by relation (the predicate), not by what is said of the objects: when a relation the goal
    asked for is unmet, the goal's objects were not the pairs' ("another object"); else, when the goal's
    relations are all among those the pairs show, the unmet ones were not asked ("more than the goal");
    else the goal asked for a relation the pairs do not show ("another relation")."""
    if not reached:
        return "unreached"
    asked = {atom.predicate for atom in goal}
    if asked & {atom.predicate for atom in missing}:
        return "another object"
    return "more than the goal" if asked <= {atom.predicate for atom in task} else "another relation"


@reading_states()  # each test pair named in the log lines of the spaces sized for it
def evaluate_pairs(train: list[Command], test: list[Command], library, demonstrations: str = "end-state",
                   layouts: str = "shared", skip_inconsistent: bool = False, learner_options: dict | None = None,
                   max_states: int = REACHABILITY_MAX_STATES, progress: bool = False,
                   min_confidence: float = DEFAULT_MIN_CONFIDENCE, judge=None) -> PairEvaluation:
    """Train on ``train``'s pairs, follow ``test``'s commands from each start state (module docstring).

    Every command is acted on; ``min_confidence`` is the threshold whose coverage and accuracy the
    calibration report gives (what ``follow --min-confidence`` would act on), predictions unchanged.
    ``judge``: a TaskLibrary to judge what the test pairs show and whether a final state does it with, where
    not ``library`` (two domains compared under one judge: a domain's descriptions are also the judge's)."""
    check_pair_evaluation(library, judge, min_confidence)
    if library is None:  # the corpus's own domain, as the CLI's default (its evidence cache is keyed by it)
        from groundlang.bdm_check import default_library

        library = default_library()
    started = time.perf_counter()
    same = judge is not None and [s.text for s in judge.program.sources] == [s.text for s in library.program.sources]
    judged_by = None if judge is None or same else judge.program.user_names  # the learner's own is no other judge
    judge = library if judge is None else judge
    tasks = [command_task(command, judge) for command in test]  # a test file's bad layout, before training
    made = training_instances(train, library, demonstrations, skip_inconsistent=skip_inconsistent, max_states=max_states,
                              layouts=layouts)
    if not made.instances:
        raise ValueError(f"no usable training pair (every pair was skipped: "
                         f"{skipped_text(made.skipped_counts()) or 'none read'})")
    learner = Learner(library=library, **(learner_options or {})).fit(made.instances, progress=progress)
    trained = time.perf_counter()
    seen = {c.text.strip().lower() for c in train}
    rows: list[dict] = []
    per_task: dict[str, list[int]] = defaultdict(lambda: [0, 0])
    failures: dict[str, dict[str, int]] = defaultdict(dict)  # kind -> the relations left unmet -> count
    correct = n = commands_correct = scored = no_task = unseen_n = unseen_correct = skipped = unscored = 0
    for index, (command, task) in enumerate(zip(test, tasks)):
        unseen = command.text.strip().lower() not in seen
        all_right = True
        followed = 0  # executions of the command that could be scored
        for k, pair in enumerate(command.pairs):
            STATE_SOURCE.set(f"{command.path}, line {pair.line}")  # for the log lines of the spaces it sizes
            row = {"index": index, "pair": k, "command": command.text}
            try:  # a layout too large to enumerate is planned in its relevance abstraction (model.relevance)
                result = learner.follow(command.text, pair.start,
                                        other_starts=[p.start for j, p in enumerate(command.pairs) if j != k])
            except NoTaskError as exc:  # nothing can be asked there, so no reading is right or wrong
                row.update(goal=None, final_state=None, not_scored=f"{command.path}, line {pair.line}: {exc}")
                unscored += 1
                rows.append(row)
                continue
            except (StateSpaceError, TabulationError) as exc:  # what neither the exact space nor the abstraction
                # can hold, or no PF table (refused before anything is grounded: learner_state.check_state)
                row.update(goal=None, final_state=None, skipped=f"{command.path}, line {pair.line}: {exc}",
                           confidence=0.0)
                missing, kind = task or frozenset(), "skipped"
            else:
                names = dict(zip(pair.start.layout.toy_names, pair.toy_names))  # the file's names of the blocks
                row.update(goal=format_goal(result.goal, names),
                           final_state=format_bdm_state(result.final_state, pair.toy_names),
                           confidence=float(result.confidence), out_of_reach=float(result.posterior.out_of_reach))
                missing = task - lifted_facts(result.final_state, judge)  # pair_tasks.satisfies, keeping what is unmet
                kind = failure_kind(result.goal, task, missing, result.reached) if missing else None
            hit = bool(task) and kind is None
            if task or task is None:  # None: no layout of the command could be tabulated, all skipped (wrong)
                row["correct"] = hit
                if not hit:
                    row.update(failure=kind, unmet=None if task is None else sorted(map(str, missing)))
                    unmet = "(unknown)" if task is None else "+".join(sorted({a.predicate for a in missing})) or "(none)"
                    failures[kind][unmet] = failures[kind].get(unmet, 0) + 1
                skipped += kind == "skipped"  # counted only where scored: a command showing no task counts none
                n += 1
                correct += hit
                per_task[_task_kind(task)][0] += hit
                per_task[_task_kind(task)][1] += 1
                if unseen:
                    unseen_n += 1
                    unseen_correct += hit
            all_right &= hit
            followed += 1
            rows.append(row)
        if (task or task is None) and followed:
            scored += 1
            commands_correct += all_right
        elif task is not None and not task:
            no_task += 1
        # (A task shown, yet no start state admits one: its executions are counted as not scored.)
    finished = time.perf_counter()

    calibration, command_calibration = calibration_of_rows(rows, min_confidence)

    return PairEvaluation(
        train_commands=len(train), train_pairs=sum(len(getattr(i, "pairs", (i,))) for i in made.instances),
        train_skipped=made.skipped_counts(),
        test_commands=len(test), scored_commands=scored, no_task_commands=no_task,
        executions_n=n, executions_correct=correct, commands_correct=commands_correct,
        unseen_n=unseen_n, unseen_correct=unseen_correct, skipped_executions=skipped,
        per_task={k: tuple(v) for k, v in per_task.items()}, failures=dict(failures),
        seconds_training=trained - started, seconds_following=finished - trained,
        demonstrations=demonstrations, layouts=layouts, no_task_executions=unscored, executions=rows,
        calibration=calibration, command_calibration=command_calibration, published=is_corpus_library(judge),
        judged_by=judged_by,
    )


def check_pair_evaluation(library, judge, min_confidence) -> None:
    """TypeError or ValueError, before any training, for a library, judge or threshold an evaluation cannot use."""
    for name, value in (("library", library), ("judge", judge)):  # None: the corpus's domain; the library
        if not isinstance(value, (TaskLibrary, type(None))):
            raise TypeError(f"evaluate_pairs: {name} must be a TaskLibrary or None, not {type(value).__name__}")
    if min_confidence is None:
        raise ValueError("evaluate_pairs: min_confidence must be a number from 0 to 1, got None")
    check_threshold("evaluate_pairs", "min_confidence", min_confidence)


def calibration_of_rows(rows: list[dict], min_confidence: float) -> tuple[dict, dict]:
    """The confidence reports of scored execution rows (those with ``correct``): per execution, and per
    command (rows of one ``index``) with its least confident layout, right only when every layout is (acting
    on a command means acting in every layout it comes with; a skipped layout has confidence 0)."""
    scored = [row for row in rows if "correct" in row]
    commands: dict[int, list[dict]] = defaultdict(list)
    for row in scored:
        commands[row["index"]].append(row)

    def report(pairs: list[tuple[float, bool]]) -> dict:
        return calibration_report(*zip(*pairs), threshold=min_confidence) if pairs else {}

    return (report([(row["confidence"], row["correct"]) for row in scored]),
            report([(min(r["confidence"] for r in of), all(r["correct"] for r in of)) for of in commands.values()]))
