"""Corpus reading/writing (groundlang.corpus): fixtures, malformed files, replay, example corpus, fuzzing."""

from __future__ import annotations

import logging

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from groundlang.corpus import (
    CorpusError,
    InconsistentDemonstration,
    Instance,
    example_corpus_path,
    format_state,
    parse_state,
    read_corpus,
    read_instance,
    read_state_file,
    write_instance,
)
from groundlang.model.world import Action, step

# file -> (line number in the message or None, pieces the message must contain)
MALFORMED = {
    "empty.txt": (None, ["the file is empty", "expected a command line"]),
    "blank.txt": (None, ["the file is empty"]),
    "only_command.txt": (2, ["missing", "expected the actions"]),
    "empty_command.txt": (1, ["the command is empty", "expected the command's words"]),
    "punctuation_command.txt": (1, ["the command has no word, only punctuation ('?? !')"]),
    "blank_state_line.txt": (4, ["a blank line among the state lines", "expected one state per line"]),
    "truncated.txt": (5, ["3 actions need 4 state lines", "found 2", "truncated"]),
    "truncated_midline.txt": (4, ["'room,10,4' has 3 comma-separated fields", "expected 6 (room,COLOUR,LEFT,TOP,RIGHT,BOTTOM)"]),
    "extra_state.txt": (5, ["extra state line", "need exactly 2 state lines"]),
    "wrong_fields.txt": (3, ["'room,5,0,4,4' has 5 comma-separated fields", "expected 6"]),
    "not_a_number.txt": (3, ["field X of 'agent,x,2' is 'x'", "expected an integer"]),
    "unknown_kind.txt": (3, ["unknown object kind 'lamp'", "expected room, door, block (or toy) or agent"]),
    "colour_outside_palette.txt": (3, ["colour index 13 is outside palette 'sokoban' (0..12)"]),
    "shape_outside_palette.txt": (3, ["shape index 5 is outside palette 'sokoban' (0..4)"]),
    "overlapping_rooms.txt": (3, ["room0 and room1 overlap"]),
    "door_inside_room.txt": (3, ["door0 (2,7,2,7) is not in a wall between two rooms"]),
    "door_in_outer_wall.txt": (3, ["door0 (0,7,0,7) is not in a wall between two rooms",
                                   "a door opens the walls of two rooms"]),
    "door_outside_grid.txt": (3, ["door0 (20,2,20,2) reaches outside the rooms (the grid is 11 x 11)"]),
    "door_negative.txt": (3, ["door0 (-3,2,-1,2) reaches outside the rooms"]),
    # a gap between two rooms' walls stays solid; corners open no room
    "door_across_a_gap.txt": (3, ["door0 (4,2,6,2) has cells outside every room"]),
    "door_at_corners.txt": (3, ["door0 (4,0,5,0) is not in a wall between two rooms"]),
    "doors_on_one_cell.txt": (3, ["door0 and door1 open a wall cell both: one door is enough there"]),
    "zero_size_room.txt": (3, ["room0 (0,4,1,0) has no interior", "RIGHT-LEFT >= 2"]),
    "object_in_wall.txt": (3, ["agent0 at (4,1) is inside a wall"]),
    "shared_cell.txt": (3, ["agent0 and block0 share the cell (2,2)"]),
    "unknown_action.txt": (2, ["action 2 is 'nort'", "expected one of north, south, east, west"]),
    "empty_action.txt": (2, ["action 2 is empty"]),
    "non_utf8.txt": (1, ["byte 0xe9 at offset 11 is not UTF-8", "expected a UTF-8 text file"]),
    "layout_changes.txt": (4, ["layout differs from line 3 (room1 changed)", "expected only the agent and blocks to move"]),
    "two_agents.txt": (3, ["found 2 agents", "expected exactly one agent"]),
    "no_agent.txt": (3, ["found 0 agents"]),
    "huge_coordinate.txt": (3, ["field RIGHT", "99999", "expected at most 1000"]),
}


