"""``groundlang evaluate --corpus DIR --palette NAME --labels CSV [--protocol loo|train] ...``."""

from __future__ import annotations

import argparse
import errno
from pathlib import Path

from groundlang.commands import (input_path, LANGUAGE_MODEL_NAMES, LIBRARY_NAMES, PALETTE_HELP, add_em_acceleration_option,
                                 add_language_model_settings, add_lexicon_option, fraction, inputs_read, json_bytes,
                                 language_model_settings, library_given, library_path, open_fraction, output_path,
                                 positive_int, require_palette, add_time_limit_option, time_limit_given, lexicon_beside,
                                 fold_count)
from groundlang.commands.follow import DEFAULT_MIN_CONFIDENCE


def register(subparsers) -> None:
    p = subparsers.add_parser("evaluate", help="accuracy: leave-one-out or train-set against gold labels (*.txt corpus), "
                                                   "or on held-out (start, end) pairs (.bdm corpus: --holdout, --test)")
    p.add_argument("--corpus", required=True, type=input_path, metavar="DIR",
                   help="training corpus: a folder of *.txt files, or a .bdm file or folder of them (Williams 2018)")
    p.add_argument("--palette", help=PALETTE_HELP + " (required but for .bdm, whose default is williams2018)")
    p.add_argument("--labels", type=input_path, metavar="CSV", help="gold labels of a *.txt corpus (required for it)")
    p.add_argument("--test", type=input_path, metavar="BDM", help="a .bdm test file or folder: train on --corpus, follow every test "
                   "command from each of its start states, scored by what its pairs show")
    p.add_argument("--layouts", choices=["shared", "separate"], default="shared",
                   help="a .bdm command's pairs as one instance of one lifted meaning grounded in each layout "
                        "(shared, the default; needs end-state) or each pair as an instance of its own (separate)")
    p.add_argument("--holdout", type=open_fraction, metavar="F",
                   help="instead of --test: hold out the .bdm corpus's commands whose text hashes into a fraction "
                        "F (a development split disjoint by text, the same on every machine)")
    p.add_argument("--folds", type=fold_count, metavar="K",
                   help="instead of --test or --holdout: K folds by text (fold k holds out the texts hashing into "
                        "its K-th of the range, so with 5 fold 0 is --holdout 0.2's split), each trained on the "
                        "others; prints each fold's figures and the pooled ones (--workers folds at once)")
    p.add_argument("--tuning", action="store_true",
                   help="with --holdout F: hold out the next F of the texts and train on the rest beyond it, "
                        "never reading the development split (a split to choose mechanisms on); with --holdout F "
                        "--folds K: K folds over the texts beyond the development split, which none reads")
    p.add_argument("--format", choices=["commands-to-tasks", "williams2018"],
                   help="the corpus format (default: williams2018 for .bdm files, else commands-to-tasks)")
    p.add_argument("--library", metavar="LP", action="append", type=library_path,
                   help="task library .lp file (repeatable; default: groundlang's tasks.lp, for .bdm the package's "
                        "williams2018 domain); labels may use its PFs" + LIBRARY_NAMES)
    p.add_argument("--judge", metavar="LP", action="append", type=library_path,
                   help="for a .bdm corpus: judge what the test pairs show, and each final state, with this task "
                        "library instead of the one learned and followed with (repeatable, as --library): two "
                        "domains compared under one judge, since a domain's descriptions are also the judge's")
    p.add_argument("--demonstrations", choices=["end-state", "shortest-plan"], default="end-state",
                   help="how a (start, end) pair without a trajectory is evidence (default end-state: the end "
                        "state's likelihood under each task; shortest-plan: a synthesised shortest plan)")
    p.add_argument("--protocol", choices=["loo", "train"], help="for a *.txt corpus (default loo)")
    p.add_argument("--novel-envs", metavar="DIR", help="folder of *.state files to execute each command in too")
    p.add_argument("--language-model", default="parse", choices=list(LANGUAGE_MODEL_NAMES), help="language model: bow, ibm2 or parse (default parse)")
    add_language_model_settings(p)
    add_lexicon_option(p)
    add_time_limit_option(p)
    add_em_acceleration_option(p)
    p.add_argument("--workers", type=positive_int, default=1, help="folds in parallel (processes; no more than the folds or the cores; default 1)")
    p.add_argument("--ray", metavar="ADDRESS", help="run folds on a Ray cluster ('auto', 'local' or an address, host:port)")
    p.add_argument("--skip-inconsistent", action="store_true", help="skip demonstrations (or .bdm pairs) that do not replay under the dynamics, and .bdm pairs whose start state admits no task, instead of stopping")
    p.add_argument("--limit", type=positive_int, help="score only the first N held-out instances (a *.txt corpus with labels; a .bdm "
                   "corpus is scored by its test pairs, every one)")
    p.add_argument("--cold-folds", action="store_true",
                   help="fit every leave-one-out fold from scratch instead of from the full model "
                        "(several times slower: each fold's EM starts from the prior)")
    p.add_argument("--min-confidence", type=fraction, default=DEFAULT_MIN_CONFIDENCE, metavar="P",
                   help="report coverage and accuracy of the commands read with confidence P or more, as "
                        f"follow would act on them (default {DEFAULT_MIN_CONFIDENCE}, follow's); predictions unchanged")
    p.add_argument("--json", type=output_path, metavar="OUT", help="write the result as JSON here (with the calibration report: "
                                                 "reliability bins, risk-coverage curve, per-command confidence)")
    p.set_defaults(func=run)


