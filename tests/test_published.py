"""The published RSS 2015 accuracies and the project's goals beside a measured result (groundlang.published)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from types import SimpleNamespace

import pytest

from groundlang.cli import main
from groundlang.corpus import example_corpus_path
from groundlang.published import REFERENCES, comparison, format_comparison


def _result(protocol="loo", correct=219, n=240, novel_correct=635, novel_n=720):
    return SimpleNamespace(protocol=protocol, accuracy=correct / n, correct=correct, n=n,
                           novel_accuracy=novel_correct / novel_n if novel_n else None,
                           novel_correct=novel_correct, novel_n=novel_n)


def test_the_original_commands_are_set_against_both_published_rows_and_goals():
    rows = comparison("allTurkTrain", _result())
    assert [(r["setting"], r["best_model"], r["best"], r["goal"], r["goal_correct"], r["reached"]) for r in rows] == [
        ("loo", "IBM Model 2", 0.7416, 0.90, 216, True),
        ("novel environments", "IBM Model 2", 0.7333, 0.90, 648, False),
    ]
    text = format_comparison(rows)
    assert "loo                 91.25% (219/240); published best 74.16% (IBM Model 2); goal 90%: reached" in text
    assert "88.19% (635/720); published best 73.33% (IBM Model 2); goal 90%: not reached (648/720 needed)" in text


def test_the_goal_counts_are_the_smallest_that_reach_it():
    assert comparison("allTurkTrainLimitedCommand", _result(correct=227))[0]["goal_correct"] == 228  # 95% of 240
    assert comparison("allTurkTrainLimitedCommand", _result(correct=228))[0]["reached"]
    assert not comparison("allTurkTrainLimitedCommand", _result(correct=227))[0]["reached"]
    assert REFERENCES["allTurkTrainLimitedCommand"][0].best == ("bag of words", 0.8375)


def test_nothing_is_compared_for_other_corpora_protocols_or_runs_without_novel_layouts():
    assert comparison("examples", _result()) == []
    assert comparison("allTurkTrain", _result(protocol="train")) == []
    assert [r["setting"] for r in comparison("allTurkTrain", _result(novel_n=0))] == ["loo"]
    assert format_comparison([]) == ""


@pytest.mark.slow
def test_cli_evaluate_prints_and_writes_the_comparison_for_a_folder_of_the_rss_corpus(tmp_path, capsys):
    # The shipped example corpus under the simplified folder's name (the comparison keys on the name).
    folder = tmp_path / "allTurkTrainLimitedCommand"
    shutil.copytree(example_corpus_path(), folder)
    out = tmp_path / "r.json"
    code = main(["--quiet", "evaluate", "--corpus", str(folder), "--palette", "sokoban",
                 "--labels", str(Path(example_corpus_path()) / "labels.csv"), "--workers", "2", "--json", str(out)])
    assert code == 0
    printed = capsys.readouterr().out
    assert "against RSS 2015 (Table I) and the project's goals:" in printed
    assert "loo                 100.00% (24/24); published best 83.75% (bag of words); goal 95%: reached" in printed
    published = json.loads(out.read_text())["published"]
    # A partial run (--limit) is not set beside whole-corpus figures.
    main(["--quiet", "evaluate", "--corpus", str(folder), "--palette", "sokoban",
          "--labels", str(Path(example_corpus_path()) / "labels.csv"), "--limit", "5"])
    assert "against RSS 2015" not in capsys.readouterr().out
    assert published == [{"setting": "loo", "accuracy": 1.0, "correct": 24, "n": 24,
                          "published": {"bag of words": 0.8375, "IBM Model 2": 0.8125},
                          "best_model": "bag of words", "best": 0.8375, "goal": 0.95, "goal_correct": 23,
                          "reached": True}]


def test_the_crowd_corpus_is_looked_for_beside_the_clone_or_where_the_variable_says(tmp_path, monkeypatch):
    from groundlang.published import CORPUS_VARIABLE, crowd_corpus_path

    monkeypatch.delenv(CORPUS_VARIABLE, raising=False)
    repo = tmp_path / "groundlang"
    repo.mkdir()
    assert crowd_corpus_path(repo) == tmp_path / "shared" / "data" / "commands-to-tasks"
    monkeypatch.setenv(CORPUS_VARIABLE, str(tmp_path / "elsewhere"))
    assert crowd_corpus_path(repo) == tmp_path / "elsewhere"


@pytest.mark.slow
def test_the_parse_benchmark_skips_without_the_corpus_so_make_bench_runs_the_others(tmp_path):
    import os
    import subprocess
    import sys
    from pathlib import Path

    from groundlang.published import CORPUS_VARIABLE

    bench = Path(__file__).parents[1] / "benchmarks" / "bench_parse.py"
    env = {**os.environ, CORPUS_VARIABLE: str(tmp_path / "missing")}
    run = subprocess.run([sys.executable, str(bench)], capture_output=True, text=True, env=env)
    assert run.returncode == 0, run.stderr
    assert f"crowd corpus not found under {tmp_path / 'missing'}: skipped" in run.stdout
    # a path given on the command line is the user's: missing, it is an error
    run = subprocess.run([sys.executable, str(bench), str(tmp_path / "typo")], capture_output=True, text=True)
    assert run.returncode == 1 and f"corpus not found under {tmp_path / 'typo'}" in run.stderr