@pytest.mark.parametrize("name", sorted(MALFORMED))
def test_malformed_file_gives_one_clear_message(fixtures, name):
    line, pieces = MALFORMED[name]
    with pytest.raises(CorpusError) as info:
        read_instance(fixtures / "malformed" / name, "sokoban")
    msg = str(info.value)
    assert "\n" not in msg
    assert msg.startswith(str(fixtures / "malformed" / name))
    if line is not None:
        assert f"{name}, line {line}:" in msg
    for piece in pieces:
        assert piece in msg, msg
    assert not isinstance(info.value, InconsistentDemonstration)


def test_every_malformed_fixture_is_in_the_table(fixtures):
    assert sorted(p.name for p in (fixtures / "malformed").iterdir()) == sorted(MALFORMED)


def test_sokoban_fixture_corpus(fixtures):
    corpus = read_corpus(fixtures / "sokoban", "sokoban")
    assert [i.name for i in corpus] == ["agent2red_0", "agent2red_1", "star2green_0", "star2green_1"]
    assert [i.prefix for i in corpus] == ["agent2red_", "agent2red_", "star2green_", "star2green_"]
    first = corpus.instances[0]
    assert first.command == "go to the red room"
    assert first.actions == (Action.EAST,) * 3
    assert len(first.states) == 4
    assert (first.initial_state.agent.x, first.initial_state.agent.y) == (2, 2)
    assert (first.final_state.agent.x, first.final_state.agent.y) == (5, 2)
    # stray spaces around action words are trimmed
    assert corpus.instances[1].actions == (Action.EAST,) * 3
    assert [r.colour for r in first.initial_state.layout.rooms] == ["green", "red"]
    star = corpus.instances[2].initial_state.toys[0]
    assert (star.colour, star.shape, star.x, star.y) == ("yellow", "star", 5, 2)
    assert len(corpus.commands()) == 4
    assert len(corpus.distinct_layouts()) == 1
    assert sorted(len(g) for g in corpus.distinct_demonstrations().values()) == [2, 2]
    assert corpus.skipped == []


def test_sokoban2_fixture_two_toys_and_blocked_push(fixtures):
    corpus = read_corpus(fixtures / "sokoban2", "sokoban2")
    bag, chair = corpus.instances  # sorted by prefix
    assert chair.name == "chair2blue_0"
    assert [(t.colour, t.shape) for t in chair.initial_state.toys] == [("red", "chair"), ("green", "basket")]
    assert [r.colour for r in chair.initial_state.layout.rooms] == ["blue", "yellow"]
    assert chair.final_state.positions.tolist() == [[4, 2], [3, 2], [6, 3]]
    # pushing the bag into the backpack moves nothing
    assert bag.states[1].positions.tolist() == bag.states[0].positions.tolist()
    assert chair.initial_state.layout.toy_names == ["block0", "block1"]


def test_wrong_palette_names_file_line_and_palette(fixtures):
    with pytest.raises(CorpusError, match=r"agent2red_0.txt, line 3: 'room,5,0,4,4,0': colour index 5 is outside palette 'sokoban2' \(0..4\)"):
        read_instance(fixtures / "sokoban" / "agent2red_0.txt", "sokoban2")
    with pytest.raises(ValueError, match="unknown palette 'nope'"):
        read_instance(fixtures / "sokoban" / "agent2red_0.txt", "nope")


def test_inconsistent_demonstration_is_an_error_by_default(fixtures):
    with pytest.raises(InconsistentDemonstration) as info:
        read_corpus(fixtures / "inconsistent", "sokoban")
    exc = info.value
    assert (exc.path.name, exc.line, exc.step) == ("agent2red_1.txt", 5, 2)
    assert "agent2red_1.txt, line 5: step 2 (east) from line 4 gives agent0 at (4,2); the file has agent0 at (3,3)" in str(exc)
    assert isinstance(exc, ValueError)


def test_inconsistent_demonstration_skipped_with_warning(fixtures, caplog):
    with caplog.at_level(logging.WARNING, logger="groundlang.corpus"):
        corpus = read_corpus(fixtures / "inconsistent", "sokoban", skip_inconsistent=True)
    assert [i.name for i in corpus] == ["agent2red_0"]
    assert len(corpus.skipped) == 1
    assert corpus.skipped[0][0].name == "agent2red_1.txt"
    assert "line 5" in corpus.skipped[0][1]
    assert any("skipped 1 of 2 files" in r.getMessage() for r in caplog.records)


