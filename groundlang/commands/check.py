"""``groundlang check DIR --palette NAME [--labels CSV] [--skip-inconsistent]``: load, replay, summarise a corpus.

A ``.bdm`` file, or a folder of them, or ``--format williams2018`` reads the Williams et al. (2018)
corpus instead (palette williams2018 unless given; groundlang.bdm): commands, pairs, layouts, pairs
whose end state cannot be reached from the start, and commands whose pairs show no task.

Exit code 0 when every demonstration replays (or inconsistent ones are
skipped on request) and every label's goal holds at the end; 1 otherwise;
2 for malformed input (raised by the library, reported by the CLI).
"""

from __future__ import annotations

import argparse
import sys

from groundlang.commands import (input_path, LIBRARY_NAMES, PALETTE_HELP, add_time_limit_option, library_given, library_path,
                                 require_palette)
from groundlang.corpus import read_corpus


def register(subparsers) -> None:
    p = subparsers.add_parser("check", help="load a corpus folder and replay every demonstration, or a .bdm file or folder "
                                             "and search each pair's end from its start; print a summary")
    p.add_argument("directory", type=input_path, metavar="DIR", help="folder of corpus files (*.txt), or a .bdm file or folder")
    p.add_argument("--palette", help=PALETTE_HELP + " (required but for .bdm, whose default is williams2018)")
    p.add_argument("--format", choices=("commands-to-tasks", "williams2018"),
                   help="the corpus format (default: williams2018 for .bdm files, else commands-to-tasks)")
    p.add_argument("--library", metavar="LP", action="append", type=library_path,
                   help="task library .lp file (repeatable): for the tasks .bdm pairs show (default: "
                        "williams2018), or whose PFs --labels may use" + LIBRARY_NAMES)
    p.add_argument("--labels", type=input_path, metavar="CSV", help="gold labels (prefix,goal) to check against final states")
    p.add_argument("--skip-inconsistent", action="store_true",
                   help="skip demonstrations that do not replay (counted) instead of failing")
    add_time_limit_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from groundlang.bdm import bdm_files

    if args.format == "williams2018" or (args.format is None and bdm_files(args.directory)):
        from groundlang.bdm_check import check_bdm

        if args.labels:  # said, not ignored: a .bdm pair's end state is its label
            raise ValueError(f"--labels {args.labels}: for a *.txt corpus with labels; a .bdm corpus is judged "
                             "by what its pairs show")

        return check_bdm(args)
    require_palette(args, args.directory)
    library = library_given(args)  # a library given is checked (refused with its line) even without --labels
    if args.labels:  # read before the corpus: a missing or bad file is said before half a report
        from groundlang.labels import label_coverage, read_labels

        labels = read_labels(args.labels)
    # Always collect every inconsistent file so the report lists them all; the flag decides the exit code.
    corpus = read_corpus(args.directory, args.palette, skip_inconsistent=True)
    ok = True
    print(f"corpus: {corpus.directory} (palette {corpus.palette.name})")
    print(f"instances: {len(corpus)}")
    print(f"distinct commands: {len(corpus.commands())}")
    print(f"distinct layouts: {len(corpus.distinct_layouts())}")
    print(f"distinct demonstrations: {len(corpus.distinct_demonstrations())}")
    print(f"inconsistent demonstrations: {len(corpus.skipped)}")
    unkeyed = _layouts_not_keyed(corpus)
    if unkeyed:  # said here with every file, before a run: train may stop at the first of them
        print(f"layouts whose states cannot all be keyed: {len(unkeyed)}")
        for reason in unkeyed:
            print(f"  {reason}")
        # A warning, not a failure: train reads a demonstration there in a relevance abstraction where the toys
        # it needs to move fit a key, and refuses it only where every object must move (its stepwise likelihood).
        print(f"groundlang check: warning: {len(unkeyed)} layouts whose states cannot all be keyed in 64 bits; "
              "train refuses a demonstration there where its likelihood needs every object to move",
              file=sys.stderr)
    if library is not None:
        _tabulate_layouts(corpus, library)
    for _, reason in corpus.skipped:
        print(f"  {reason}")
    if corpus.skipped:
        if args.skip_inconsistent:
            print(f"skipped: {len(corpus.skipped)} inconsistent files (--skip-inconsistent)")
        else:
            print(
                f"groundlang check: {len(corpus.skipped)} inconsistent demonstrations "
                "(use --skip-inconsistent to skip them)",
                file=sys.stderr,
            )
            ok = False
    if args.labels:
        cov = label_coverage(corpus, labels, library)  # labels may name the library's own PFs
        print(f"labelled: {cov.labelled}/{cov.total} files ({len(labels)} prefixes in {labels.path.name})")
        print(f"goal holds in final state: {cov.holding}/{cov.labelled}")
        for inst, goal in cov.failing:
            print(f"  {inst.path}: goal {' '.join(map(str, goal))} does not hold in the final state")
        if cov.failing:
            ok = False
    return 0 if ok else 1


def _layouts_not_keyed(corpus) -> list[str]:
    """``FILE: why`` for each initial state's layout (and toy count) whose states, every object moving, do not
    fit a 64-bit key (``model.state_search.key_powers``), the first file of each: more objects than its cells
    allow. Whether train refuses it depends on which toys a likelihood must move there (a warning)."""
    from groundlang.model.state_search import StateKeyError, key_powers

    first: dict = {}
    for inst in corpus.instances:
        first.setdefault((inst.initial_state.layout, len(inst.initial_state.toys)), inst)
    out = []
    for inst in first.values():
        state = inst.initial_state
        try:
            key_powers(int(state.layout.walkable.sum()), 1 + len(state.toys))
        except StateKeyError as exc:
            out.append(f"{inst.path}: {exc}")
    return out


def _tabulate_layouts(corpus, library) -> None:
    """A library given is checked in each layout of the corpus as train would meet it (model.tasks.check_library_at):
    what its PF rules get wrong only in a layout is refused here, by the library's file and the corpus file."""
    from groundlang.model.tasks import check_library_at

    for inst in {i.initial_state.layout: i for i in corpus.instances}.values():
        check_library_at(inst.initial_state, library, str(inst.path))
