"""``groundlang discover DIR --palette NAME -o tasks.lp [--restrict [--pfs LP]] [--json]``: discover a task library.

No task library, no labels, no words: MLIRL over every position PF of each
distinct demonstration, the top-weighted PFs lifted to typed variables, and
the lifted tasks that best compress all demonstrations kept (see
:mod:`groundlang.inference.discovery`). Writes the library as commented ASP
(loadable with ``groundlang tasks FILE --library tasks.lp``) and prints, per
distinct demonstration, the top MLIRL features and the task and grounding
that explain it; ``--json`` prints
``{"output": "tasks.lp", "lifted_tasks": [{"name", "task", "variables", "goal", "demonstrations"}],
"score": ..., "alternatives": [...], "demonstrations": [...], "seconds": ...}``.
"""

from __future__ import annotations

import argparse
import time

from groundlang.commands import (input_path, PALETTE_HELP, add_time_limit_option, cache_option, fraction, inputs_read, json_text,
                                 output_path, positive_int, time_limit_given)


def register(subparsers) -> None:
    p = subparsers.add_parser("discover", help="discover lifted tasks from a corpus's demonstrations")
    p.add_argument("directory", type=input_path, metavar="DIR", help="a corpus folder (one instance per *.txt file)")
    p.add_argument("--palette", required=True, help=PALETTE_HELP)
    p.add_argument("-o", "--output", required=True, type=output_path, metavar="LP", help="where to write the discovered library (.lp)")
    p.add_argument("--weight-margin", type=fraction, default=0.5, metavar="FRACTION",
                   help="top features: MLIRL weight at least this fraction of the largest, above 0 up to 1 (default 0.5)")
    p.add_argument("--max-conjuncts", type=positive_int, default=2, metavar="N",
                   help="candidate goals: conjunctions of up to N top features (default 2)")
    p.add_argument("--max-tasks", type=positive_int, default=4, metavar="N", help="largest library considered (default 4)")
    p.add_argument("--cache-dir", metavar="DIR",
                   help="behaviour-likelihood cache (default $GROUNDLANG_CACHE or ./.groundlang-cache)")
    p.add_argument("--no-cache", action="store_true", help="do not read or write the behaviour-likelihood cache")
    p.add_argument("--restrict", action="store_true",
                   help="restrict each task variable by the colour/shape PFs that single out its object "
                        "in every demonstration the task explains (restrict/3 facts)")
    p.add_argument("--pfs", type=input_path, metavar="LP", action="append",
                   help="an .lp file of your own PFs (pf/3, holds/2): its position PFs are candidate goals "
                        "and its colour and shape families tell objects apart in the report and for --restrict, "
                        "besides pfs.lp's (repeatable; load it beside the written library)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    add_time_limit_option(p, "stop grounding/solving the --pfs files in a layout after this long (default 10; "
                             "only with --pfs: the package's own PFs are not grounded under it)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from groundlang.corpus import read_corpus
    from groundlang.inference.discovery import DiscoverySettings, discover_tasks, write_library
    from groundlang.logic.tasks import TaskLibrary
    from groundlang.logic.storage import check_destination

    if args.weight_margin == 0:  # a fraction of the largest weight: 0 would keep every feature, and is refused
        raise ValueError("--weight-margin 0: expected a fraction above 0, up to 1 (of the largest MLIRL weight)")

    start = time.perf_counter()
    check_destination(args.output, "-o", inputs_read(args, "directory", "pfs", "palette", "lexicon"))
    cache = cache_option(args)
    if args.time_limit is not None and not args.pfs:  # refused, not ignored: only a --pfs file is grounded under it
        raise ValueError("--time-limit: discover grounds a --pfs file of yours under it; without --pfs there is "
                         "none (the package's PFs ground at once)")
    pfs = TaskLibrary.load(args.pfs, **time_limit_given(args)) if args.pfs else None  # a bad file: before any work
    corpus = read_corpus(args.directory, args.palette)
    if not corpus.instances:
        raise ValueError(f"{args.directory}: no corpus files (*.txt) found")
    settings = DiscoverySettings(weight_margin=args.weight_margin, max_conjuncts=args.max_conjuncts,
                                 max_tasks=args.max_tasks, restrict=args.restrict)
    quiet = args.json or getattr(args, "quiet", False)
    discovery = discover_tasks(corpus.instances, settings, cache_dir=cache, progress=not quiet and getattr(args, "progress", False), pfs=pfs)
    path = write_library(discovery, args.output)
    seconds = time.perf_counter() - start
    if args.json:
        print(json_text({"output": str(path), **discovery.to_json(), "seconds": seconds}))
        return 0
    print(f"{len(corpus.instances)} instances, {len(discovery.demonstrations)} distinct demonstrations")
    for r in discovery.demonstrations:
        more = f" (+{len(r.instances) - 1})" if len(r.instances) > 1 else ""
        print(f"{r.instances[0]}{more}: {r.num_states} states")
        print("  top features: " + ", ".join(f"{a} {w:.2f}" for a, w in r.top_features))
        if r.task is None:
            print("  explained by no discovered task")
        else:
            print(f"  {r.task}: {r.grounding.goal_text} (log-likelihood {r.log_likelihood:.3f})")
    print(f"lifted tasks ({len(discovery.tasks)}), score {discovery.score:.3f} nats:")
    for t in discovery.tasks:
        print(f"  {t}")
    if len(discovery.alternatives) > 1:
        names, score = discovery.alternatives[1]
        print(f"runner-up: {', '.join(names)} ({score:.3f} nats)")
    print(f"written: {path}")
    print(f"seconds: {seconds:.2f}")
    return 0