def test_folder_errors(fixtures, tmp_path):
    with pytest.raises(CorpusError, match=r"no_corpus: no corpus files; expected files like agent2red_0.txt"):
        read_corpus(fixtures / "no_corpus", "sokoban")
    with pytest.raises(CorpusError, match="not a directory"):
        read_corpus(tmp_path / "absent", "sokoban")


def test_write_instance_round_trips_atomically(fixtures, tmp_path):
    for folder, palette in (("sokoban", "sokoban"), ("sokoban2", "sokoban2")):
        for inst in read_corpus(fixtures / folder, palette):
            out = tmp_path / inst.path.name
            write_instance(out, inst)
            again = read_instance(out, palette)
            assert (again.command, again.actions, again.states) == (inst.command, inst.actions, inst.states)
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
    original = (fixtures / "sokoban" / "agent2red_0.txt").read_text()
    assert (tmp_path / "agent2red_0.txt").read_text() == original


def test_write_instance_refuses_bad_instances(fixtures, tmp_path):
    inst = read_instance(fixtures / "sokoban" / "agent2red_0.txt", "sokoban")
    bad = Instance(inst.path, "two\nlines", inst.actions, inst.states)
    with pytest.raises(CorpusError, match="one line"):
        write_instance(tmp_path / "x.txt", bad)
    with pytest.raises(CorpusError, match="3 actions need 4 states, got 3"):
        write_instance(tmp_path / "x.txt", Instance(inst.path, "go", inst.actions, inst.states[:3]))
    # had failed with AttributeError 'NoneType' object has no attribute 'command'
    with pytest.raises(TypeError, match=r"^write_instance: instance must be an Instance \(read_instance, .* got NoneType"):
        write_instance(tmp_path / "x.txt", None)
    assert list(tmp_path.iterdir()) == []


def test_format_state_names_a_state_of_another_type():
    with pytest.raises(TypeError, match="^format_state: state must be a State, got str$"):  # had: no attribute 'layout'
        format_state("x")


def test_format_state_round_trips(fixtures):
    for path in [*(fixtures / "sokoban").glob("*.txt")]:
        for line in path.read_text().splitlines()[2:]:
            assert format_state(parse_state(line, "sokoban")) == line
    line = (fixtures / "two_toys.state").read_text().strip()
    assert format_state(parse_state(line, "sokoban2")) == line


def test_toy_keyword_is_accepted():
    state = parse_state("room,5,0,4,4,0 toy,12,0,2,2 agent,1,1", "sokoban")
    assert format_state(state) == "room,5,0,4,4,0 block,12,0,2,2 agent,1,1"


def test_state_files(fixtures, tmp_path):
    state = read_state_file(fixtures / "small.state", "sokoban")
    assert (state.agent.x, state.agent.y, len(state.layout.rooms)) == (2, 2, 2)
    two = read_state_file(fixtures / "two_toys.state", "sokoban2")
    assert len(two.toys) == 2
    with pytest.raises(CorpusError, match=r"two_lines.state, line 2: a second line \(line 1 is the state\); expected "
                                          "exactly one state line"):
        read_state_file(fixtures / "two_lines.state", "sokoban")
    line = (fixtures / "small.state").read_text(encoding="utf-8").strip()
    (tmp_path / "blank_first.state").write_text(f"\n\n{line}\n", encoding="utf-8")  # blank lines before it are no lines
    assert read_state_file(tmp_path / "blank_first.state", "sokoban") == state
    (tmp_path / "blank_first.state").write_text(f"\n\n{line.replace('agent,2,2', 'agent,4,1')}\n", encoding="utf-8")
    with pytest.raises(CorpusError, match=r"blank_first.state, line 3: agent0 at \(4,1\)"):  # its own line, not 1
        read_state_file(tmp_path / "blank_first.state", "sokoban")
    (tmp_path / "comment.state").write_text(f"# my layout\n{line}\n", encoding="utf-8")  # it had blamed line 2
    with pytest.raises(CorpusError, match=r"comment.state, line 1: a comment; a state file holds its state line alone"):
        read_state_file(tmp_path / "comment.state", "sokoban")
    with pytest.raises(CorpusError, match=r"empty.state: the file is empty; expected one state line"):
        read_state_file(fixtures / "empty.state", "sokoban")
    with pytest.raises(CorpusError, match=r"in_wall.state, line 1: agent0 at \(4,1\) is inside a wall"):
        read_state_file(fixtures / "in_wall.state", "sokoban")