def read_novel_states(directory: str, palette: str) -> list:
    from groundlang.corpus import read_state_file

    if not Path(directory).is_dir():
        raise ValueError(f"--novel-envs {directory}: not a folder (it does not exist or is a file); "
                         "expected a folder of *.state files")
    paths = sorted(Path(directory).glob("*.state"))
    if not paths:
        raise ValueError(f"{directory}: no *.state files for --novel-envs")
    return [(str(p), read_state_file(p, palette)) for p in paths]  # named as a path: errors say which file


def run(args: argparse.Namespace) -> int:
    from groundlang.corpus import read_corpus
    from groundlang.evaluation import evaluate
    from groundlang.labels import check_label_prefixes, read_labels
    from groundlang.model.domain_words import extra_words
    from groundlang.logic.storage import check_destination, write_atomically
    from groundlang.published import comparison, format_comparison

    if args.json:
        check_destination(args.json, "--json", inputs_read(args, "corpus", "test", "labels", "layouts", "library",
                                                           "judge", "novel_envs", "palette", "lexicon"))
    if args.cold_folds and args.protocol == "train":  # it trains once: there are no folds to start cold
        raise ValueError("--cold-folds: the train protocol trains one model, with no folds; it is for loo")
    if not Path(args.corpus).exists():  # else taken for a *.txt corpus, and a pair option named as the fault
        raise FileNotFoundError(errno.ENOENT, "No such file or directory", args.corpus)
    if _is_pairs(args):
        return run_pairs(args)
    if args.test:
        raise ValueError("--test takes a .bdm test file for a .bdm training corpus; a *.txt corpus is "
                         "evaluated by --protocol loo or train")
    given = [f"--{name}" for name, default in _PAIR_OPTIONS.items() if getattr(args, name) != default]
    if given:
        raise ValueError(f"{', '.join(given)}: for a .bdm corpus of (start, end) pairs; {args.corpus} is a *.txt corpus")
    require_palette(args, args.corpus)
    if not args.labels:
        raise ValueError("a *.txt corpus needs --palette and --labels (the gold labels it is scored against)")
    # read here, before any work: a malformed word file is one error line, and workers get the words
    words = extra_words(args.lexicon)
    corpus = read_corpus(args.corpus, args.palette, skip_inconsistent=args.skip_inconsistent)
    labels = read_labels(args.labels)
    check_label_prefixes(corpus, labels)  # as check does: labels of another corpus are refused, not ignored
    novel = read_novel_states(args.novel_envs, args.palette) if args.novel_envs else []
    options = {"em_acceleration": args.em_acceleration, **({"lexicon": words} if words else {})}
    if (library := library_given(args)) is not None:  # trained, followed and scored with the user's PFs and tasks
        options["library"] = library
    lexicon_beside(args, library)
    result = evaluate(
        corpus, labels, protocol=args.protocol or "loo", language_model=args.language_model,
        novel_states=novel, workers=args.workers, ray_address=args.ray,
        progress=args.progress, limit=args.limit, warm_start=not args.cold_folds,
        language_model_settings=language_model_settings(args.lm_settings),
        learner_options=options,
        min_confidence=args.min_confidence,
    )
    print(result.summary())
    # A run of a whole RSS 2015 folder is set beside the published accuracies and the project's goals.
    # Only a whole run compares: no instance left out by --limit, --skip-inconsistent or a failed fold.
    whole = result.n == len(corpus.instances) and not corpus.skipped
    rows = comparison(Path(args.corpus).resolve().name, result) if whole else []
    if rows:
        print(format_comparison(rows))
    if args.json:
        data = result.to_json()
        if rows:
            data["published"] = rows
        write_atomically(Path(args.json), json_bytes(data))
        print(f"result written to {args.json}")
    return 0 if not result.failed_folds else 1


# Options of one corpus format only (name -> default): refused, not ignored, with the other.
_PAIR_OPTIONS = {"holdout": None, "folds": None, "tuning": False, "layouts": "shared", "demonstrations": "end-state",
                 "judge": None}
_TEXT_OPTIONS = ("labels", "novel_envs", "protocol", "limit", "cold_folds", "ray")


def _is_pairs(args) -> bool:
    from groundlang.bdm import bdm_files

    return args.format == "williams2018" or (args.format is None and bool(bdm_files(args.corpus)))


