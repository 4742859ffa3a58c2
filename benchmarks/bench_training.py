"""Training time of the joint model once behaviour likelihoods are cached (issue 6).

Prints, for each language model, the seconds to fit on the example corpus
and, where the crowd corpus is present (../shared/data/commands-to-tasks or
$GROUNDLANG_CORPUS), on its 240 simplified commands, next
to the seconds the behaviour likelihoods took (first run) and take from the
cache, measured in the same run; the fit with EM steps chained by SQUAREM
(the default) beside plain EM (``em_acceleration="none"``), and their ratio.

    python benchmarks/bench_training.py
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

from groundlang.corpus import example_corpus_path, read_corpus
from groundlang.learner import Learner
from groundlang.published import crowd_corpus_path

SHARED = crowd_corpus_path(Path(__file__).resolve().parents[1]) / "allTurkTrainLimitedCommand"


def measure(name: str, corpus, language_models: list[str], cache: str) -> None:
    for lm in language_models:
        learner = Learner(lm, cache_dir=cache)
        t = time.perf_counter()
        observations = learner.observe(corpus.instances)
        first = time.perf_counter() - t
        t = time.perf_counter()
        observations = learner.observe(corpus.instances)
        cached = time.perf_counter() - t
        fits = {}
        for acceleration in ("none", "squarem"):
            learner.em_acceleration = acceleration
            t = time.perf_counter()
            learner.fit(corpus.instances, observations=observations)
            fits[acceleration] = (time.perf_counter() - t, learner.fit_result.steps)
        (plain, plain_steps), (fast, fast_steps) = fits["none"], fits["squarem"]
        print(f"{name:<28} {lm:<6} {len(corpus):>4} instances  behaviour {first:6.2f} s (cached {cached:5.2f} s)  "
              f"training {fast:6.2f} s ({fast_steps} EM steps; plain EM {plain:6.2f} s, {plain_steps} steps: "
              f"{plain / fast:.2f}x)")


def main() -> int:
    models = sys.argv[1:] or ["bow", "parse"]
    with tempfile.TemporaryDirectory() as cache:
        measure("example corpus", read_corpus(example_corpus_path(), "sokoban"), models, cache)
        if SHARED.is_dir():
            measure("allTurkTrainLimitedCommand", read_corpus(SHARED, "sokoban"), models, cache)
        else:
            print(f"(crowd corpus not found at {SHARED}: skipped)")
    print(f"load average: {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
