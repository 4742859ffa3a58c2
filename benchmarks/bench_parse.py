"""Benchmark: commands parsed per second on the commands-to-tasks corpus (goal: all 480 in < 2 s, one core).

Prints, per folder and for both together: commands, full parses vs fallback-only, and commands/second,
cold (a fresh Earley tree cache, the parser already built) and warm (trees cached, weights re-applied).
Run: .venv/bin/python benchmarks/bench_parse.py [CORPUS_DIR]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from groundlang.grammar import parser

DEFAULT_CORPUS = Path(__file__).resolve().parents[2] / "shared" / "data" / "commands-to-tasks"


def first_lines(folder: Path) -> list[str]:
    out = []
    for path in sorted(folder.glob("*.txt")):
        with open(path, encoding="utf-8", errors="replace") as fh:
            out.append(fh.readline().strip())
    return out


def timed(commands: list[str]) -> tuple[float, int]:
    start = time.process_time()
    full = sum(not parser.parse(c)[0].logical_form.fallback for c in commands)
    return time.process_time() - start, full


def main() -> int:
    corpus = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_CORPUS
    folders = [corpus / "allTurkTrain", corpus / "allTurkTrainLimitedCommand"]
    if not all(f.is_dir() for f in folders):
        print(f"corpus not found under {corpus}")
        return 1
    t0 = time.process_time()
    parser.parse("push the star into the green room")  # builds the Earley parser once
    print(f"build parser: {time.process_time() - t0:.3f} s cpu")
    every: list[str] = []
    for folder in folders:
        commands = first_lines(folder)
        every += commands
        parser._parse_tree.cache_clear()
        secs, full = timed(commands)
        print(f"{folder.name:28s} {len(commands)} commands: {full} full parse, {len(commands) - full} fallback only; "
              f"{secs:.2f} s cpu, {len(commands) / secs:.0f} commands/s (cold)")
    parser._parse_tree.cache_clear()
    cold, full = timed(every)
    warm, _ = timed(every)
    print(f"{'both':28s} {len(every)} commands: {full} full parse; cold {cold:.2f} s cpu "
          f"({len(every) / cold:.0f}/s), warm {warm:.2f} s ({len(every) / warm:.0f}/s), warm/cold {warm / cold:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
