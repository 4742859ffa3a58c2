"""A discovered task library as commented ASP text a person can read and edit, and its file."""

from __future__ import annotations

import os
from pathlib import Path

from groundlang.logic.storage import write_atomically
from groundlang.logic.tasks import TaskLibrary, format_lifted_task

__all__ = ["library_text", "write_library"]


def library_text(tasks, reports, score, settings, num_instances: int, pfs: TaskLibrary | None = None) -> str:
    """The discovered tasks as ASP facts (tasks.lp's format) with a comment header and per-task evidence;
    ``reports`` are discovery's DemonstrationReports, ``settings`` its DiscoverySettings."""
    lines = [
        "% Lifted tasks discovered from demonstrations by groundlang (inference/discovery.py).",
        "%",
        "% Format as in groundlang's tasks.lp: task(Name), var(Name, \"V\", Class), goal(Name, Pf, (\"V\", ...)).",
        f"% Evidence: {num_instances} instances, {len(reports)} distinct demonstrations. Each task below was",
        "% lifted from MLIRL's top-weighted position PFs (objects -> typed variables) and kept because it",
        f"% shortens the description of the demonstrations (score J = {score:.3f} nats; weight margin",
        f"% {settings.weight_margin}, up to {settings.max_conjuncts} atoms per goal, "
        f"{settings.atom_cost:.3f} nats per atom).",
        ("% Edit freely: this file loads with TaskLibrary.load([path])." if pfs is None else
         f"% Edit freely: this file loads with TaskLibrary.load([path, ...]) beside the PFs it names: "
         f"{pfs.program.user_names}."),
        "",
    ]
    for task in tasks:
        explained = [r for r in reports if r.task == task.name]
        lines.append(f"% {task}")
        instances = sum(len(r.instances) for r in explained)
        lines.append(f"%   explains {len(explained)} distinct demonstration(s) ({instances} instance(s)):")
        for r in explained:
            picks = ", ".join(f"{v} {describe_pick(c)}" for v, c in r.singled_out)
            more = f" (+{len(r.instances) - 1} more)" if len(r.instances) > 1 else ""
            lines.append(f"%   - {r.instances[0]}{more}: {r.grounding.goal_text}, "
                         f"log-likelihood {r.log_likelihood:.3f}; {picks}")
        lines.append(format_lifted_task(task))
    unexplained = [r for r in reports if r.task is None]
    if unexplained:
        lines.append("% Not explained by any task: " + ", ".join(r.instances[0] for r in unexplained))
    return "\n".join(lines).rstrip("\n") + "\n"


def describe_pick(conjunction) -> str:
    if conjunction is None:
        return "not singled out by colour/shape"
    if not conjunction:
        return "the only one of its class"
    return "by " + " ∧ ".join(map(str, conjunction))


def write_library(discovery, path: str | os.PathLike) -> Path:
    """Write a :class:`~groundlang.inference.discovery.Discovery`'s ASP text to ``path`` atomically
    (temporary file + os.replace)."""
    return write_atomically(path, discovery.text)
