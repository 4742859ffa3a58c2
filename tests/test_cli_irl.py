"""``groundlang irl``: MLIRL weights over position PFs of one corpus file."""

from __future__ import annotations

import csv
import json

import pytest

from groundlang.cli import main
from groundlang.logic.atoms import parse_atom, parse_goal

PREFIXES = ["agent2orange_", "agent2tan_", "agent2teal_", "star2orange_", "star2tan_",
            pytest.param("star2teal_", marks=pytest.mark.xfail(
                reason="the block ends on (3,3), both a door0 cell and inside room2: toyInDoor(block0, door0) "
                       "and toyInRoom(block0, room2) first hold together and tie within 1%", strict=False))]


@pytest.mark.parametrize("prefix", PREFIXES)
def test_irl_ranks_the_gold_atom_first(shared_corpus, prefix, capsys):
    with open(shared_corpus / "labels.csv") as f:
        gold = {row["prefix"]: parse_goal(row["goal"]) for row in csv.DictReader(f)}
    assert main(["irl", str(shared_corpus / "allTurkTrain" / f"{prefix}0.txt"), "--palette", "sokoban", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) >= {"weights", "log_likelihood", "states", "seconds"}
    ranked = list(out["weights"])
    assert parse_atom(ranked[0]) == gold[prefix][0]
    assert out["states"] in (70, 4830) and out["log_likelihood"] < 0


def test_irl_table_output(shared_corpus, capsys):
    assert main(["irl", str(shared_corpus / "allTurkTrain" / "agent2orange_0.txt"), "--palette", "sokoban"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("agentInRoom(agent0, room1) ")
    assert any(line.startswith("states: 70") for line in lines)


def test_irl_missing_file_is_exit_code_2(tmp_path, capsys):
    assert main(["irl", str(tmp_path / "nope.txt"), "--palette", "sokoban"]) == 2
    assert "groundlang irl: error" in capsys.readouterr().err
