"""Cross-validation by text on a corpus of (start, end) pairs: ``evaluate --folds K`` (groundlang.pair_folds)."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from groundlang.bdm import read_bdm
from groundlang.confidence import calibration_report
from groundlang.pair_corpus import fold_of_text, held_out_by_text
from groundlang.pair_evaluation import PairEvaluation
from groundlang.pair_folds import fold_indices, pool

SMALL = Path(__file__).parent / "fixtures" / "williams2018" / "small.bdm"


def _many(n: int = 300):
    one = read_bdm(SMALL)[0]
    return [replace(one, text=f"go to room number {k}") for k in range(n)]


def test_five_folds_hold_out_the_development_split_then_the_tuning_split():
    many = _many()
    texts = lambda commands: [c.text for c in commands]
    held = fold_indices(many, 5)
    assert sorted(i for fold in held for i in fold) == list(range(len(many)))  # every command held out once
    assert [many[i].text for i in held[0]] == texts(held_out_by_text(many, 0.2)[1])
    assert [many[i].text for i in held[1]] == texts(held_out_by_text(many, 0.2, tuning=True)[1])
    # a text's copies fall in one fold, wherever they stand in the corpus
    doubled = many + many[::-1]
    assert all(fold_of_text(doubled[i].text, 5) == k for k, fold in enumerate(fold_indices(doubled, 5)) for i in fold)
    assert all(20 < len(fold) < 100 for fold in held)  # a fifth of 300 texts each, roughly
    with pytest.raises(ValueError, match="at least 2"):
        fold_of_text("go", 1)


def _evaluation(rows: list[dict], **counts) -> PairEvaluation:
    fields = dict(train_commands=4, train_pairs=12, train_skipped={"unreachable": 1}, test_commands=2,
                  scored_commands=2, no_task_commands=0, executions_n=4, executions_correct=3, commands_correct=1,
                  unseen_n=4, unseen_correct=3, skipped_executions=0, per_task={"agentInRoom": (3, 4)},
                  failures={"another object": {"agentInRoom": 1}}, seconds_training=1.0, seconds_following=2.0,
                  demonstrations="end-state", layouts="shared")
    return PairEvaluation(**(fields | counts), executions=rows)


def test_pooling_sums_the_folds_and_reads_confidence_again_from_every_row():
    row = lambda index, pair, confidence, correct: {"index": index, "pair": pair, "confidence": confidence,
                                                    "correct": correct}
    # corpus commands 0 and 3 in the first fold, 1 and 2 in the second; command 2's second pair was not scored
    first = _evaluation([row(3, 0, 0.9, True), row(3, 1, 0.4, True), row(0, 0, 0.8, False), row(0, 1, 0.7, True)])
    second = _evaluation([row(1, 0, 0.6, True), row(1, 1, 0.95, True), row(2, 0, 0.2, False),
                          {"index": 2, "pair": 1, "goal": None, "not_scored": "no task"}],
                         per_task={"agentInRoom": (2, 2), "toyInRoom": (0, 1)}, executions_n=3, executions_correct=2,
                         failures={"another object": {"toyInRoom": 1}, "more than the goal": {"toyInRoom": 2}},
                         train_skipped={"unreachable": 2, "too large": 1}, no_task_executions=1)
    pooled = pool([first, second], min_confidence=0.7)
    assert (pooled.executions_n, pooled.executions_correct, pooled.commands_correct) == (7, 5, 2)
    assert pooled.per_task == {"agentInRoom": (5, 6), "toyInRoom": (0, 1)}
    assert pooled.failures == {"another object": {"agentInRoom": 1, "toyInRoom": 1}, "more than the goal": {"toyInRoom": 2}}
    assert pooled.train_skipped == {"unreachable": 3, "too large": 1} and pooled.no_task_executions == 1
    assert [(r["index"], r["pair"]) for r in pooled.executions] == [(0, 0), (0, 1), (1, 0), (1, 1), (2, 0), (2, 1), (3, 0), (3, 1)]
    scored = [r for r in pooled.executions if "correct" in r]
    assert pooled.calibration == calibration_report([r["confidence"] for r in scored], [r["correct"] for r in scored],
                                                    threshold=0.7)
    # per command: the least confident layout, right only when all are (0: 0.7 wrong; 1: 0.6 right; 2: 0.2
    # wrong; 3: 0.4 right)
    assert pooled.command_calibration == calibration_report([0.7, 0.6, 0.2, 0.4], [False, True, False, True],
                                                            threshold=0.7)
    assert pooled.seconds_training == 2.0 and pooled.seconds_following == 4.0


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "groundlang.cli", *args], capture_output=True, text=True, timeout=600)


def test_evaluate_with_folds_pools_rows_numbered_by_the_corpus(tmp_path):
    out = tmp_path / "folds.json"
    run = _cli("evaluate", "--corpus", str(SMALL), "--folds", "2", "--json", str(out))
    assert run.returncode == 0, run.stderr
    assert "2 folds by text" in run.stdout and "pooled over the folds:" in run.stdout
    assert "per execution: 100.00% (6/6" in run.stdout
    data = json.loads(out.read_text())
    commands = read_bdm(SMALL)
    rows = data["executions"]
    # each command held out by the fold its text falls in, its rows numbered as the file counts commands
    assert [(r["index"], r["pair"], r["fold"]) for r in rows] == [
        (i, k, fold_of_text(commands[i].text, 2)) for i in range(2) for k in range(3)]
    assert [r["command"] for r in rows] == [commands[i].text for i in range(2) for _ in range(3)]
    assert [f["held_out_commands"] for f in data["folds"]] == [1, 1]
    assert [f["train_commands"] for f in data["folds"]] == [1, 1]
    assert data["executions_correct"] == sum(f["executions_correct"] for f in data["folds"]) == 6


@pytest.mark.slow
def test_folds_in_two_processes_give_the_rows_of_one(tmp_path):
    rows = {}
    for workers in ("1", "2"):
        out = tmp_path / f"folds{workers}.json"
        run = _cli("evaluate", "--corpus", str(SMALL), "--folds", "2", "--workers", workers, "--json", str(out))
        assert run.returncode == 0, run.stderr
        rows[workers] = [(r["index"], r["pair"], r["goal"], r["final_state"]) for r in json.loads(out.read_text())["executions"]]
    assert rows["1"] == rows["2"] and len(rows["1"]) == 6


@pytest.mark.parametrize("args, message", [
    (["--folds", "1"], "argument --folds: expected a whole number of folds from 2 to 20, not '1'"),
    (["--folds", "21"], "expected a whole number of folds from 2 to 20, not '21'"),
    (["--folds", "0"], "expected a whole number of folds from 2 to 20, not '0'"),  # it had said "1 or more"
    (["--folds", "2", "--holdout", "0.2"], "pass one of --test TEST.bdm, --holdout F and --folds K"),
    (["--folds", "2", "--test", str(SMALL)], "pass one of --test TEST.bdm, --holdout F and --folds K"),
    (["--folds", "2", "--tuning"], "--tuning splits the training side of --holdout F"),
    # the fixture's two texts hash to about 0.31 and 0.59: of 5 folds, fold 0 holds out neither
    (["--folds", "5"], "fold 0 of 5 holds out no command (no text falls in it): 2 texts in the corpus: use at most 2 folds"),
])
def test_evaluate_with_folds_refuses_in_one_line(args, message):
    run = _cli("evaluate", "--corpus", str(SMALL), *args)
    assert run.returncode == 2 and message in run.stderr, run.stderr
    assert "Traceback" not in run.stderr and len(run.stderr.strip().splitlines()) == 1


def test_folds_are_refused_for_a_text_corpus():
    run = _cli("evaluate", "--corpus", "groundlang/examples", "--palette", "sokoban", "--labels", "x.csv",
               "--folds", "5")
    assert run.returncode == 2 and "--folds: for a .bdm corpus" in run.stderr and "Traceback" not in run.stderr


def test_a_folds_error_stops_the_run_at_that_fold(monkeypatch):
    """A fold's error was said only once every fold had been trained."""
    import groundlang.pair_folds as pair_folds
    from groundlang.pair_folds import cross_validate_pairs

    calls = []

    def failing(train, test, library, **options):
        calls.append(len(test))
        raise ValueError("no usable training pair (every pair was skipped)")

    monkeypatch.setattr(pair_folds, "evaluate_pairs", failing)
    with pytest.raises(ValueError, match=r"^fold 0 of 5: no usable training pair"):
        cross_validate_pairs(_many(), 5, library=None)
    assert len(calls) == 1


