"""``groundlang ablate --corpus DIR --palette NAME --labels CSV [--language-models ...] [--sizes ...] ...``, or
``groundlang ablate --held-out-likelihood --corpus DIR --palette NAME --switch NAME [--switch NAME=VALUE ...]``."""

from __future__ import annotations

import argparse
from pathlib import Path

from groundlang.commands import (input_path, PALETTE_HELP, add_language_model_settings, add_lexicon_option, inputs_read,
                                 json_bytes, language_model_settings, output_path, positive_int, seed)


def _list_of(example: str):
    """An argparse type: a comma-separated list of names, its message giving ``example``."""
    def names(text: str) -> list[str]:
        # once each, in the order given: "bow,bow" had made the same cells twice (sizes were already once each)
        found = list(dict.fromkeys(x.strip() for x in text.split(",") if x.strip()))
        if not found:
            raise argparse.ArgumentTypeError(f"expected a comma-separated list, e.g. {example}")
        return found
    return names


def _sizes(text: str) -> list[int]:
    try:
        sizes = [int(x) for x in _list_of("24,60,120,240")(text)]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, e.g. 24,60,120,240; got {text!r}")
    return sizes


def _at_least_two(text: str) -> int:
    try:
        value = positive_int(text)
    except argparse.ArgumentTypeError:
        value = 0
    if value < 2:  # folds: one fold would train on nothing it is scored against
        raise argparse.ArgumentTypeError(f"expected a whole number of 2 or more, not {text!r}")
    return value


def register(subparsers) -> None:
    p = subparsers.add_parser("ablate", help="accuracy over language models x task libraries x training sizes, "
                                             "or held-out likelihood of settings switched")
    p.add_argument("--corpus", required=True, type=input_path, metavar="DIR", help="folder of corpus files (*.txt)")
    p.add_argument("--palette", required=True, help=PALETTE_HELP)
    p.add_argument("--labels", type=input_path, metavar="CSV",
                   help="gold labels (prefix,goal) the corpus is scored against (not with --held-out-likelihood)")
    p.add_argument("--language-models", type=_list_of("bow,ibm2,parse"), metavar="LIST",
                   help="comma-separated: bow,ibm2,parse (default: all three; with --held-out-likelihood one, parse)")
    p.add_argument("--held-out-likelihood", action="store_true",
                   help="instead of the grid: per --switch, the held-out log-likelihood of the demonstrations given "
                        "the words (what chooses), of words and demonstrations and of words alone, with the default "
                        "and with the other value (no labels used)")
    p.add_argument("--switch", action="append", default=[], metavar="NAME[=VALUE]", dest="switches",
                   help="with --held-out-likelihood: a setting of the language model to switch; NAME alone for a "
                        "true/false setting (its other value), else NAME=VALUE (repeatable)")
    p.add_argument("--folds", type=_at_least_two, default=None,
                   help="with --held-out-likelihood: folds, instance n in fold n mod FOLDS (default 10)")
    p.add_argument("--libraries", type=_list_of("authored,discovered"), default=None, metavar="LIST",
                   help="comma-separated: authored,discovered (default: both)")
    p.add_argument("--sizes", type=_sizes, metavar="LIST",
                   help="training sizes, e.g. 24,60,120,240 (default: the whole corpus)")
    p.add_argument("--protocol", default=None, choices=["loo", "train"],
                   help="loo: unseen commands (held-out remainder below the full size); train: training commands (default loo)")
    p.add_argument("--seed", type=seed, default=None, help="seed of the training subsets (default 0)")
    p.add_argument("--workers", type=positive_int, default=None, help="folds in parallel (processes; no more than the folds or the cores; default 1)")
    p.add_argument("--ray", metavar="ADDRESS", help="run cells on a Ray cluster ('auto', 'local' or an address, host:port)")
    p.add_argument("--skip-inconsistent", action="store_true", help="skip demonstrations that do not replay under the dynamics instead of stopping")
    p.add_argument("--limit", type=positive_int, help="score only the first N instances of each cell")
    add_language_model_settings(p)
    add_lexicon_option(p)
    p.add_argument("--json", type=output_path, metavar="OUT", help="write the rows as JSON here")
    p.add_argument("--plot", type=output_path, metavar="PNG", help="write a plot of accuracy by cell here (.png, .svg or .pdf)")
    p.set_defaults(func=run)


def write_plot(result, path: Path) -> None:
    """Save the ablation plot atomically, in the format of the path's suffix (png, svg or pdf)."""
    import matplotlib

    matplotlib.use("Agg")
    import io

    import matplotlib.pyplot as plt

    from groundlang.ablation import plot_ablation
    from groundlang.logic.storage import write_atomically
    from groundlang.render import picture_format

    fig, ax = plt.subplots(figsize=(7, 4.2))
    plot_ablation(result.rows, ax=ax, title=f"{Path(result.corpus).name}, {result.protocol}")
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format=picture_format(path), dpi=120)
    plt.close(fig)
    write_atomically(path, buffer.getvalue())


