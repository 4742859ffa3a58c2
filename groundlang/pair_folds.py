"""Cross-validation by text on a corpus of (start, end) pairs: ``evaluate --folds K``.

One held-out split by text scores a fifth of the corpus, and a text that recurs lands there whole: in the
Williams corpus one text is 15 commands, so one split's figure can turn on one text. K folds hold out
every text once (fold ``k``: the texts whose position falls in the ``k``-th K-th of the range,
``pair_corpus.fold_of_text``), each trained on the other folds' commands, and the executions of all folds
are pooled into one figure (:func:`pool`), with each fold's own beside it. Folds run in forked processes
(``workers``), each on one torch thread, sharing the evidence cache.
"""

from __future__ import annotations

import logging
import multiprocessing
import numbers
import os
import time
from collections import defaultdict
from dataclasses import dataclass, replace

from groundlang.bdm import Command
from groundlang.folds import prepare_worker, usable_workers
from groundlang.learner import DEFAULT_MIN_CONFIDENCE
from groundlang.pair_corpus import fold_of_text, text_position
from groundlang.pair_evaluation import PairEvaluation, calibration_of_rows, check_pair_evaluation, evaluate_pairs

__all__ = ["PairCrossValidation", "cross_validate_pairs", "pool", "MAX_FOLDS"]

log = logging.getLogger(__name__)

# More folds than this hold out too little to be worth a model each; leave-one-text-out is not offered.
MAX_FOLDS = 20

_CONTEXT: dict = {}  # a forked worker's: the commands, the folds' held-out indices, evaluate_pairs' options


@dataclass
class PairCrossValidation:
    """The folds' evaluations (each with its rows' ``index`` counting the corpus's commands) and their pool."""

    folds: list[PairEvaluation]
    held_out: list[list[int]]  # the corpus indices each fold held out
    pooled: PairEvaluation
    seconds: float  # wall time of the whole run
    beyond: float = 0.0  # the development split set aside (--holdout F --tuning), 0 for none

    def to_json(self) -> dict:
        data = self.pooled.to_json()
        # what each fold trained on is under "folds": summed over folds, a command would count K - 1 times
        data.update(train_commands=None, train_pairs=None, train_skipped=None, seconds=self.seconds,
                    development_split_set_aside=self.beyond)
        data["folds"] = [{key: value for key, value in fold.to_json().items() if key != "executions"}
                         | {"fold": k, "held_out_commands": len(self.held_out[k])}
                         for k, fold in enumerate(self.folds)]
        return data

    def summary(self) -> str:
        p = self.pooled
        sizes = [fold.train_commands for fold in self.folds]
        lines = [f"{len(self.folds)} folds by text, each trained on the others' commands ({min(sizes)} to "
                 f"{max(sizes)} commands; {p.demonstrations}, layouts {p.layouts}); every text held out once"
                 + (f" but the development split's (the texts hashing into the first {self.beyond:g} of the range), "
                    "which no fold reads"
                    if self.beyond else ""),
                 "fold  held out  per execution            per command"]
        for k, fold in enumerate(self.folds):
            lines.append(f"{k:>4}  {fold.test_commands:>8}  "
                         f"{_ratio(fold.executions_correct, fold.executions_n):<23}  "
                         f"{_ratio(fold.commands_correct, fold.scored_commands)}")
        lines.append("pooled over the folds:")
        lines += self.pooled.figure_lines()
        lines.append(f"time: training {p.seconds_training:.1f} s and following {p.seconds_following:.1f} s, summed "
                     f"over the folds; {self.seconds:.1f} s wall")
        return "\n".join(lines)


def _ratio(k: int, n: int) -> str:
    return f"{k / n:.2%} ({k}/{n})" if n else "- (none)"


def fold_indices(commands: list[Command], folds: int, beyond: float = 0.0) -> list[list[int]]:
    """The corpus indices each of ``folds`` folds holds out (``pair_corpus.fold_of_text``), in corpus order;
    with ``beyond``, the commands of the development split it names are in none."""
    held: list[list[int]] = [[] for _ in range(folds)]
    for i, command in enumerate(commands):
        if (k := fold_of_text(command.text, folds, beyond)) is not None:
            held[k].append(i)
    return held