def test_folds_beyond_a_development_split_never_read_it(monkeypatch):
    """--folds K --holdout F --tuning: cross-validation to choose mechanisms on, the development split unread."""
    import groundlang.pair_folds as pair_folds
    from groundlang.pair_folds import cross_validate_pairs

    many = _many()
    development = {c.text for c in held_out_by_text(many, 0.2)[1]}
    held = fold_indices(many, 4, beyond=0.2)
    assert not {many[i].text for fold in held for i in fold} & development
    assert sorted(i for fold in held for i in fold) == [i for i, c in enumerate(many) if c.text not in development]
    assert all(40 < len(fold) < 90 for fold in held)  # a quarter of the 240 or so texts beyond it each
    assert fold_of_text(next(iter(development)), 4, beyond=0.2) is None
    with pytest.raises(ValueError, match="beyond=1"):
        fold_of_text("go", 4, beyond=1)

    seen = []

    def recording(train, test, library, **options):
        seen.append(({c.text for c in train}, {c.text for c in test}))
        raise ValueError("stop")

    monkeypatch.setattr(pair_folds, "evaluate_pairs", recording)
    with pytest.raises(ValueError, match="stop"):
        cross_validate_pairs(many, 4, library=None, beyond=0.2)
    train, test = seen[0]
    assert not (train | test) & development and not train & test
    assert train | test == {c.text for c in many} - development