def test_example_corpus_is_consistent_and_labelled():
    from groundlang.labels import goal_holds, label_for, read_labels

    folder = example_corpus_path()
    corpus = read_corpus(folder, "sokoban")
    assert len(corpus) == 24
    assert len(corpus.commands()) == 24
    assert len(corpus.distinct_demonstrations()) == 6
    assert len(corpus.distinct_layouts()) == 1
    labels = read_labels(folder / "labels.csv")
    assert sorted(labels) == sorted({i.prefix for i in corpus})
    for inst in corpus:
        goal = label_for(inst, labels)
        assert not goal_holds(goal, inst.initial_state), inst.name
        assert goal_holds(goal, inst.final_state), inst.name
        # shortest: no earlier state satisfies the goal
        assert not any(goal_holds(goal, s) for s in inst.states[:-1]), inst.name
    novel = sorted(folder.glob("*.state"))
    assert [p.name for p in novel] == ["novel_a.state", "novel_b.state", "novel_c.state"]
    for path in novel:
        state = read_state_file(path, "sokoban")
        assert sorted(r.colour for r in state.layout.rooms) == ["blue", "green", "red"]
        assert [(t.colour, t.shape) for t in state.toys] == [("yellow", "star")]


def test_example_corpus_build_is_deterministic(tmp_path):
    """Every data file shipped in groundlang/examples is written by its builder (our commands,
    shortest-path demonstrations): nothing there comes from the crowd corpus."""
    from groundlang.examples.build import build

    written = build(tmp_path)
    assert len(written) == 24 + 1 + 3
    shipped = example_corpus_path()
    for path in written:
        assert path.read_bytes() == (shipped / path.name).read_bytes(), path.name
    data = sorted(p.name for p in shipped.iterdir() if p.suffix in {".txt", ".csv", ".state"})
    assert data == sorted(p.name for p in written)


def test_shortest_demonstration_replays():
    from groundlang.examples.build import TASKS, shortest_demonstration
    from groundlang.logic.atoms import parse_goal

    goal_text, start = TASKS["star2red_"]
    actions = shortest_demonstration(start, parse_goal(goal_text))
    state = start
    for a in actions:
        state = step(state, a)
    assert state.toys[0].y > 4 and 5 < state.toys[0].x < 12  # inside the red room's interior
    assert len(actions) == 11


def test_shared_corpus_loads_and_round_trips(shared_corpus):
    for folder in ("allTurkTrain", "allTurkTrainLimitedCommand"):
        corpus = read_corpus(shared_corpus / folder, "sokoban")
        assert len(corpus) == 240
        assert len(corpus.distinct_demonstrations()) == 6
        assert len(corpus.distinct_layouts()) == 1
        assert corpus.skipped == []
        for inst in corpus.instances[::20]:
            lines = inst.path.read_text().splitlines()
            assert [format_state(s) for s in inst.states] == lines[2:]


_GOOD = (
    "go to the red room\neast,east,east\n"
    + "\n".join(f"room,5,0,4,4,0 room,10,4,4,8,0 door,4,2,4,2 agent,{x},2" for x in (2, 3, 4, 5))
    + "\n"
)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.one_of(
    st.binary(max_size=300),
    st.text(alphabet=st.sampled_from(list("roomdrblckagentsuhwas0123456789-,  \n\r\t\xe9\x00")), max_size=300),
    st.tuples(st.integers(0, len(_GOOD)), st.integers(0, len(_GOOD)), st.text(max_size=20)).map(
        lambda t: _GOOD[: t[0]] + t[2] + _GOOD[t[1]:]
    ),
))
def test_fuzz_reader_only_raises_corpus_errors(tmp_path, data):
    path = tmp_path / "fuzz.txt"
    path.write_bytes(data if isinstance(data, bytes) else data.encode("utf-8", "surrogatepass"))
    try:
        inst = read_instance(path, "sokoban")
    except CorpusError as exc:
        assert str(exc).startswith(str(path))
        assert "\n" not in str(exc)
    else:
        assert len(inst.states) == len(inst.actions) + 1


