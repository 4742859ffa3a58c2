"""``groundlang check`` for the Williams et al. (2018) corpus: what is there, what is unusable, and why.

Reports commands, (start, end) pairs and distinct layouts; every pair whose end state cannot be reached
from its start state under the project's dynamics (file and line); pairs that cannot be checked (too
large even for the relevance abstraction, or not reached in it); pairs in a layout too large to tabulate
(file and line: training skips them, and a command's task is what its other pairs show); commands whose pairs show no task
(nothing that changed holds in every end state: groundlang.pair_tasks); and, over the commands whose text
is given more than once, how many one task per text could get right (``pair_tasks.text_agreement``: the
labels' noise). Exit 1 when a pair is unreachable, unless ``--skip-inconsistent``.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from importlib.resources import files

from groundlang.bdm import DEFAULT_PALETTE, bdm_files, read_bdm
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.relevance import STATE_SOURCE, reading_states
from groundlang.model.pf_tables import tabulation_refusal
from groundlang.pair_tasks import command_task, reachable, text_agreement

__all__ = ["check_bdm", "default_library", "is_corpus_library"]


def default_library(files_given=None, **load) -> TaskLibrary:
    """The task library of ``files_given`` (a ``--library`` list) or, without them, the relations,
    superlatives and tasks of the corpus (``logic/domains/williams2018.lp``); ``load``: TaskLibrary.load's
    keywords (``time_limit``)."""
    if files_given:
        return TaskLibrary.load(files_given, **load)
    return TaskLibrary.load([str(files("groundlang.logic") / "domains" / "williams2018.lp")], **load)


def is_corpus_library(library: TaskLibrary) -> bool:
    """Whether ``library`` is the corpus's own (the same programs as :func:`default_library`'s, however
    named): only then is a run on its tasks set beside the published figure."""
    return [s.text for s in library.program.sources] == [s.text for s in default_library().program.sources]


@reading_states()
def check_bdm(args: argparse.Namespace) -> int:
    paths = bdm_files(args.directory, any_name=getattr(args, "format", None) == "williams2018")
    if not paths:
        raise ValueError(f"{args.directory}: no .bdm file there (with --format williams2018 also a file of any "
                         "name or a folder of .txt files)")
    palette = args.palette or DEFAULT_PALETTE
    from groundlang.commands import time_limit_given, words_beside_checked

    library = words_beside_checked(default_library(args.library, **time_limit_given(args)))
    commands = [c for path in paths for c in read_bdm(path, palette)]
    pairs = [(c, p) for c in commands for p in c.pairs]
    layouts = {p.start.layout for _, p in pairs}
    if args.library:  # a library of the user's, checked in each layout as training meets it
        from groundlang.model.tasks import check_library_at

        for command, pair in {p.start.layout: (c, p) for c, p in pairs}.values():
            check_library_at(pair.start, library, f"{command.path}, line {pair.line}")
    sizes = Counter((p.start.layout.width - 1, p.start.layout.height - 1, len(p.start.toys)) for _, p in pairs)
    # Everything is computed before anything is printed. A layout too large to tabulate is set aside before
    # any of its states is enumerated or it is grounded (the reachability check had taken gigabytes to get
    # there); a command's task is what its other pairs show.
    refused = {layout: tabulation_refusal(layout) for layout in layouts}
    too_large = [(c, p, refused[p.start.layout]) for c, p in pairs if refused[p.start.layout] is not None]
    tasks = [command_task(c, library) for c in commands]
    unreachable, unchecked = [], 0
    for command, pair in pairs:
        if refused[pair.start.layout] is not None:
            continue
        STATE_SOURCE.set(f"{command.path}, line {pair.line}")  # for the log lines of the spaces it sizes
        found = reachable(pair.start, pair.end)
        if found is None:
            unchecked += 1
        elif not found:
            unreachable.append((command, pair))
    empty = [c for c, task in zip(commands, tasks) if task is not None and not task]
    print(f"corpus: {', '.join(map(str, paths))} (palette {palette})")
    distinct = len({c.text for c in commands})
    print(f"commands: {len(commands)} ({distinct} distinct text{'' if distinct == 1 else 's'})")
    print(f"pairs: {len(pairs)}; distinct layouts: {len(layouts)}")
    # A grid by its largest x and y, as the corpus names its layouts (8x8: x and y from 0 to 8, 9 cells a side).
    print("pairs by grid (largest x by largest y) and blocks: " + ", ".join(f"{w}x{h} with {k}: {n}" for (w, h, k), n in sorted(sizes.items())))
    print(f"pairs whose end state cannot be reached from the start: {len(unreachable)}")
    for command, pair in unreachable:
        print(f"  {command.path}, line {pair.line}: {command.text!r}")
    print(f"pairs not checked (too large even for the relevance abstraction, or not reached in it): {unchecked}")
    print(f"pairs in a layout too large to tabulate (training skips them): {len(too_large)}")
    for command, pair, why in too_large[:20]:
        print(f"  {command.path}, line {pair.line}: {why}")
    if len(too_large) > 20:
        print(f"  ... and {len(too_large) - 20} more")
    print(f"commands whose pairs show no task: {len(empty)}")
    for c in empty[:20]:
        print(f"  {c.path}, line {c.line}: {c.text!r}")
    if len(empty) > 20:
        print(f"  ... and {len(empty) - 20} more")
    texts, shared, covered = text_agreement(commands, tasks)
    if shared:
        print(f"commands whose text another command shares: {shared} ({texts} text{'' if texts == 1 else 's'}); "
              f"one task per text does what the pairs of at most {covered} of them show "
              f"({100 * covered / shared:.1f}%), a bound for any reader of the words alone")
    if unreachable and not args.skip_inconsistent:
        print(f"groundlang check: {len(unreachable)} unreachable pair{'s' * (len(unreachable) != 1)} (use "
              "--skip-inconsistent to skip them)",
              file=sys.stderr)
        return 1
    return 0
