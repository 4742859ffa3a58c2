"""``groundlang train CORPUS --palette NAME -o MODEL_DIR [--language-model NAME]``: fit and save a learner."""

from __future__ import annotations

import argparse
import time

from groundlang.bdm import bdm_files
from groundlang.corpus import read_corpus
from groundlang.commands import (LANGUAGE_MODEL_NAMES, LIBRARY_NAMES, PALETTE_HELP, add_em_acceleration_option, input_path,
                                 add_language_model_settings, add_lexicon_option, cache_option, check_cache_outside,
                                 language_model_settings, library_given, library_path, output_path, require_palette,
                                 seed, add_time_limit_option, time_limit_given, lexicon_beside)


def register(subparsers) -> None:
    p = subparsers.add_parser("train", help="learn word meanings from a corpus and save the model")
    p.add_argument("corpus", type=input_path, metavar="CORPUS", help="folder of corpus files (*.txt), or a .bdm file or folder of them "
                   "(Williams et al. 2018: (start, end) pairs, learned from as evaluate does)")
    p.add_argument("--palette", help=PALETTE_HELP + " (required but for .bdm, whose default is williams2018)")
    p.add_argument("-o", "--output", required=True, type=output_path, metavar="MODEL_DIR", help="folder to write the model to")
    p.add_argument("--language-model", default="parse", choices=list(LANGUAGE_MODEL_NAMES), help="language model: bow, ibm2 or parse (default parse)")
    add_language_model_settings(p)
    add_lexicon_option(p)
    add_time_limit_option(p)
    p.add_argument("--library", metavar="LP", action="append", type=library_path, help="task library .lp file (repeatable; default: groundlang's tasks.lp, for .bdm the "
                   "williams2018 domain)" + LIBRARY_NAMES)
    p.add_argument("--format", choices=("commands-to-tasks", "williams2018"),
                   help="the corpus format (default: williams2018 for .bdm files, else commands-to-tasks)")
    p.add_argument("--skip-inconsistent", action="store_true", help="skip demonstrations (or .bdm pairs) that do not replay under the dynamics, and .bdm pairs whose start state admits no task, instead of stopping")
    p.add_argument("--cache-dir", metavar="DIR", help="cache of behaviour likelihoods and .bdm pairs' end-state evidence "
                   "(default $GROUNDLANG_CACHE or ./.groundlang-cache)")
    p.add_argument("--no-cache", action="store_true", help="do not read or write that cache")
    p.add_argument("--seed", type=seed, default=0, help="seed of the fit (default 0; training is deterministic)")
    add_em_acceleration_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from groundlang.learner import Learner
    from groundlang.model.domain_words import extra_words
    from groundlang.model.language_models import get_language_model

    from groundlang.model_io import check_model_destination

    check_model_destination(args.output, "-o")  # before training, not after it
    check_cache_outside(cache_option(args), args.output)
    words = extra_words(args.lexicon)  # a malformed word file stops here, before the corpus is read
    lm = get_language_model(args.language_model, **language_model_settings(args.lm_settings))  # and a setting
    cache_option(args)
    started = time.perf_counter()
    pairs = args.format == "williams2018" or (args.format is None and bdm_files(args.corpus))
    instances, library = _pairs(args) if pairs else (None, None)
    if instances is None:
        require_palette(args, args.corpus)
        corpus = read_corpus(args.corpus, args.palette, skip_inconsistent=args.skip_inconsistent)
        if corpus.skipped:
            print(f"skipped {len(corpus.skipped)} inconsistent demonstrations")
        instances = corpus.instances
        library = library_given(args)
    lexicon_beside(args, library)
    learner = Learner(lm, library=library, seed=args.seed, lexicon=words, cache_dir=cache_option(args),
                      em_acceleration=args.em_acceleration)
    learner.fit(instances, progress=args.progress)
    learner.save(args.output)
    fit = learner.fit_result
    print(
        f"trained {args.language_model} on {len(instances)} instances in {time.perf_counter() - started:.1f} s "
        f"({fit.steps} EM steps, {'converged' if fit.converged else 'not converged'}); "
        f"model written to {args.output}"
    )
    return 0


def _pairs(args: argparse.Namespace):
    """The training instances of a .bdm corpus (one per command, its pairs sharing one meaning) and its
    library (the package's williams2018 domain unless --library)."""
    from groundlang.bdm import DEFAULT_PALETTE
    from groundlang.bdm_check import default_library
    from groundlang.pair_corpus import read_pair_corpus, skipped_text, training_instances

    library = default_library(args.library, **time_limit_given(args))
    commands = read_pair_corpus(args.corpus, args.palette or DEFAULT_PALETTE, args.format == "williams2018").commands
    made = training_instances(commands, library, skip_inconsistent=args.skip_inconsistent, cache_dir=cache_option(args))
    skipped = skipped_text(made.skipped_counts())
    if not made.instances:
        raise ValueError(f"{args.corpus}: no usable training pair (every pair was skipped: {skipped or 'none read'})")
    print(f"{len(commands)} commands, {sum(len(i.pairs) for i in made.instances)} pairs used"
          + (f"; pairs skipped: {skipped}" if skipped else ""))
    return made.instances, library
