"""Gold labels (groundlang.labels): reading the CSV, checking goals on states, coverage."""

from __future__ import annotations

import re

import pytest

from groundlang.corpus import parse_state, read_corpus, read_instance
from groundlang.labels import (
    LabelError,
    check_goal_objects,
    goal_holds,
    label_coverage,
    label_for,
    read_labels,
)
from groundlang.logic.atoms import Atom, parse_goal

LAYOUT = "room,5,0,4,4,0 room,10,4,4,8,0 door,4,2,4,2"


def state(objects: str, palette: str = "sokoban"):
    return parse_state(f"{LAYOUT} {objects}", palette)


def test_read_labels(fixtures):
    labels = read_labels(fixtures / "sokoban" / "labels.csv")
    assert labels == {
        "agent2red_": (Atom("agentInRoom", ("agent0", "room1")),),
        "star2green_": (Atom("toyInRoom", ("block0", "room0")),),
    }
    assert labels.path.name == "labels.csv"
    multi = read_labels(fixtures / "sokoban2" / "labels.csv")["chair2blue_"]
    assert [a.predicate for a in multi] == ["toyInRoom", "toyIsChair", "toyIsRed", "roomIsBlue"]


@pytest.mark.parametrize(
    "name, pieces",
    [
        ("bad_header.csv", ["bad_header.csv, line 1: header is 'prefix,target'; expected prefix,goal"]),
        ("bad_goal.csv", ["bad_goal.csv, line 2:", "agentInRoom(agent0 room1"]),
        ("wrong_fields.csv", ["wrong_fields.csv, line 2: 3 fields; expected 2"]),
        # the quote left open on line 2 swallows the line break; the reader fails on line 3
        ("unclosed_quote.csv", ["unclosed_quote.csv, line 2: not valid CSV",
                                "a quote opened on line 2 is not closed there"]),
    ],
)
def test_malformed_labels(fixtures, name, pieces):
    with pytest.raises(LabelError) as info:
        read_labels(fixtures / "labels" / name)
    for piece in pieces:
        assert piece in str(info.value)


def test_duplicate_and_empty_labels(tmp_path):
    path = tmp_path / "dup.csv"
    path.write_text('prefix,goal\na_,"agentInRoom(agent0, room0)"\na_,"agentInRoom(agent0, room1)"\n')
    with pytest.raises(LabelError, match=r"dup.csv, line 3: prefix 'a_' is labelled twice"):
        read_labels(path)
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(LabelError, match="empty.csv: the file is empty"):
        read_labels(empty)
    binary = tmp_path / "bin.csv"
    binary.write_bytes(b"prefix,goal\n\xff\xfe\n")
    with pytest.raises(LabelError, match=r"bin.csv, line 2: not UTF-8"):
        read_labels(binary)


def test_position_atoms():
    s = state("block,12,0,5,2 agent,4,2")  # star in the red room, agent in the door
    assert goal_holds(parse_goal("toyInRoom(block0, room1)"), s)
    assert goal_holds(parse_goal("blockInRoom(block0, room1)"), s)
    assert not goal_holds(parse_goal("toyInRoom(block0, room0)"), s)
    assert not goal_holds(parse_goal("agentInRoom(agent0, room0)"), s)
    assert not goal_holds(parse_goal("agentInRoom(agent0, room1)"), s)
    assert goal_holds(parse_goal("agentInDoor(agent0, door0)"), s)
    assert not goal_holds(parse_goal("toyInDoor(block0, door0)"), s)
    assert goal_holds(parse_goal("agentTouchingToy(agent0, block0)"), s)
    assert not goal_holds(parse_goal("agentTouchingToy(agent0, block0)"), state("block,12,0,6,2 agent,4,2"))
    # a conjunction needs every atom
    assert not goal_holds(parse_goal("toyInRoom(block0, room1) agentInRoom(agent0, room1)"), s)
    assert goal_holds(parse_goal("toyInRoom(block0, room1) agentInRoom(agent0, room1)"), state("block,12,0,5,2 agent,6,2"))
    assert goal_holds((), s)


def test_a_goal_may_be_given_as_its_text_and_anything_else_is_a_label_error():
    s = state("block,12,0,5,2 agent,6,2")
    assert goal_holds("toyInRoom(block0, room1) agentInRoom(agent0, room1)", s)
    assert not goal_holds("toyInRoom(block0, room0)", s)
    # a string had been read one character at a time ("'a' is not an atom"), a number not at all
    for bad, piece in ((5, "expected Atoms or their text"), (["toyInRoom"], "expected Atoms or their text"),
                       ("toyInRoom(", "goal 'toyInRoom(': cannot read an atom")):
        with pytest.raises(LabelError, match=re.escape(piece)):
            goal_holds(bad, s)


