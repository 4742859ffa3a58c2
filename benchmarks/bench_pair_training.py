"""Training on the Williams et al. (2018) corpus from a cold and from a warm cache, side by side (issue 21).

Prints, for every command of ``../shared/data/williams2018/train`` (or ``--corpus``):
- the end-state evidence of every pair (``pair_corpus.training_instances``) into an empty cache folder
  (cold; a pair that repeats within the corpus is computed once) and from the filled folder (warm);
  with ``--uncached``, first, every pair computed anew, as before the cache (``LayoutEvidence`` per pair;
  it alone pays the layouts' groundings and PF tables, which the process keeps for the lines after);
- the fit of the joint model on those instances (``Learner.fit``: interpretations, parses, behaviour
  terms, the bag-of-words start and the parse model's EM) with the parse cache empty (cold) and filled
  (warm), EM steps chained by SQUAREM (the default), and, beside it, by plain EM;
- one EM step's words terms and their gradient (the parse model's ``words_by_reading``), computed in
  parts of one width (``ParseBatch.by_width``) and over the whole padded batch, side by side;
- training's total cold and warm (evidence + fit), their ratio, and the load average.

Skips, saying so, where the corpus is absent. No timing asserts.
Usage: python benchmarks/bench_pair_training.py [--corpus DIR] [--limit N] [--no-fit] [--uncached]
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import tempfile
import time
from pathlib import Path

from groundlang.bdm_check import default_library
from groundlang.inference.end_states import EndStateNoise
from groundlang.inference.shared_meaning import LayoutEvidence
from groundlang.learner import Learner
from groundlang.pair_corpus import read_pair_corpus, training_instances
from groundlang.pair_tasks import REACHABILITY_MAX_STATES

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "williams2018" / "train"


def timed(call):
    started = time.perf_counter()
    value = call()
    return value, time.perf_counter() - started


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--corpus", type=Path, default=SHARED, help="a .bdm file or folder (default the shared corpus)")
    parser.add_argument("--limit", type=int, help="the first N commands only")
    parser.add_argument("--no-fit", action="store_true", help="time the evidence only")
    parser.add_argument("--uncached", action="store_true", help="also time the evidence of every pair computed anew")
    args = parser.parse_args()
    if not args.corpus.exists():
        print(f"(Williams et al. 2018 corpus not found at {args.corpus}: skipped)")
        return 0
    logging.getLogger("groundlang").setLevel(logging.WARNING)
    library = default_library()
    commands = read_pair_corpus(args.corpus).commands[: args.limit]
    print(f"{len(commands)} commands, {sum(len(c.pairs) for c in commands)} pairs; load average before: "
          f"{os.getloadavg()[0]:.2f}")
    if args.uncached:
        noise = EndStateNoise()
        _, uncached = timed(lambda: [LayoutEvidence(p.start, p.end, library, noise, REACHABILITY_MAX_STATES) for c in commands for p in c.pairs])
        print(f"evidence, every pair anew: {uncached:6.1f} s")
    with tempfile.TemporaryDirectory() as cache:
        made, cold = timed(lambda: training_instances(commands, library, cache_dir=cache))
        again, warm = timed(lambda: training_instances(commands, library, cache_dir=cache))
        print(f"evidence, empty cache:    {cold:7.1f} s")
        print(f"evidence, warm cache:     {warm:7.1f} s   ({cold / warm:.0f}x)")
        if not args.no_fit:
            first, cold_fit = timed(lambda: Learner(library=library, cache_dir=cache).fit(made.instances))
            fast, fit = timed(lambda: Learner(library=library, cache_dir=cache).fit(again.instances))
            plain, plain_fit = timed(lambda: Learner(library=library, cache_dir=cache, em_acceleration="none")
                                     .fit(again.instances))
            print(f"fit, parses not cached: {cold_fit:6.1f} s; cached: {fit:6.1f} s ({fast.fit_result.steps} EM "
                  f"steps); plain EM {plain_fit:6.1f} s ({plain.fit_result.steps} steps): {plain_fit / fit:.2f}x")
            words_terms(fast, again.instances)
            print(f"training cold {cold + cold_fit:.1f} s, warm {warm + fit:.1f} s "
                  f"({(cold + cold_fit) / (warm + fit):.2f}x)")
    print(f"load average after: {os.getloadavg()[0]:.2f} (2 cores)")
    return 0


def words_terms(learner: Learner, instances, rounds: int = 5) -> None:
    """One EM step's words terms and gradient, in parts of one width and over the whole padded batch."""
    from groundlang.inference.joint import single_threaded

    batch = learner.lm.encode(learner.observe(instances), learner.vocab)

    def step(compute):
        leaves = {k: v.detach().clone().requires_grad_(True) for k, v in learner.globals.items()}
        compute(leaves).clamp_min(-1e3).sum().backward()

    with single_threaded():
        times = {}
        for name, compute in (("parts", lambda g: learner.lm.words_by_reading(g, batch)[0]),
                              ("whole", lambda g: learner.lm._words_given_reading(g, batch)[0])):
            step(compute)  # once unmeasured: allocations
            times[name] = min(timed(lambda: step(compute))[1] for _ in range(rounds))
    parts, order = batch.by_width()
    print(f"words terms and gradient, one EM step (best of {rounds}, one thread): {len(parts)} parts of one width "
          f"{times['parts'] * 1e3:.0f} ms, the whole padded batch {times['whole'] * 1e3:.0f} ms "
          f"({times['whole'] / times['parts']:.1f}x)")


if __name__ == "__main__":
    sys.exit(main())
