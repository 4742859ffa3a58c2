"""The child process that solves a program of user files (``Program(..., isolated=True)``): killed at the time
limit, capped in memory, and its answer capped in size before the parent reads it. The parent sends a JSON request
on the child's stdin (the sources, the facts, the models wanted, the time limit); the child replies on stdout with
the answer sets' shown atoms, or the error's class and message, which the parent raises again."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import clingo

from groundlang.logic.program import (AspError, AspGroundingError, AspScriptRefused, AspSyntaxError, AspTimeout,
                                      Program, Source)
from groundlang.logic.sources import one_line

__all__ = ["solve_in_child", "CHILD_MEMORY_LIMIT", "MAX_REPLY_ATOMS", "MAX_REPLY_SHOWN"]

# Address-space cap of the child process that solves user programs.
CHILD_MEMORY_LIMIT = 2 << 30
# Extra seconds the parent waits for the child's own timeout report before killing it.
_CHILD_GRACE = 5.0
# What a child may send back, which the parent reads into memory: each distinct shown atom once (the package's
# libraries show at most about 7,500: a Williams layout's PF tables; "task(t(1..3000000))." would show millions),
# and each answer set as the indices of its atoms (a layout's groundings repeat most atoms in every answer set).
MAX_REPLY_ATOMS = 200_000
MAX_REPLY_SHOWN = 5_000_000
_ERRORS = {c.__name__: c for c in (AspError, AspSyntaxError, AspScriptRefused, AspGroundingError, AspTimeout)}


def solve_in_child(program: Program, facts: str, models: int, time_limit: float | None) -> list:
    request = {
        "sources": [[s.name, s.text] for s in program.sources],
        "allow_scripts": program.allow_scripts,
        "facts": facts,
        "models": models,
        "time_limit": time_limit,
    }
    try:
        done = subprocess.run(
            [sys.executable, "-m", "groundlang.logic.child_process"],
            input=json.dumps(request), capture_output=True, text=True,
            timeout=None if time_limit is None else time_limit + _CHILD_GRACE,
        )
    except subprocess.TimeoutExpired:
        raise AspTimeout(f"solving {program.names} did not finish within {time_limit:g} s "
                         "(child process killed)") from None
    try:
        reply = json.loads(done.stdout)
    except ValueError:
        reason = (one_line(done.stderr)[-300:] or f"exit code {done.returncode}")
        if done.returncode < 0 or "MemoryError" in reason or "bad_alloc" in reason:
            reason = f"it ran out of memory ({CHILD_MEMORY_LIMIT >> 30} GiB) or crashed: {reason}"
        raise AspGroundingError(f"grounding {program.names} failed: {reason}") from None
    if "error" in reply:
        kind, message = reply["error"]
        raise _ERRORS.get(kind, AspError)(message)
    atoms = [clingo.parse_term(t) for t in reply["atoms"]]
    return [[atoms[k] for k in model] for model in reply["models"]]


def _reply(found: list, where: str, in_layout: bool) -> dict:
    """The answer sets as each distinct atom once and each set as its atoms' indices; AspGroundingError, before
    anything is written out, where they are more than the parent may read (its memory stays bounded)."""
    shown = sum(len(model) for model in found)
    index: dict = {}
    models: list[list[int]] = []
    for model in found if shown <= MAX_REPLY_SHOWN else ():
        models.append([index.setdefault(sym, len(index)) for sym in model])
        if len(index) > MAX_REPLY_ATOMS:  # stop counting: a runaway range would take its time to index
            break
    if shown > MAX_REPLY_SHOWN or len(index) > MAX_REPLY_ATOMS:
        counted = (f"{len(found):,} answer set{'s' * (len(found) != 1)} of {shown:,} atoms in all, more than "
                   f"{MAX_REPLY_ATOMS:,} distinct" if shown <= MAX_REPLY_SHOWN else
                   f"{shown:,} atoms in {len(found):,} answer sets")
        limits = f"at most {MAX_REPLY_ATOMS:,} distinct and {MAX_REPLY_SHOWN:,} in all are read"
        why = (f"grounded in this layout it shows {counted}; {limits} from a library of your own (solved in a child "
               "process): a layout of many rooms or toys" if in_layout else
               f"the program shows {counted}; {limits} (a rule that makes an atom per number of a large range?)")
        raise AspGroundingError(f"{where}: {why}")
    return {"atoms": [str(sym) for sym in index], "models": models}


def _child_main() -> None:
    """Child side of ``isolated`` solving: JSON request on stdin, JSON reply on stdout."""
    try:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (CHILD_MEMORY_LIMIT, CHILD_MEMORY_LIMIT))
    except (ImportError, ValueError, OSError):  # pragma: no cover - not on every platform
        pass
    request = json.loads(sys.stdin.read())
    try:
        program = Program(tuple(Source(n, t) for n, t in request["sources"]), request["allow_scripts"])
        found = program.solve(request["facts"], models=request["models"], time_limit=request["time_limit"])
        reply = _reply(found, program.user_names, bool(request["facts"].strip()))
    except AspError as exc:
        reply = {"error": [type(exc).__name__, str(exc)]}
    except MemoryError:
        reply = {"error": ["AspGroundingError",
                           f"grounding ran out of memory ({CHILD_MEMORY_LIMIT >> 30} GiB)"]}
    sys.stdout.write(json.dumps(reply))
    sys.stdout.flush()
    # A runaway grounding may still be running in a thread; leave without finalising it.
    os._exit(0)


if __name__ == "__main__":
    _child_main()