def cross_validate_pairs(commands: list[Command], folds: int, library, workers: int = 1,
                         min_confidence: float = DEFAULT_MIN_CONFIDENCE, beyond: float = 0.0,
                         **options) -> PairCrossValidation:
    """Evaluate ``folds`` folds by text (module docstring); ``options`` go to ``evaluate_pairs`` (not
    ``progress``: the folds report only when done). With ``beyond`` (``--holdout F --tuning``), the
    commands of the development split ``held_out_by_text(commands, beyond)`` are neither held out nor
    trained on, and the folds cut the rest: cross-validation to choose mechanisms on. Raises ValueError for a
    fold count out of range or a fold that holds out nothing or leaves nothing to train on, before any fold
    is trained."""
    if isinstance(folds, bool) or not isinstance(folds, numbers.Integral):
        raise TypeError(f"cross_validate_pairs: folds must be an integer, not {type(folds).__name__}")
    if isinstance(beyond, bool) or not isinstance(beyond, numbers.Real) or not 0 <= beyond < 1:
        raise ValueError(f"cross_validate_pairs: beyond must be a fraction from 0 to below 1, got {beyond!r:.40}")
    check_pair_evaluation(library, options.get("judge"), min_confidence)
    if "progress" in options:  # a fold's progress lines, interleaved with the others', would say nothing
        raise TypeError("cross_validate_pairs: no progress argument (the folds report only when done)")
    if not 2 <= folds <= MAX_FOLDS:
        raise ValueError(f"--folds {folds}: expected 2 to {MAX_FOLDS} folds")
    held = fold_indices(commands, folds, beyond)
    in_folds = sum(map(len, held))
    if beyond and not in_folds:
        raise ValueError(f"no text hashes beyond the development split (the first {beyond:g} of the range): "
                         "nothing to cross-validate; set aside a smaller --holdout")
    texts = len({text_position(commands[i].text) for fold in held for i in fold})  # a text as the folds cut them
    where = "beyond the development split" if beyond else "in the corpus"
    for k, indices in enumerate(held):
        if not indices:
            fewer = (f"one text {where}: nothing to hold out by text" if texts == 1 else
                     "use fewer folds" if texts >= folds else f"{texts} texts {where}: use at most {texts} folds")
            raise ValueError(f"fold {k} of {folds} holds out no command (no text falls in it): {fewer}")
        if len(indices) == in_folds:
            raise ValueError(f"fold {k} of {folds} holds out every command {where} (its "
                             f"{'one text hashes' if texts == 1 else f'{texts} texts all hash'} into that fold): "
                             "nothing to train on")
    started = time.perf_counter()
    context = {"commands": commands, "held": held, "library": library, "options": options,
               "min_confidence": min_confidence}
    workers = usable_workers(workers, folds)
    results: list[PairEvaluation] = []

    def take(result: PairEvaluation | str) -> None:
        if isinstance(result, str):  # a fold's error, said at once with its fold: the others are not waited for
            raise ValueError(f"fold {len(results)} of {folds}: {result}")
        results.append(result)

    if workers <= 1:
        _CONTEXT.update(context)
        try:
            for k in range(folds):
                take(_fold(k))
        finally:
            _CONTEXT.clear()
    else:  # leaving the pool on an error terminates the folds still running
        with multiprocessing.get_context("fork").Pool(workers, _init, ({**context, "parent": os.getpid()},)) as pool_:
            for result in pool_.imap(_fold, range(folds), chunksize=1):
                take(result)
    evaluations = [_renumbered(result, held[k], k) for k, result in enumerate(results)]
    return PairCrossValidation(evaluations, held, pool(evaluations, min_confidence), time.perf_counter() - started,
                               beyond)


def _init(context: dict) -> None:
    prepare_worker(context.pop("parent"))
    _CONTEXT.clear()
    _CONTEXT.update(context)


def _fold(k: int) -> PairEvaluation | str:
    commands, held = _CONTEXT["commands"], set(_CONTEXT["held"][k])
    in_folds = {i for indices in _CONTEXT["held"] for i in indices}  # all but a development split set aside
    train = [c for i, c in enumerate(commands) if i not in held and i in in_folds]
    test = [c for i, c in enumerate(commands) if i in held]
    started = time.perf_counter()
    try:
        result = evaluate_pairs(train, test, _CONTEXT["library"], min_confidence=_CONTEXT["min_confidence"],
                                **_CONTEXT["options"])
    except (ValueError, OSError) as exc:  # returned, not raised: a library error need not survive pickling
        return " ".join(str(exc).split())
    log.info("fold %d: %d/%d executions in %.1f s", k, result.executions_correct, result.executions_n,
             time.perf_counter() - started)
    return result


def _renumbered(result: PairEvaluation, held: list[int], fold: int) -> PairEvaluation:
    """A fold's evaluation whose rows count the corpus's commands (not the fold's) and say their fold."""
    rows = [{**row, "index": held[row["index"]], "fold": fold} for row in result.executions]
    return replace(result, executions=rows)


def pool(parts: list[PairEvaluation], min_confidence: float = DEFAULT_MIN_CONFIDENCE) -> PairEvaluation:
    """The folds' executions as one evaluation: counts summed, rows in corpus order, the confidence
    reports computed again over every scored row (``calibration_of_rows``, as ``evaluate_pairs`` does)."""
    def summed(name: str) -> int:
        return sum(getattr(part, name) for part in parts)

    per_task: dict[str, list[int]] = defaultdict(lambda: [0, 0])
    failures: dict[str, dict[str, int]] = defaultdict(dict)
    train_skipped: dict[str, int] = defaultdict(int)
    for part in parts:
        for task, (k, n) in part.per_task.items():
            per_task[task][0] += k
            per_task[task][1] += n
        for kind, of_kind in part.failures.items():
            for unmet, n in of_kind.items():
                failures[kind][unmet] = failures[kind].get(unmet, 0) + n
        for why, n in part.train_skipped.items():
            train_skipped[why] += n
    rows = sorted((row for part in parts for row in part.executions), key=lambda row: (row["index"], row["pair"]))
    calibration, command_calibration = calibration_of_rows(rows, min_confidence)
    return PairEvaluation(
        train_commands=summed("train_commands"), train_pairs=summed("train_pairs"), train_skipped=dict(train_skipped),
        test_commands=summed("test_commands"), scored_commands=summed("scored_commands"),
        no_task_commands=summed("no_task_commands"), executions_n=summed("executions_n"),
        executions_correct=summed("executions_correct"), commands_correct=summed("commands_correct"),
        unseen_n=summed("unseen_n"), unseen_correct=summed("unseen_correct"),
        skipped_executions=summed("skipped_executions"), per_task={k: tuple(v) for k, v in per_task.items()},
        failures=dict(failures), seconds_training=sum(p.seconds_training for p in parts),
        seconds_following=sum(p.seconds_following for p in parts), demonstrations=parts[0].demonstrations,
        layouts=parts[0].layouts, no_task_executions=summed("no_task_executions"), executions=rows,
        calibration=calibration, command_calibration=command_calibration,
        published=all(part.published for part in parts), judged_by=parts[0].judged_by,
    )