def run_pairs(args: argparse.Namespace) -> int:
    """``evaluate`` on a corpus of (start, end) pairs against a test file (groundlang.pair_evaluation)."""
    from groundlang.bdm import DEFAULT_PALETTE
    from groundlang.bdm_check import default_library
    from groundlang.model.domain_words import extra_words
    from groundlang.pair_corpus import held_out_by_text, read_pair_corpus
    from groundlang.pair_evaluation import evaluate_pairs

    tuning_folds = args.tuning and args.folds is not None and args.holdout is not None and args.test is None
    if not tuning_folds and sum(x is not None for x in (args.test, args.holdout, args.folds)) != 1:
        raise ValueError(f"{args.corpus}: a corpus of (start, end) pairs is evaluated against a test file, a "
                         "held-out split or folds: pass one of --test TEST.bdm, --holdout F and --folds K "
                         "(or --folds K --holdout F --tuning: folds beyond the development split)")
    given = [f"--{name.replace('_', '-')}" for name in _TEXT_OPTIONS if getattr(args, name)]
    if given:
        raise ValueError(f"{', '.join(given)}: for a *.txt corpus with labels; a .bdm corpus is scored by what its "
                         "test pairs show")
    if args.layouts == "shared" and args.demonstrations != "end-state":
        # Said here in the options' names: training_instances would say it in its arguments' (layouts='shared').
        raise ValueError(f"--demonstrations {args.demonstrations}: --layouts shared (the default) multiplies "
                         "end-state evidence across a command's layouts; pass --layouts separate too")
    palette = args.palette or DEFAULT_PALETTE
    words = extra_words(args.lexicon)
    library = default_library(args.library, **time_limit_given(args))
    lexicon_beside(args, library)
    judge = None if args.judge is None else default_library(args.judge, **time_limit_given(args))
    if judge is not None and not judge.tasks:  # it would judge every command to show nothing, after all the work
        raise ValueError(f"--judge {', '.join(args.judge)}: declares no task/1; a judge reads what the pairs show "
                         "through its tasks' relations")
    any_name = args.format == "williams2018"  # said: a file is read whatever its name
    train = read_pair_corpus(args.corpus, palette, any_name).commands
    if args.tuning and args.holdout is None:
        raise ValueError("--tuning splits the training side of --holdout F; pass --holdout too (not --test)")
    if args.folds is not None:
        return _run_folds(args, train, library, _learner_options(args, words), judge)
    if args.test:
        test = read_pair_corpus(args.test, palette, any_name).commands
    else:
        split = "the tuning split" if args.tuning else "the held-out split"
        train, test = held_out_by_text(train, args.holdout, tuning=args.tuning)
        if not test:
            raise ValueError(f"{args.corpus}: --holdout {args.holdout!r} holds out no command (no text falls in "
                             f"{split}); nothing to score: hold out a larger fraction")
        if not train:
            where = "the development or the tuning split" if args.tuning else split
            raise ValueError(f"{args.corpus}: --holdout {args.holdout!r} leaves no command to train on (every text "
                             f"falls in {where}): hold out a smaller fraction")
    result = evaluate_pairs(train, test, library, demonstrations=args.demonstrations,
                            layouts=args.layouts,
                            skip_inconsistent=args.skip_inconsistent, learner_options=_learner_options(args, words),
                            progress=args.progress, min_confidence=args.min_confidence, judge=judge)
    _report(args, result)
    return 0


def _learner_options(args: argparse.Namespace, words) -> dict:
    from groundlang.model.language_models import get_language_model

    options = {"language_model": get_language_model(args.language_model, **language_model_settings(args.lm_settings)),
               "em_acceleration": args.em_acceleration}
    if words:
        options["lexicon"] = words
    return options


def _run_folds(args: argparse.Namespace, commands: list, library, options: dict, judge) -> int:
    """``--folds K``: cross-validation by text (groundlang.pair_folds), the folds in ``--workers`` processes."""
    from groundlang.pair_folds import cross_validate_pairs

    result = cross_validate_pairs(commands, args.folds, library, workers=args.workers,
                                  beyond=args.holdout if args.tuning else 0.0,
                                  min_confidence=args.min_confidence, demonstrations=args.demonstrations,
                                  layouts=args.layouts, skip_inconsistent=args.skip_inconsistent,
                                  learner_options=options, judge=judge)
    _report(args, result)
    return 0


def _report(args: argparse.Namespace, result) -> None:
    from groundlang.logic.storage import write_atomically
    from groundlang.model.language_models import get_language_model

    print(result.summary())
    if args.json:
        # what was trained, as the *.txt protocol's result records it: the figures can be reproduced from the file
        model = get_language_model(args.language_model, **language_model_settings(args.lm_settings))
        data = {**result.to_json(), "language_model": model.name, "language_model_settings": model.settings()}
        write_atomically(Path(args.json), json_bytes(data))
        print(f"result written to {args.json}")
