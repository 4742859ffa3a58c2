"""``groundlang irl``: MLIRL weights over position PFs of one corpus file."""

from __future__ import annotations

import csv
import json

import pytest

from groundlang.cli import main
from groundlang.logic.atoms import parse_atom, parse_goal

PREFIXES = ["agent2orange_", "agent2tan_", "agent2teal_", "star2orange_", "star2tan_", "star2teal_"]


@pytest.mark.parametrize("prefix", PREFIXES)
def test_irl_ranks_the_gold_atom_first(shared_corpus, prefix, capsys):
    with open(shared_corpus / "labels.csv") as f:
        gold = {row["prefix"]: parse_goal(row["goal"]) for row in csv.DictReader(f)}
    assert main(["irl", str(shared_corpus / "allTurkTrain" / f"{prefix}0.txt"), "--palette", "sokoban", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) >= {"weights", "words", "ranking", "log_likelihood", "states", "seconds"}
    assert list(out["words"]) == list(out["weights"])  # every atom said in words, in the same order
    # star2teal: the block ends on (3,3), both a door0 cell and inside room2, so toyInDoor and
    # toyInRoom first hold together and their weights tie within 1%; the ranking breaks the tie by
    # each atom's behaviour likelihood as a goal.
    assert parse_atom(out["ranking"][0]) == gold[prefix][0]
    weights = list(out["weights"].values())
    assert weights == sorted(weights, reverse=True)
    assert out["states"] in (70, 4830) and out["log_likelihood"] < 0


def test_irl_table_output(shared_corpus, capsys):
    assert main(["irl", str(shared_corpus / "allTurkTrain" / "agent2orange_0.txt"), "--palette", "sokoban"]) == 0
    lines = capsys.readouterr().out.splitlines()
    # the file's palette index 1 is the sokoban palette's red (the corpus's folder names say orange)
    assert lines[0] == "most likely goal: the agent in the red room \u2014 agentInRoom(agent0, room1)"
    assert lines[2].split() == ["weight", "proposition", "atom"]
    assert lines[3].split()[1:] == "the agent in the red room agentInRoom(agent0, room1)".split()
    assert any(line.startswith("states: 70") for line in lines)


def test_irl_table_on_the_shipped_examples_has_headings_words_and_ids(capsys):
    from groundlang.corpus import example_corpus_path

    assert main(["irl", str(example_corpus_path() / "star2red_0.txt"), "--palette", "sokoban"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "most likely goal: the yellow star in the red room \u2014 toyInRoom(block0, room1)"
    heading = lines[2]
    assert heading.split() == ["weight", "proposition", "atom"]
    rows = lines[3:lines.index("", 3)]
    assert len(rows) == 13  # every grounded position PF of the layout
    # columns line up under their headings: words start under "proposition", atoms under "atom"
    words_at, atom_at = heading.index("proposition"), heading.index("atom")
    assert rows[0][words_at:atom_at].strip() == "the yellow star in the red room"
    assert rows[0][atom_at:] == "toyInRoom(block0, room1)"
    assert all(row[atom_at - 2:atom_at] == "  " and row[atom_at] != " " for row in rows)
    assert float(rows[0][:words_at]) > float(rows[1][:words_at])


def test_irl_missing_file_is_exit_code_2(tmp_path, capsys):
    assert main(["irl", str(tmp_path / "nope.txt"), "--palette", "sokoban"]) == 2
    assert "groundlang irl: error" in capsys.readouterr().err


def test_irl_given_a_state_file_says_it_holds_no_demonstration(capsys):
    # its layout line had been read as a command, and the error asked for the actions on line 2
    from groundlang.corpus import example_corpus_path

    assert main(["irl", str(example_corpus_path() / "novel_a.state"), "--palette", "sokoban"]) == 2
    err = capsys.readouterr().err
    assert "novel_a.state: a .state file holds a layout, no demonstration; expected a corpus file" in err


def test_irl_fits_weights_over_a_librarys_own_position_pfs_too(tmp_path, capsys):
    """--library: a user's position PF is a feature (it had fitted the package's PFs only, so a demonstration of
    a PF of one's own was explained by another)."""
    from groundlang.corpus import example_corpus_path

    within = tmp_path / "within.lp"  # toyInRoom under another name: its weight is toyInRoom's
    within.write_text("pf(position, toyWithin, (toy, room)).\nholds(toyWithin, (T, R)) :- holds(toyInRoom, (T, R)).\n")
    demo = str(example_corpus_path() / "star2red_3.txt")
    assert main(["irl", demo, "--palette", "sokoban", "--json", "--library", "tasks", "--library", str(within)]) == 0
    weights = json.loads(capsys.readouterr().out)["weights"]
    assert list(weights)[:2] in (["toyInRoom(block0, room1)", "toyWithin(block0, room1)"],
                                 ["toyWithin(block0, room1)", "toyInRoom(block0, room1)"])
    assert weights["toyWithin(block0, room1)"] == pytest.approx(weights["toyInRoom(block0, room1)"], abs=1e-3)
    assert main(["irl", demo, "--palette", "sokoban", "--json"]) == 0
    assert not any(a.startswith("toyWithin") for a in json.loads(capsys.readouterr().out)["weights"])