def test_a_state_or_library_of_another_type_is_named():
    """Each had failed deep inside with an AttributeError ('str' object has no attribute 'layout')."""
    s = state("block,12,0,5,2 agent,6,2")
    with pytest.raises(TypeError, match=re.escape("goal_holds: state must be a State (read_state_file, "
                                                  "read_initial_state), got str")):
        goal_holds("agentInRoom(agent0, room0)", "x")
    with pytest.raises(TypeError, match=re.escape("goal_holds: library must be a TaskLibrary (TaskLibrary.load(path)) "
                                                  "or None, got str")):
        goal_holds("agentInRoom(agent0, room0)", s, library="tasks")


def test_colour_and_shape_atoms():
    s = state("block,12,0,5,2 agent,4,2")
    assert goal_holds(parse_goal("roomIsGreen(room0) roomIsRed(room1) toyIsYellow(block0) toyIsStar(block0)"), s)
    assert not goal_holds(parse_goal("roomIsRed(room0)"), s)
    assert not goal_holds(parse_goal("toyIsMoon(block0)"), s)
    assert goal_holds(parse_goal("blockIsStar(block0)"), s)
    gray = parse_state("room,3,0,4,4,0 block,6,4,2,2 agent,1,1", "sokoban")
    assert goal_holds(parse_goal("roomIsDarkGray(room0) toyIsLightGray(block0) toyIsSquare(block0)"), gray)
    two = parse_state(
        "room,0,0,4,4,0 room,4,4,4,8,0 door,4,2,4,2 block,3,0,5,2 block,1,3,6,3 agent,6,2", "sokoban2"
    )
    assert goal_holds(parse_goal("toyIsChair(block0) toyIsRed(block0) toyIsBasket(block1) roomIsYellow(room1)"), two)
    assert not goal_holds(parse_goal("toyIsChair(block1)"), two)


@pytest.mark.parametrize(
    "goal, piece",
    [
        ("agentInRoom(agent0, room7)", "names room7, which does not exist"),
        ("toyInRoom(block0, room0)", "names block0, which does not exist"),
        ("agentInRoom(room0, agent0)", "room0 is a room; expected an agent there"),
        ("roomIsPurple(room0)", "unknown predicate 'roomIsPurple'"),
        ("agentInRoom(agent0)", "has 1 arguments; agentInRoom takes 2 (agent, room)"),
    ],
)
def test_bad_goals_are_clear_errors(goal, piece):
    s = state("agent,2,2")
    with pytest.raises(LabelError) as info:
        goal_holds(parse_goal(goal), s)
    assert piece in str(info.value)


def test_label_for(fixtures):
    labels = read_labels(fixtures / "sokoban2" / "labels.csv")
    chair = read_instance(fixtures / "sokoban2" / "chair2blue_0.txt", "sokoban2")
    bag = read_instance(fixtures / "sokoban2" / "bag2yellow_0.txt", "sokoban2")
    assert len(label_for(chair, labels)) == 4
    assert label_for(bag, labels) is None
    bad = read_labels(fixtures / "labels" / "unknown_object.csv")
    inst = read_instance(fixtures / "sokoban" / "agent2red_0.txt", "sokoban")
    with pytest.raises(LabelError, match=r"unknown_object.csv: goal of 'agent2red_' for .*agent2red_0.txt: .*names room7"):
        label_for(inst, bad)


def test_label_coverage(fixtures):
    corpus = read_corpus(fixtures / "sokoban", "sokoban")
    cov = label_coverage(corpus, read_labels(fixtures / "sokoban" / "labels.csv"))
    assert (cov.total, cov.labelled, cov.holding, cov.failing, cov.unlabelled) == (4, 4, 4, [], [])
    wrong = label_coverage(corpus, read_labels(fixtures / "labels" / "wrong_goal.csv"))
    assert (wrong.labelled, wrong.holding) == (4, 2)
    assert [i.name for i, _ in wrong.failing] == ["agent2red_0", "agent2red_1"]
    two = read_corpus(fixtures / "sokoban2", "sokoban2")
    cov2 = label_coverage(two, read_labels(fixtures / "sokoban2" / "labels.csv"))
    assert (cov2.total, cov2.labelled, cov2.holding) == (2, 1, 1)
    assert [i.name for i in cov2.unlabelled] == ["bag2yellow_0"]


def test_labels_naming_missing_files(fixtures):
    corpus = read_corpus(fixtures / "sokoban", "sokoban")
    with pytest.raises(LabelError, match=r"unknown_prefix.csv: prefixes star2blue_ name no files in .*sokoban"):
        label_coverage(corpus, read_labels(fixtures / "labels" / "unknown_prefix.csv"))


def test_check_goal_objects_passes_good_goals():
    check_goal_objects(parse_goal("agentInRoom(agent0, room1) roomIsRed(room1)"), state("agent,2,2"))


