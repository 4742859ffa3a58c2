"""Benchmark: commands parsed per second on the commands-to-tasks corpus (goal: all 480 in < 2 s, one core).

Prints, per folder and for both together: commands, full parses vs fallback-only, CPU seconds and
commands/second, cold (empty forest cache, the parser already built) and warm (forests cached, weights
re-applied). Side by side in the same run, for the whole corpus cold: without sharing forests between
sentences of the same class sequence, and with lark's own Earley predictor (grammar.earley not
installed). Prints /proc/loadavg before and after: other processes share this machine.
Run: .venv/bin/python benchmarks/bench_parse.py [CORPUS_DIR]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from groundlang.grammar import earley, parser
from groundlang.model.domain_words import domain_lexicon
from groundlang.published import CORPUS_VARIABLE, crowd_corpus_path

WORDS = domain_lexicon()  # the words a learner parses the corpus with

DEFAULT_CORPUS = crowd_corpus_path(Path(__file__).resolve().parents[1])


def first_lines(folder: Path) -> list[str]:
    out = []
    for path in sorted(folder.glob("*.txt")):
        with open(path, encoding="utf-8", errors="replace") as fh:
            out.append(fh.readline().strip())
    return out


def loadavg() -> str:
    try:
        return Path("/proc/loadavg").read_text().strip()
    except OSError:
        return "n/a"


def timed(commands: list[str], share_forests: bool = True) -> tuple[float, int]:
    """CPU seconds to parse every command (forest cache cleared first), and how many parsed fully."""
    parser._parse_forest.cache_clear()
    full = 0
    start = time.process_time()
    for c in commands:
        if not share_forests:
            parser._parse_forest.cache_clear()
        full += not parser.parse(c, word_lexicon=WORDS)[0].logical_form.fallback
    return time.process_time() - start, full


def long_commands() -> None:
    """Parsing time against command length, side by side: 8 times the sentences should cost about 8 times
    the time (it cost 64 times when composing a logical form was quadratic)."""
    sentence = "take the star to the green room and go to the blue room ."
    parser.parse(sentence, word_lexicon=WORDS)
    times = {}
    for n in (200, 1600):
        command = " ".join([sentence] * n) + " go to purple."
        t0 = time.process_time()
        parser.parse(command, word_lexicon=WORDS)
        times[n] = time.process_time() - t0
    print(f"long commands: 200 sentences {times[200]:.2f} s cpu, 1600 sentences {times[1600]:.2f} s cpu: "
          f"{times[1600] / times[200]:.1f}x for 8x the words (linear: 8x, quadratic: 64x)")


def many_multiword_entries() -> None:
    """Joining multiword entries against the size of a word file, side by side: ten times the entries that
    share a first word should cost about the same (each position walks one entry's words, not every entry
    with its first word; 60,000 entries and a 10,000-word command took minutes when it did)."""
    tokens = ["the", "side", "of", "it"] * 2500  # no entry fits: the costly case for a list of entries
    times = {}
    for n in (6000, 60000):
        words = WORDS.extend({"PREP": [f"the side{i} of" for i in range(n)]})
        t0 = time.process_time()
        words.join_multiword(tokens)
        times[n] = time.process_time() - t0
    print(f"multiword entries: 6,000 {times[6000] * 1e3:.1f} ms cpu, 60,000 {times[60000] * 1e3:.1f} ms cpu for "
          f"{len(tokens)} words: {times[60000] / times[6000]:.1f}x for 10x the entries (a trie: 1x, a list: 10x)")


def long_hues() -> None:
    """Splitting a solid colour compound against the length of a word file's longest hue, side by side: ten
    times the length should cost about ten times as much (cuts only at hue lengths; every cut of the word,
    each a slice, was quadratic: an 80,000-letter hue took seconds a word)."""
    times = {}
    for n in (20_000, 200_000):
        hue = "a" * n
        words = WORDS.extend({"HUE": [hue]})
        t0 = time.process_time()
        assert words.split_compound_colour(hue + "red") == (hue, "red")
        times[n] = time.process_time() - t0
    print(f"colour compounds: a 20,000-letter hue {times[20_000] * 1e3:.2f} ms cpu, 200,000 letters "
          f"{times[200_000] * 1e3:.2f} ms cpu: {times[200_000] / times[20_000]:.1f}x for 10x the length "
          "(linear: 10x, quadratic: 100x)")


def main() -> int:
    long_commands()  # needs no corpus
    many_multiword_entries()
    long_hues()
    given = len(sys.argv) > 1
    corpus = Path(sys.argv[1]) if given else DEFAULT_CORPUS
    folders = [corpus / "allTurkTrain", corpus / "allTurkTrainLimitedCommand"]
    if not all(f.is_dir() for f in folders):
        if given:  # a path the user typed: a mistake, not an absent optional corpus
            print(f"corpus not found under {corpus}", file=sys.stderr)
            return 1
        print(f"(crowd corpus not found under {corpus}: skipped; give its folder as the argument or in "
              f"${CORPUS_VARIABLE})")
        return 0
    print(f"loadavg before: {loadavg()}")
    t0 = time.process_time()
    parser.parse("push the star into the green room", word_lexicon=WORDS)  # builds the Earley parser once
    print(f"build parser: {time.process_time() - t0:.3f} s cpu")
    every: list[str] = []
    for folder in folders:
        commands = first_lines(folder)
        every += commands
        secs, full = timed(commands)
        print(f"{folder.name:28s} {len(commands)} commands: {full} full parse, {len(commands) - full} fallback only; "
              f"{secs:.2f} s cpu, {len(commands) / secs:.0f} commands/s (cold)")
    cold, full = timed(every)
    start = time.process_time()
    for c in every:  # forests now cached
        parser.parse(c, word_lexicon=WORDS)
    warm = time.process_time() - start
    n = len(every)
    print(f"{'both':28s} {n} commands: {full} full parse; cold {cold:.2f} s cpu ({n / cold:.0f}/s), "
          f"warm {warm:.2f} s ({n / warm:.0f}/s), warm/cold {warm / cold:.2f}")
    unshared, _ = timed(every, share_forests=False)
    lark_earley = parser._earley()[0].parser.parser
    del lark_earley.predict_and_complete  # lark's own method again
    try:
        own, _ = timed(every)
    finally:
        earley.install(lark_earley)
    print(f"{'both, no forest sharing':28s} cold {unshared:.2f} s cpu ({n / unshared:.0f}/s), "
          f"{unshared / cold:.2f}x the cold time")
    print(f"{'both, lark own predictor':28s} cold {own:.2f} s cpu ({n / own:.0f}/s), {own / cold:.2f}x the cold time")
    print(f"loadavg after: {loadavg()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