def test_a_corpus_folder_entry_that_is_not_a_file_is_reported_not_skipped(fixtures, tmp_path):
    import shutil

    corpus = tmp_path / "corpus"
    shutil.copytree(fixtures / "sokoban", corpus)
    assert len(read_corpus(corpus, "sokoban")) == 4
    (corpus / "agent2red_7.txt").mkdir()
    with pytest.raises(CorpusError, match=r"agent2red_7.txt: a folder, not a corpus file"):
        read_corpus(corpus, "sokoban")
    (corpus / "agent2red_7.txt").rmdir()
    (corpus / "star2green_5.txt").symlink_to(tmp_path / "gone.txt")
    with pytest.raises(CorpusError, match=r"star2green_5.txt: a broken link, not a corpus file"):
        read_corpus(corpus, "sokoban")
    (corpus / "star2green_5.txt").unlink()
    (corpus / "star2green_5.txt").symlink_to("/dev/zero")  # a link that resolves, to what is no file
    with pytest.raises(CorpusError, match=r"star2green_5.txt: a device, FIFO or socket, not a corpus file"):
        read_corpus(corpus, "sokoban")


def test_a_byte_order_mark_is_read_as_nothing(fixtures, tmp_path):
    line = (fixtures / "novel_envs" / "novel_a.state").read_text(encoding="utf-8")
    path = tmp_path / "bom.state"
    path.write_bytes(b"\xef\xbb\xbf" + line.encode("utf-8"))
    assert read_state_file(path, "sokoban") == read_state_file(fixtures / "novel_envs" / "novel_a.state", "sokoban")


def test_line_ends_are_the_editors_and_only_those(tmp_path):
    """CR alone (an old Mac's line end) ends a line as LF and CRLF do; U+2028 or a form feed in the command
    does not, so the line numbers of errors after it stay right."""
    for name, text in (("lf", _GOOD), ("crlf", _GOOD.replace("\n", "\r\n")), ("cr", _GOOD.replace("\n", "\r"))):
        path = tmp_path / f"{name}.txt"
        path.write_bytes(text.encode("utf-8"))
        inst = read_instance(path, "sokoban")
        assert inst.command == "go to the red room" and len(inst.states) == 4, name
    bad = tmp_path / "separator.txt"
    bad.write_text(_GOOD.replace("go to", "go\u2028to\x0c").replace("agent,5,2", "agent,9,2"), encoding="utf-8")
    with pytest.raises(CorpusError, match=r", line 6: "):
        read_instance(bad, "sokoban")


@pytest.mark.parametrize("line", [
    # the crowd corpus's layout: one-cell doors in shared walls, one two-cell door reaching into a room
    "room,5,0,10,6,4 room,10,6,10,10,4 room,1,0,4,10,0 door,3,4,3,3 door,8,4,8,3 door,5,6,6,6 agent,8,6",
    # rooms side by side with walls of their own: a two-cell door crosses both walls
    "room,5,0,4,4,0 room,10,5,4,9,0 door,4,2,5,2 agent,2,2",
])
def test_doors_between_two_rooms_are_accepted(line):
    state = parse_state(line, "sokoban")
    assert state.layout.doors and state.layout.walkable[state.layout.doors[-1].left, state.layout.doors[-1].bottom]


@pytest.mark.parametrize("x, piece", [
    ("0" * 5000 + "9", None),  # leading zeros are only zeros: x = 9
    ("9" * 5000, "field X of 'agent," + "9" * 54 + "... (5008 characters)' is 99999999999999999999... (5000 digits); "
     "expected at most"),
    ("12345678", "is 12345678; expected at most 1000 in size"),
])
def test_a_coordinate_of_many_digits_is_read_or_refused_without_converting_them_all(tmp_path, x, piece):
    rooms = "room,1,0,10,6,5 room,5,6,10,12,5 room,10,0,5,12,0 door,6,8,6,8 door,3,5,3,5 door,9,5,9,5"
    path = tmp_path / "s.state"
    path.write_text(f"{rooms} agent,{x},5\n", encoding="utf-8")
    if piece is None:
        assert read_state_file(path, "sokoban").agent.x == 9
        return
    with pytest.raises(CorpusError) as info:
        read_state_file(path, "sokoban")
    assert piece in str(info.value) and len(str(info.value)) < 300
