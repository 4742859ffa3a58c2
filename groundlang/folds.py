"""The folds of an evaluation: refit (leave-one-out) and follow each held-out command, in this process,
in forked worker processes or on a Ray cluster. :func:`groundlang.evaluation.evaluate` builds the context."""

from __future__ import annotations

import multiprocessing
import os
import time

from groundlang.corpus import Instance
from groundlang.goal_translation import GoalHoldsAtStart, describe_goal, translate_goal
from groundlang.labels import goal_holds
from groundlang.learner import Learner
from groundlang.results import LAYOUT_ERRORS
from groundlang.logic.atoms import format_goal
from groundlang.wording import goal_phrase

__all__ = ["run_folds", "prepare_worker", "usable_workers"]

_CONTEXT: dict = {}


def _score(learner: Learner, instance: Instance, gold, novel_states) -> dict:
    result = learner.follow(instance.command, instance.initial_state)
    record = {
        "instance": instance.name,
        "command": instance.command,
        "gold": format_goal(gold),
        "gold_size": len(gold),
        "gold_task": describe_goal(gold, instance.initial_state),
        "predicted": format_goal(result.goal),
        "predicted_task": describe_goal(result.goal, instance.initial_state),
        "gold_words": goal_phrase(gold, instance.initial_state, learner.library),
        "predicted_words": result.goal_words,
        "correct": goal_holds(gold, result.final_state, learner.library),
        "confidence": result.confidence,
        "margin": result.posterior.margin,
        "novel": [],
    }
    for name, state in novel_states:
        try:
            translated = translate_goal(gold, instance.initial_state, state, name, learner.library)
        except GoalHoldsAtStart as exc:  # counted apart, as an execution whose start admits no task
            record["novel"].append({"environment": name, "not_scored": str(exc)})
            continue
        try:
            novel = learner.follow(instance.command, state)
        except LAYOUT_ERRORS as exc:  # the layout, not the command: counted wrong
            record["novel"].append({"environment": name, "gold": format_goal(translated), "correct": False,
                                    "confidence": None, "unfollowed": f"{name}: {exc}"})
            continue
        record["novel"].append(
            {
                "environment": name,
                "gold": format_goal(translated),
                "predicted": format_goal(novel.goal),
                "predicted_task": describe_goal(novel.goal, state),
                "correct": goal_holds(translated, novel.final_state, learner.library),
                "confidence": novel.confidence,
            }
        )
    return record


def _fold(index: int) -> dict:
    ctx = _CONTEXT
    learner: Learner = ctx["learner"]
    instance = ctx["instances"][index]
    started = time.perf_counter()
    try:
        if ctx["protocol"] == "loo":
            keep = [k for k in range(len(ctx["instances"])) if k != index]
            learner.fit(
                [ctx["instances"][k] for k in keep],
                batch=ctx["batch"].subset(keep),
                init=ctx["globals"] if ctx["warm_start"] else None,
            )
        record = _score(learner, instance, ctx["golds"][index], ctx["novel_states"])
    except (ValueError, RuntimeError) as exc:
        return {"instance": instance.name, "error": f"{type(exc).__name__}: {exc}", "seconds": time.perf_counter() - started}
    record["seconds"] = time.perf_counter() - started
    return record


def _init_worker(context: dict) -> None:
    prepare_worker(context.get("parent"))
    _CONTEXT.clear()
    _CONTEXT.update(context)


def prepare_worker(parent: int | None) -> None:
    """What a forked worker of a pool does first: one torch thread (the pool's processes share the cores),
    stopped silently by the pool's SIGTERM, deaf to Ctrl-C (the parent reports an interruption once) and
    ended when ``parent`` dies."""
    import signal

    import torch

    # Forked workers inherit the CLI's SIGTERM-as-Ctrl-C handler; the pool
    # stops them with SIGTERM when it closes, which must stay silent.
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _die_with_parent(signal.SIGTERM, parent)
    torch.set_num_threads(1)


def _die_with_parent(sig: int, parent: int | None = None) -> None:
    """Linux: the kernel sends ``sig`` to this worker when its parent dies (``prctl(PR_SET_PDEATHSIG)``).
    A parent killed with -9 cannot stop its pool: its workers had gone on computing their fold and then
    printed a BrokenPipe traceback each, after the command had ended. Elsewhere nothing is done."""
    import ctypes
    import ctypes.util

    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        libc.prctl(1, int(sig), 0, 0, 0)  # 1: PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    if parent is not None and os.getppid() != parent:  # it died before the call: no signal will come
        os._exit(0)


def usable_workers(workers: int, folds: int) -> int:
    """How many processes to fork for ``workers`` asked: no more than there are folds to run or cores to run
    them on. A pool forks every process it is asked for at once, so an unbounded ``--workers`` (100000)
    would fork that many copies of this process, folds or not; beyond the cores they only share them."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, min(workers, folds, cores))


def run_folds(context: dict, indices: list[int], workers: int, ray_address: str | None, progress: bool) -> list[dict]:
    workers = usable_workers(workers, len(indices))
    if ray_address is not None:
        from groundlang.distributed import run_on_ray

        return run_on_ray(_init_worker, _fold, context, indices, ray_address)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(indices), desc="folds", unit="fold", leave=False)
    records = []
    if workers <= 1:  # in this process: its signals stay the CLI's (a worker's are deaf to Ctrl-C)
        _CONTEXT.clear()
        _CONTEXT.update(context)
        try:
            for i in indices:
                records.append(_fold(i))
                if bar is not None:
                    bar.update(1)
        finally:
            _CONTEXT.clear()
    else:
        with multiprocessing.get_context("fork").Pool(workers, _init_worker, ({**context, "parent": os.getpid()},)) as pool:
            for record in pool.imap(_fold, indices, chunksize=max(1, len(indices) // (8 * workers))):
                records.append(record)
                if bar is not None:
                    bar.update(1)
    if bar is not None:
        bar.close()
    return records