def test_evaluate_with_tuning_folds_says_what_it_set_aside(tmp_path):
    # the fixture's two texts hash to about 0.31 and 0.59: beyond 0.05, two folds cut [0.05, 0.525) and [0.525, 1)
    out = tmp_path / "tuning_folds.json"
    run = _cli("evaluate", "--corpus", str(SMALL), "--folds", "2", "--holdout", "0.05", "--tuning", "--json", str(out))
    assert run.returncode == 0, run.stderr
    assert "but the development split's (the texts hashing into the first 0.05 of the range), which no fold reads" in run.stdout
    data = json.loads(out.read_text())
    assert data["development_split_set_aside"] == 0.05 and [f["held_out_commands"] for f in data["folds"]] == [1, 1]
    # set aside 0.35, the text at 0.31 is in the development split and the one at 0.59 alone in the folds (in
    # fold 0): one line, nothing trained
    run = _cli("evaluate", "--corpus", str(SMALL), "--folds", "2", "--holdout", "0.35", "--tuning")
    assert run.returncode == 2 and run.stderr.count("\n") == 1, run.stderr
    assert ("fold 0 of 2 holds out every command beyond the development split (its one text hashes into that "
            "fold): nothing to train on") in run.stderr
    for holdout, folds, message in [("0.6", "2", "no text hashes beyond the development split (the first 0.6 of "
                                     "the range): nothing to cross-validate; set aside a smaller --holdout"),
                                    ("0.05", "3", "2 texts beyond the development split: use at most 2 folds")]:
        run = _cli("evaluate", "--corpus", str(SMALL), "--folds", folds, "--holdout", holdout, "--tuning")
        assert run.returncode == 2 and message in run.stderr and run.stderr.count("\n") == 1, run.stderr
    run = _cli("evaluate", "--corpus", str(SMALL), "--folds", "2", "--holdout", "0.05", "--tuning", "--test", str(SMALL))
    assert run.returncode == 2 and "pass one of --test TEST.bdm, --holdout F and --folds K" in run.stderr, run.stderr


def test_a_fold_holding_every_text_says_how_many(monkeypatch):
    from groundlang.pair_folds import cross_validate_pairs

    two = [c for c in _many() if fold_of_text(c.text, 2) == 0][:2]
    with pytest.raises(ValueError, match=r"^fold 0 of 2 holds out every command in the corpus \(its 2 texts all hash "
                                         r"into that fold\): nothing to train on$"):
        cross_validate_pairs(two, 2, library=None)