def run_held_out(args: argparse.Namespace, words: dict) -> int:
    """``--held-out-likelihood``: the table of :func:`groundlang.held_out.format_switches`."""
    from groundlang.corpus import read_corpus
    from groundlang.held_out import compare_switches, format_switches, switch_settings

    models = args.language_models or ["parse"]
    if len(models) != 1:
        raise ValueError(f"--held-out-likelihood: name one language model, not {','.join(models)}")
    if not args.switches:
        raise ValueError("--held-out-likelihood: name at least one --switch, e.g. --switch start_role")
    base = language_model_settings(args.lm_settings)
    args.switches = list(dict.fromkeys(args.switches))  # one row a switch: a repeated one was compared twice
    for switch in args.switches:
        switch_settings(models[0], switch, base)  # every switch checked before the corpus is read
    corpus = read_corpus(args.corpus, args.palette, skip_inconsistent=args.skip_inconsistent)
    folds = args.folds or 10
    rows = compare_switches(corpus.instances, args.switches, models[0], folds,
                            {"lexicon": words} if words else None, base)
    given = f" with {', '.join(f'{k}={v}' for k, v in base.items())}" if base else ""
    print(f"{folds}-fold held-out log-likelihood (nats), {len(corpus.instances)} instances, "
          f"language model {models[0]}{given}")
    print(format_switches(rows))
    if args.json:
        from groundlang.logic.storage import write_atomically

        data = [{"setting": r.setting, "default": r.default, "value": r.value, "favours": r.favours,
                 "default_joint": r.on.joint, "value_joint": r.off.joint, "default_words": r.on.words,
                 "value_words": r.off.words, "default_demonstrations": r.on.demonstrations,
                 "value_demonstrations": r.off.demonstrations} for r in rows]
        write_atomically(Path(args.json), json_bytes({  # what was compared, so the figures can be reproduced
            "folds": folds, "n": len(corpus.instances), "corpus": str(args.corpus), "language_model": models[0],
            "language_model_settings": base, "rows": data}))
        print(f"rows written to {args.json}")
    return 0


def run(args: argparse.Namespace) -> int:
    from groundlang.ablation import run_ablation
    from groundlang.corpus import read_corpus
    from groundlang.labels import check_label_prefixes, read_labels
    from groundlang.model.domain_words import extra_words
    from groundlang.logic.storage import check_destination, write_atomically

    if args.json:
        check_destination(args.json, "--json", inputs_read(args, "corpus", "labels", "libraries", "palette", "lexicon"))
    if args.plot:
        from groundlang.render import check_picture_destination

        reads = inputs_read(args, "corpus", "labels", "libraries", "palette", "lexicon")
        if args.json and Path(args.plot).resolve() == Path(args.json).resolve():
            raise ValueError(f"--plot {args.plot}: the same file as --json {args.json}; the picture would replace "
                             "the rows: name two files")
        check_picture_destination(args.plot, "--plot", reads)
    # An option the mode does not read is refused, not ignored (--libraries discovered had shown the authored's)
    grid_only = {"--labels": args.labels, "--plot": args.plot, "--sizes": args.sizes, "--libraries": args.libraries,
                 "--protocol": args.protocol, "--seed": args.seed, "--workers": args.workers, "--ray": args.ray,
                 "--limit": args.limit}
    if args.held_out_likelihood and (given := [name for name, value in grid_only.items() if value is not None]):
        raise ValueError(f"--held-out-likelihood uses no {', '.join(given)} (they are the grid's)")
    if not args.held_out_likelihood:
        if args.switches:
            raise ValueError("--switch needs --held-out-likelihood (the grid takes --lm-setting)")
        if args.folds is not None:
            raise ValueError("--folds is --held-out-likelihood's (the grid's cells are held out by --protocol)")
        if not args.labels:
            raise ValueError("--labels is required (except with --held-out-likelihood)")
    words = extra_words(args.lexicon)  # read once here: a bad file is one error line, workers get the words
    if args.held_out_likelihood:
        return run_held_out(args, words)
    corpus = read_corpus(args.corpus, args.palette, skip_inconsistent=args.skip_inconsistent)
    labels = read_labels(args.labels)
    # Once, before any cell: a bad labels file had failed every cell of the grid, a row each, exit 1
    check_label_prefixes(corpus, labels)
    if unlabelled := sorted({inst.prefix for inst in corpus.instances if inst.prefix not in labels}):
        raise ValueError(f"{args.labels}: no gold label for the prefix{'es' * (len(unlabelled) > 1)} "
                         f"{', '.join(map(repr, unlabelled[:5]))}{' ...' * (len(unlabelled) > 5)} of {args.corpus}")
    result = run_ablation(
        corpus, labels, language_models=args.language_models or ["bow", "ibm2", "parse"],
        libraries=args.libraries or ["authored", "discovered"],
        sizes=args.sizes,
        protocol=args.protocol or "loo", seed=args.seed or 0, workers=args.workers or 1, ray_address=args.ray,
        progress=args.progress, limit=args.limit, language_model_settings=language_model_settings(args.lm_settings),
        learner_options={"lexicon": words} if words else None,
    )
    print(result.table())
    print(f"wall time {result.seconds:.1f} s")
    if args.json:
        write_atomically(Path(args.json), json_bytes(result.to_json()))
        print(f"rows written to {args.json}")
    if args.plot:
        write_plot(result, Path(args.plot))
        print(f"plot written to {args.plot}")
    return 0 if all(r.error is None and not r.failed_folds for r in result.rows) else 1