def test_shared_labels_hold_at_the_end_only(shared_corpus):
    labels = read_labels(shared_corpus / "labels.csv")
    assert len(labels) == 6
    for folder in ("allTurkTrain", "allTurkTrainLimitedCommand"):
        corpus = read_corpus(shared_corpus / folder, "sokoban")
        cov = label_coverage(corpus, labels)
        assert (cov.total, cov.labelled, cov.holding) == (240, 240, 240)
        for inst in corpus:
            assert not goal_holds(label_for(inst, labels), inst.initial_state), inst.name


def test_quotes_left_open_or_closed_on_another_line_are_refused(tmp_path):
    at_end = tmp_path / "end.csv"
    at_end.write_text('prefix,goal\na_,"agentInRoom(agent0, room1)"\nb_,"agentInRoom(agent0, room0)\n')
    with pytest.raises(LabelError, match=r"end.csv, line 3: not valid CSV \(unexpected end of data"):
        read_labels(at_end)  # before, the last goal was read to the end of the file and accepted
    spanning = tmp_path / "span.csv"
    spanning.write_text('prefix,goal\na_,"agentInRoom(agent0,\n room1)"\n')
    with pytest.raises(LabelError, match="span.csv, line 2: a quote opened on this line closes only on line 3"):
        read_labels(spanning)


def test_the_corpus_spelling_of_toys_is_read_in_any_predicate():
    from groundlang.logic.atoms import canonical_predicate

    assert [canonical_predicate(p) for p in ("blockInRoom", "blockInDoor", "agentTouchingBlock", "blockIsStar",
                                             "agentNextToBlock", "blocky", "roomIsDarkGray")] == [
        "toyInRoom", "toyInDoor", "agentTouchingToy", "toyIsStar", "agentNextToToy", "blocky", "roomIsDarkGray"]


@pytest.mark.slow
def test_evaluate_refuses_labels_of_another_corpus_as_check_does(tmp_path):
    import subprocess
    import sys

    from groundlang import example_corpus_path

    labels = tmp_path / "labels.csv"
    labels.write_text("prefix,goal\n" + "".join(f'other{n}_,"agentInRoom(agent0, room0)"\n' for n in range(1000)),
                      encoding="utf-8")
    for argv in (["check", str(example_corpus_path()), "--palette", "sokoban", "--labels", str(labels)],
                 ["evaluate", "--corpus", str(example_corpus_path()), "--palette", "sokoban", "--labels", str(labels)]):
        done = subprocess.run([sys.executable, "-m", "groundlang.cli", *argv], capture_output=True, text=True)
        assert done.returncode == 2 and len(done.stderr.splitlines()) == 1, done.stderr
        assert "prefixes other0_, other100_, other101_, other102_, other103_, ... (1000 in all) name no files" in done.stderr


def test_labels_may_name_a_user_librarys_pf(tmp_path, fixtures):
    """A goal of a PF the user's library defines (agentNextToToy, examples/next_to.lp) is checked against
    final states with that library, by check --labels --library as by the Python call."""
    from groundlang.cli import main
    from groundlang.corpus import example_corpus_path
    from groundlang.logic.tasks import TaskLibrary

    csv = tmp_path / "labels.csv"
    csv.write_text('prefix,goal\nagent2red_,"agentInRoom(agent0, room1)"\n'
                   'star2green_,"agentNextToToy(agent0, block0)"\n', encoding="utf-8")
    corpus = read_corpus(fixtures / "sokoban", "sokoban")
    labels = read_labels(csv)
    with pytest.raises(LabelError, match="unknown predicate 'agentNextToToy'"):
        label_coverage(corpus, labels)  # the package's PFs alone do not define it
    library = TaskLibrary.load([example_corpus_path() / "next_to.lp"])
    cov = label_coverage(corpus, labels, library)
    assert (cov.labelled, cov.holding) == (4, 4)  # each push ends with the agent beside the star
    assert main(["check", str(fixtures / "sokoban"), "--palette", "sokoban", "--labels", str(csv),
                 "--library", str(example_corpus_path() / "next_to.lp")]) == 0


def test_an_unreadable_goal_of_any_length_is_quoted_by_its_start(tmp_path):
    """A label's goal nested 5,000 deep is refused in a line of bounded length (it was quoted whole: 30 KB)."""
    path = tmp_path / "deep.csv"
    path.write_text("prefix,goal\nstar2red_," + "f(" * 5000 + "x" + ")" * 5000 + "\n", encoding="utf-8")
    with pytest.raises(LabelError) as caught:
        read_labels(path)
    message = str(caught.value)
    assert message.startswith(f"{path}, line 2: cannot read an atom at 'f(f(f(") and len(message) < 400
    assert "(15001 characters)" in message
