"""Training time of the joint model once behaviour likelihoods are cached (issue 6).

Prints, for each language model, the seconds to fit on the example corpus
and, where the crowd corpus is present (../shared/data/commands-to-tasks or
$GROUNDLANG_CORPUS), on its 240 simplified commands, next
to the seconds the behaviour likelihoods took (first run) and take from the
cache, measured in the same run.

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
        t = time.perf_counter()
        learner.fit(corpus.instances, observations=observations)
        fit = time.perf_counter() - t
        print(f"{name:<34} {lm:<6} {len(corpus):>4} instances  behaviour {first:6.2f} s "
              f"(cached {cached:5.2f} s)  training {fit:6.2f} s  ({learner.fit_result.steps} EM/L-BFGS rounds)")


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
