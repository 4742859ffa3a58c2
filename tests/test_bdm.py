"""The Williams et al. (2018) corpus format: reading, the tasks pairs show, checking; and its domain in ASP."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from groundlang.bdm import format_bdm_state, parse_bdm_state, read_bdm
from groundlang.corpus import CorpusError, read_initial_state
from groundlang.logic.atoms import Atom
from groundlang.pair_tasks import covers, lifted_facts, pair_task, reachable, satisfies

FIXTURE = Path(__file__).parent / "fixtures" / "williams2018"
SHARED = Path(__file__).parent.parent.parent / "shared" / "data" / "williams2018" / "train"




def test_the_fixture_reads_as_two_commands_of_three_pairs(williams_commands):
    assert [c.text for c in williams_commands] == ["go to the largest room", "go next to the chair"]
    assert [len(c.pairs) for c in williams_commands] == [3, 3] and [c.line for c in williams_commands] == [1, 14]
    pair = williams_commands[1].pairs[0]
    assert pair.toy_names == ("block0", "block3")  # the file's names; the state's are block0, block1
    assert pair.start.layout.toy_attributes == (("blue", "chair"), ("large", "box"))
    assert [r.colour for r in pair.start.layout.rooms] == ["red", "green", "blue"]
    assert (pair.start.agent.x, pair.start.agent.y, pair.end.agent.x, pair.end.agent.y) == (2, 6, 5, 2)


def test_a_state_string_round_trips(williams_commands):
    pair = williams_commands[1].pairs[0]
    again, names = parse_bdm_state(format_bdm_state(pair.start, pair.toy_names))
    assert again == pair.start and names == pair.toy_names


@pytest.mark.parametrize("separator", ["\t,\t", "\u00a0,\u00a0", "  ,  "])
def test_objects_are_separated_by_a_comma_with_any_white_space_around_it(williams_commands, separator):
    """A tab or a no-break space around the comma had been read as an object running into the one before it."""
    line = format_bdm_state(williams_commands[0].pairs[0].start)
    assert parse_bdm_state(line.replace(" , ", separator)) == parse_bdm_state(line)


def test_a_one_line_bdm_state_file_is_a_state_file():
    state = read_initial_state(FIXTURE / "one.state", "williams2018")
    assert state.layout.toy_attributes == (("green", "chair"),) and (state.agent.x, state.agent.y) == (2, 2)


def test_the_tasks_pairs_show_are_lifted_facts(williams_commands, williams_library):
    largest, chair = (pair_task([(p.start, p.end) for p in c.pairs], williams_library) for c in williams_commands)
    assert Atom("agentInRoom", ("agent", "roomIsLargest")) in largest
    assert not any("Green" in f.args[1] or "Red" in f.args[1] for f in largest)  # colours differ across pairs
    assert Atom("agentNextToToy", ("agent", "toyIsChair")) in chair
    # the agent ends in different kinds of room, each the room with the chair (a room is said by what it holds)
    assert {f for f in chair if f.predicate == "agentInRoom"} == {
        Atom("agentInRoom", ("agent", "toyInRoom(toyIsChair, _)")), Atom("agentInRoom", ("agent", "toyInRoom(toy, _)"))}
    for c, task in zip(williams_commands, (largest, chair)):
        assert all(satisfies(p.end, task, williams_library) and not satisfies(p.start, task, williams_library) for p in c.pairs)


def test_a_room_is_said_by_what_it_holds_never_through_the_fact_itself(williams_commands, williams_library):
    # the blue chair and the large box both in the red room (room0), the agent in the green room
    line = format_bdm_state(williams_commands[1].pairs[0].start).replace("x: {6} y: {6} shape: {box}",
                                                                          "x: {2} y: {2} shape: {box}")
    facts = {str(a) for a in lifted_facts(parse_bdm_state(line)[0], williams_library)}
    assert "toyInRoom(toyIsChair, toyInRoom(toyIsBox, _))" in facts  # the room with the box holds the chair
    assert "toyInRoom(toyIsBox, toyInRoom(toyIsChair, _))" in facts
    assert "toyInRoom(toyIsChair, roomIsRed)" in facts
    # not the chair's room as "the room with the chair" in the fact that puts the chair there
    assert not any(f.startswith("toyInRoom(toyIsChair, toyInRoom(toyIsChair") for f in facts)
    assert "agentInRoom(agent, roomIsGreen)" in facts
    assert not any("agentInRoom(" in f.split(", ", 1)[1] for f in facts if ", " in f)  # the agent holds nothing


def test_reachability(williams_commands, tmp_path):
    assert all(reachable(p.start, p.end) for c in williams_commands for p in c.pairs)
    # A block in a room's corner cannot be pushed north: the agent would have to stand in the wall.
    pair = williams_commands[1].pairs[1]  # green room x 0..4, y 0..8 in layout B; the red chair at (2, 2)
    start = parse_bdm_state(format_bdm_state(pair.start).replace("x: {2} y: {2} shape", "x: {1} y: {1} shape"))[0]
    end = parse_bdm_state(format_bdm_state(pair.start).replace("x: {2} y: {2} shape", "x: {1} y: {2} shape"))[0]
    assert reachable(start, end) is False
    bad = tmp_path / "bad.bdm"
    bad.write_text(f"push the chair up\n{format_bdm_state(start)}\n{format_bdm_state(end)}\ntrue\n", encoding="utf-8")
    done = subprocess.run([sys.executable, "-m", "groundlang.cli", "check", str(bad)], capture_output=True, text=True)
    assert done.returncode == 1 and f"{bad}, line 2: 'push the chair up'" in done.stdout
    assert "1 unreachable pair (use" in done.stderr
    done = subprocess.run([sys.executable, "-m", "groundlang.cli", "check", str(bad), "--skip-inconsistent"],
                          capture_output=True, text=True)
    assert done.returncode == 0


def test_check_reports_the_fixture():
    done = subprocess.run([sys.executable, "-m", "groundlang.cli", "check", str(FIXTURE)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "commands: 2 (2 distinct texts)" in done.stdout and "pairs: 6; distinct layouts: 6" in done.stdout
    assert "pairs whose end state cannot be reached from the start: 0" in done.stdout
    assert "commands whose pairs show no task: 0" in done.stdout
    # grids named as the corpus names them, by the largest x and y (9 cells a side is 8x8), and said so
    assert "pairs by grid (largest x by largest y) and blocks: 8x8 with 0: 3, 8x8 with 1: 2, 8x8 with 2: 1" in done.stdout


@pytest.mark.parametrize("text, piece", [
    ("go\n{agent0 (agent): [x: {1} y: {1} ] , }\n", "a pair needs a start state, an end state and the word true"),
    ("go\n{agent0 (agent): [x: {1} ] , }\n{agent0 (agent): [x: {1} ] , }\ntrue\n", "agent agent0 has no y"),
    ("go\n{lamp0 (lamp): [x: {1} ] , }\n{}\ntrue\n", "object lamp0 has class 'lamp'"),
    ("{agent0 (agent): [x: {1} y: {1} ] , }\n", "line 1: a block starts with a state"),
    ("go\nSTATE\nSTATE\nfalse\n", "line 4: expected the word true"),
    ("go\nROOMS_RED\nROOMS_PURPLE\ntrue\n", "'purple', which the palette does not have"),
    ("go\nROOMS_RED\nROOMS_RED_MOVED\ntrue\n", "line 3: the end state's rooms, doors or blocks differ"),
    # one name for two objects of different classes ("agent0" a room too) is as ambiguous as within one class
    ("go\nAGENT_ROOM\nAGENT_ROOM\ntrue\n", "line 2: two objects are called agent0"),
    # a number too large is said to be too large, and its digits are never all converted
    ("go\nFAR\nFAR\ntrue\n", "x of agent0 is 99999999999999999999... (5000 digits); expected at most 1000"),
    ("go\nNEGATIVE\nNEGATIVE\ntrue\n", "x of agent0 is '-1'; expected a whole number, 0 or more"),
    # a space missing before a comma: two objects run together, never read as one the second overwrote
    ("go\nJOINED\nJOINED\ntrue\n", "line 2: object room0 runs into the one before it"),
    ("go\nTWICE\nTWICE\ntrue\n", "line 2: agent agent0 gives x more than once"),
    ("go\nZEROS\nZEROS\ntrue\n", "x of agent0 is 00000000000000000000... (5004 digits); expected at most 1000"),
    # a separator inside a command that str.splitlines would take for a line end (U+2028, form feed, NEL)
    # does not shift the line numbers after it; a file with CR alone as its line end is read as an editor shows it
    ("go\u2028now\x0cplease\x85\nSTATE\nSTATE\nfalse\n", "line 4: expected the word true"),
    ("go\rSTATE\rSTATE\rfalse\r", "line 4: expected the word true"),
    # a --- promises another pair: a file cut off after one is refused, not read as one pair fewer
    ("go\nSTATE\nSTATE\ntrue\n---\n", "line 5: --- at line 5 is followed by no pair"),
    ("go\nSTATE\nSTATE\ntrue\n---\n\nmore\nSTATE\nSTATE\ntrue\n", "line 5: --- at line 5 is followed by no pair;"),
    ("go\nSTATE\nSTATE\ntrue\n---\nmore\nSTATE\nSTATE\ntrue\n", "line 5: --- at line 5 is followed by no pair (line 6 is 'more'"),
    # --- is never a command's text
    ("---\nSTATE\nSTATE\ntrue\n", "line 1: --- where a command was expected"),
    ("\n---\n\ngo\nSTATE\nSTATE\ntrue\n", "line 2: --- where a command was expected"),
    # a state left out of a pair is named as missing where it is, not as the word true coming late
    ("go\nSTATE\ntrue\n---\nSTATE\nSTATE\ntrue\n", "line 3: expected the end state of a pair (a state in braces), found 'true'"),
    # a command needs a word: punctuation or control characters alone say nothing to learn from
    ("go\nSTATE\nSTATE\ntrue\n\n?! ...\nSTATE\nSTATE\ntrue\n", "line 6: the command has no word, only punctuation ('?! ...')"),
    ("\x00\x07\nSTATE\nSTATE\ntrue\n", "line 1: the command is empty or only whitespace"),
    # commands written back to back: the next command's text is where a --- or a blank line was due
    ("go\nSTATE\nSTATE\ntrue\nwalk\nSTATE\nSTATE\ntrue\n", "line 5: expected --- between pairs, found 'walk' "
                                                         "(a command's block ends with a blank line)"),
    # a blank line after the command ends its block: the message says why it has no pair
    ("go\n\nSTATE\nSTATE\ntrue\n", "line 1: the command 'go' has no (start, end) pair (its pairs follow it with "
                                   "no blank line between: a blank line ends a command)"),
])
def test_bad_files_are_one_line_naming_file_and_line(tmp_path, text, piece):
    room = "room0 (room): [top: {4} left: {0} bottom: {0} right: {4} colour: {%s} ]"
    state = "{agent0 (agent): [x: {1} y: {1} ] , " + room % "red" + " , }"
    text = (text.replace("ROOMS_RED_MOVED", state.replace("right: {4}", "right: {5}"))
            .replace("ROOMS_RED", state).replace("ROOMS_PURPLE", state.replace("{red}", "{purple}"))
            .replace("STATE", state).replace("AGENT_ROOM", state.replace("room0 (room)", "agent0 (room)"))
            .replace("FAR", state.replace("x: {1}", "x: {%s}" % ("9" * 5000)))
            .replace("NEGATIVE", state.replace("x: {1}", "x: {-1}"))
            .replace("JOINED", state.replace("] , room0", "] ,room0"))
            .replace("TWICE", state.replace("y: {1}", "y: {1} X: {3}"))
            .replace("ZEROS", state.replace("x: {1}", "x: {%s}" % ("0" * 5000 + "5000"))))
    path = tmp_path / "bad.bdm"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(CorpusError) as info:
        read_bdm(path)
    assert piece in str(info.value) and str(path) in str(info.value)


def test_blank_lines_beside_a_separator_do_not_end_the_command(tmp_path):
    """A stray blank line before or after a --- was read as a new command whose text is ---."""
    lines = (FIXTURE / "small.bdm").read_text(encoding="utf-8").splitlines()
    path = tmp_path / "blank.bdm"
    path.write_text("\n".join(lines[:4] + [""] + lines[4:5] + ["", ""] + lines[5:]) + "\n", encoding="utf-8")
    commands, fixture = read_bdm(path), read_bdm(FIXTURE / "small.bdm")
    assert [c.text for c in commands] == [c.text for c in fixture]
    assert [[p.start for p in c.pairs] for c in commands] == [[p.start for p in c.pairs] for c in fixture]
    assert [p.line for p in commands[0].pairs] == [2, 9, 13]


def test_a_state_line_shown_again_is_read_once_and_a_bad_copy_is_still_named(tmp_path):
    """Workers were shown the same demonstrations: a repeated state line is the same State, read once."""
    text = (FIXTURE / "small.bdm").read_text(encoding="utf-8")
    first = text.split("\n\n")[0].strip().splitlines()  # the first command: its text and three pairs
    path = tmp_path / "again.bdm"
    path.write_text(text.rstrip("\n") + "\n\nthe same again\n" + "\n".join(first[1:]) + "\n", encoding="utf-8")
    commands = read_bdm(path)
    assert commands[-1].text == "the same again" and len(commands[-1].pairs) == len(commands[0].pairs)
    assert all(a.start is b.start and a.end == b.end for a, b in zip(commands[0].pairs, commands[-1].pairs))
    bad = first[1].replace("x: {2}", "x: {two}", 1)
    assert bad != first[1]
    path.write_text(text.rstrip("\n") + "\n\nthe same again\n" + "\n".join([bad] + first[2:]) + "\n",
                    encoding="utf-8")
    with pytest.raises(CorpusError, match=f"again.bdm, line {len(text.rstrip(chr(10)).splitlines()) + 3}"):
        read_bdm(path)


@pytest.mark.slow
def test_the_shared_corpus_reads_and_every_command_shows_a_task(williams_library):
    if not (SHARED / "part1.bdm").is_file():
        pytest.skip(f"Williams et al. 2018 corpus not found at {SHARED} (it is not part of the repository)")
    part1, part2 = read_bdm(SHARED / "part1.bdm"), read_bdm(SHARED / "part2.bdm")
    assert (len(part1), len(part2)) == (1048, 571)
    assert all(len(c.pairs) == 3 for c in part1 + part2)
    assert len({c.text for c in part1}) == 466 and len({c.text for c in part2}) == 295
    large = [p for c in part2 for p in c.pairs if p.start.layout.width == 17]
    assert len(large) == 63 and all(len(p.start.toys) == 3 for p in large)
    sample = part2[::25]
    assert all(pair_task([(p.start, p.end) for p in c.pairs], williams_library) for c in sample)


def test_synthesised_demonstrations_end_in_the_end_state_by_a_shortest_path(williams_commands):
    from groundlang.model.world import replay
    from groundlang.pair_tasks import shortest_actions

    lengths = []
    for c in williams_commands:
        for p in c.pairs:
            actions = shortest_actions(p.start, p.end)
            assert replay(p.start, actions)[-1] == p.end
            lengths.append(len(actions))
    # Manhattan distance is a lower bound, reached when no wall is in the way.
    assert lengths == [7, 5, 5, 7, 7, 9]
    assert shortest_actions(williams_commands[0].pairs[0].start, williams_commands[0].pairs[0].start) == ()


def test_a_fifo_or_device_is_refused_by_name(tmp_path):
    import os

    fifo = tmp_path / "pipe.bdm"
    os.mkfifo(fifo)
    for path in (fifo, Path("/dev/zero")):
        with pytest.raises(CorpusError, match="not a regular file"):
            read_bdm(path)


@pytest.mark.parametrize("command", ["show", "tasks"])
def test_a_state_file_with_a_byte_order_mark_reads_and_an_empty_one_is_said_empty(tmp_path, capsys, command):
    from groundlang.cli import main

    line = (Path(__file__).parent / "fixtures" / "williams2018" / "one.state").read_bytes()
    marked, empty = tmp_path / "marked.state", tmp_path / "empty.state"
    marked.write_bytes(b"\xef\xbb\xbf" + line)
    empty.write_bytes(b"\xef\xbb\xbf \n\n")
    assert main([command, str(marked)]) == 0  # the Williams format, found behind the mark: no --palette
    capsys.readouterr()
    assert main([command, str(empty)]) == 2
    assert capsys.readouterr().err == f"groundlang {command}: error: {empty}: the file is empty; expected one state line\n"


def test_tasks_reads_a_burlap_state_line_with_the_corpus_domain_by_default(capsys):
    # A one-line .state file in the Williams et al. format works without --palette and --library: the
    # palette williams2018 and its domain's relations and tasks are the defaults for it.
    from groundlang.cli import main

    import json

    fixtures = Path(__file__).parent / "fixtures"
    assert main(["tasks", str(fixtures / "williams2018" / "one.state"), "--json"]) == 0
    shown = json.loads(capsys.readouterr().out)
    assert {"agentNextToToy", "agentLeftOfToy", "agentRightOfToy"} <= set(shown["lifted_tasks"])
    assert main(["tasks", str(fixtures / "small.state")]) == 2
    assert "--palette is required for a state in the corpus's format" in capsys.readouterr().err


@pytest.mark.parametrize("command", [["check"], ["train", "-o", "model"], ["evaluate", "--holdout", "0.5", "--corpus"]])
def test_a_folder_of_bdm_and_txt_corpus_files_is_refused_not_half_read(tmp_path, capsys, command):
    from groundlang.cli import main

    folder = tmp_path / "mixed"
    folder.mkdir()
    (folder / "small.bdm").write_bytes((FIXTURE / "small.bdm").read_bytes())
    (folder / "agent2blue_0.txt").write_text("go to the blue room\nnorth\n", encoding="utf-8")
    argv = [command[0], *command[1:], str(folder)]
    if command[0] == "train":
        argv = ["train", str(folder), "-o", str(tmp_path / "model")]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "holds both .bdm files and corpus files (*.txt)" in err
    assert not (tmp_path / "model").exists()


def test_a_json_result_that_cannot_be_written_names_the_path_given(tmp_path, capsys):
    from groundlang.cli import main

    small = str(FIXTURE / "small.bdm")
    assert main(["evaluate", "--corpus", small, "--test", small, "--json", "/proc/groundlang-test.json"]) == 2
    err = capsys.readouterr().err.strip()
    # Refused before any work, naming the path given (never a temporary file's).
    assert err == ("groundlang evaluate: error: --json /proc/groundlang-test.json: cannot create a file in /proc "
                   "(No such file or directory)")


def test_objects_are_ordered_by_the_number_in_their_name_however_long():
    """room10 after room9, and a name of thousands of digits is ordered, never converted to an int."""
    room = "{name} (room): [top: {{4}} left: {{{left}}} bottom: {{0}} right: {{{right}}} colour: {{red}} ]"
    rooms = [room.format(name=n, left=l, right=r) for n, l, r in
             (("room10", 0, 4), ("room" + "7" * 5000, 4, 8), ("room9", 8, 12))]
    state, _ = parse_bdm_state("{agent0 (agent): [x: {1} y: {1} ] , " + " , ".join(rooms) + " , }")
    assert [r.left for r in state.layout.rooms] == [8, 0, 4]


def test_a_world_error_names_objects_as_the_file_does():
    """The layout numbers a file's room0, room1, room3 as its rooms 0 to 2; an error about the third names room3,
    the object a user can find in the line, and a block the file calls block7 is block7 in the message."""
    room = "{name} (room): [top: {{4}} left: {{{left}}} bottom: {{0}} right: {{{right}}} colour: {{red}} ]"
    rooms = [room.format(name=n, left=l, right=r) for n, l, r in (("room0", 0, 4), ("room1", 4, 8), ("room3", 6, 12))]
    with pytest.raises(CorpusError, match=r"^here: room1 and room3 overlap$"):
        parse_bdm_state("{agent0 (agent): [x: {1} y: {1} ] , " + " , ".join(rooms) + " , }", where="here")
    block = "block7 (block): [x: {4} y: {0} shape: {chair} colour: {red} ]"
    with pytest.raises(CorpusError, match=r"^here: block7 at \(4,0\) is inside a wall or outside every room$"):
        parse_bdm_state("{me (agent): [x: {1} y: {1} ] , " + " , ".join(rooms[:2]) + " , " + block + " , }",
                        where="here")


def test_a_bdm_file_of_commands_where_one_state_is_wanted_is_said_to_be_one():
    small = Path(__file__).parent / "fixtures" / "williams2018" / "small.bdm"
    with pytest.raises(CorpusError, match=r"small\.bdm: a \.bdm file of commands \(line 1 is not a state line\); "
                                          r"expected one state line"):
        read_initial_state(small, "williams2018")


def test_a_layout_too_large_to_tabulate_is_set_aside_by_file_and_line_and_counted(tmp_path, capsys):
    """A pair in a layout too large for PF tables is skipped by training and check (counted, named) and followed by
    evaluate as skipped, counted wrong: never a stop for the whole corpus, never dropped silently."""
    from groundlang.cli import main

    line = (Path(__file__).parent / "fixtures" / "williams2018" / "one.state").read_text().strip()
    agent = line.split(" , ")[0]
    big = agent + " , room0 (room): [top: {200} left: {0} bottom: {0} right: {200} colour: {red} ] , }"
    moved = big.replace(agent, agent.replace("x: {2}", "x: {3}"))
    (tmp_path / "big.bdm").write_text(f"go right\n{big}\n{moved}\ntrue\n")
    small = Path(__file__).parent / "fixtures" / "williams2018" / "small.bdm"
    mixed = tmp_path / "mixed"
    mixed.mkdir()
    (mixed / "small.bdm").write_text(small.read_text())
    (mixed / "big.bdm").write_text((tmp_path / "big.bdm").read_text())

    assert main(["check", str(mixed)]) == 0
    out = capsys.readouterr().out
    assert (f"pairs in a layout too large to tabulate (training skips them): 1\n  {mixed / 'big.bdm'}, line 2: "
            "this layout has 39,601 walkable cells; PFs are tabulated for at most 4,096") in out
    assert "commands whose pairs show no task: 0" in out  # what it cannot read is not said to show nothing

    assert main(["train", str(mixed), "-o", str(tmp_path / "m")]) == 0
    assert "6 pairs used; pairs skipped: 1 too large to tabulate" in capsys.readouterr().out

    assert main(["evaluate", "--corpus", str(small), "--test", str(mixed), "--json", str(tmp_path / "e.json")]) == 0
    out = capsys.readouterr().out
    assert "executions skipped (too large even for the relevance abstraction, or to tabulate; counted wrong above): 1" in out
    report = json.loads((tmp_path / "e.json").read_text())
    assert report["executions_n"] == 7 and report["skipped_executions"] == 1
    row, = [r for r in report["executions"] if r["command"] == "go right"]
    assert row["correct"] is False and row["failure"] == "skipped" and row["final_state"] is None
    assert row["skipped"].startswith(f"{mixed / 'big.bdm'}, line 2: this layout has 39,601 walkable cells")
    # a command whose other pair shows no task is not scored: its skipped execution is not counted wrong either
    (tmp_path / "no_task.bdm").write_text(f"stay\n{line}\n{line}\ntrue\n---\n{big}\n{moved}\ntrue\n")
    assert main(["evaluate", "--corpus", str(small), "--test", str(tmp_path / "no_task.bdm"), "--json",
                 str(tmp_path / "n.json")]) == 0
    assert "executions skipped" not in capsys.readouterr().out
    report = json.loads((tmp_path / "n.json").read_text())
    assert report["executions_n"] == 0 and report["skipped_executions"] == 0 and report["no_task_commands"] == 1


def test_follow_refuses_a_layout_too_large_to_tabulate_by_its_file_at_once(tmp_path, capsys):
    """It had grounded the layout until the time limit ran out (10 s), then advised a longer one."""
    from groundlang.cli import main

    line = (Path(__file__).parent / "fixtures" / "williams2018" / "one.state").read_text().strip()
    big = line.split(" , ")[0] + " , room0 (room): [top: {200} left: {0} bottom: {0} right: {200} colour: {red} ] , }"
    (tmp_path / "big.state").write_text(big + "\n")
    small = Path(__file__).parent / "fixtures" / "williams2018" / "small.bdm"
    assert main(["--quiet", "train", str(small), "-o", str(tmp_path / "m")]) == 0
    capsys.readouterr()
    assert main(["follow", "go right", "--env", str(tmp_path / "big.state"), "--model", str(tmp_path / "m")]) == 2
    assert capsys.readouterr().err == (f"groundlang follow: error: {tmp_path / 'big.state'}: this layout has 39,601 "
                                       "walkable cells; PFs are tabulated for at most 4,096 (every movable object is "
                                       "copied onto each cell)\n")


def test_check_bounds_what_a_reader_of_words_could_get_right(tmp_path):
    """Commands that share a text but whose pairs show different tasks: one answer per text can do what at most
    one group of them shows. Copies that agree count in full; a text given once is not counted."""
    largest, chair = (FIXTURE / "small.bdm").read_text(encoding="utf-8").split("\n\n")
    chair_body = chair.split("\n", 1)[1]
    noisy = "\n\n".join([largest, largest, "go to the largest room\n" + chair_body, "go next to the chair\n" + chair_body])
    (tmp_path / "noisy.bdm").write_text(noisy, encoding="utf-8")
    done = subprocess.run([sys.executable, "-m", "groundlang.cli", "check", str(tmp_path / "noisy.bdm")],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert ("commands whose text another command shares: 3 (1 text); one task per text does what the pairs of "
            "at most 2 of them show (66.7%)") in done.stdout
    done = subprocess.run([sys.executable, "-m", "groundlang.cli", "check", str(FIXTURE / "small.bdm")],
                          capture_output=True, text=True)
    assert "another command shares" not in done.stdout  # no text is given twice


def test_covers_asks_each_relation_with_a_description_in_common():
    red = Atom("agentInRoom", ("agent", "roomIsRed"))
    large = Atom("agentInRoom", ("agent", "roomIsLargest"))
    beside = Atom("agentNextToToy", ("agent", "toyIsChair"))
    assert covers(frozenset({red, large}), frozenset({large}))  # one way of saying the room in common
    assert covers(frozenset({red, beside}), frozenset({red}))  # doing more still does it
    assert not covers(frozenset({red}), frozenset({red, beside}))  # a relation it does not do
    assert not covers(frozenset({red}), frozenset({large}))  # the same relation, nothing said alike


def test_format_williams2018_reads_a_file_of_any_name_and_a_folder_of_txt_files(tmp_path):
    """`--format williams2018` says the format, so the file is read whatever its name (a copy saved as .txt),
    and a folder without .bdm files gives its .txt files; without the flag only .bdm names are read so."""
    from groundlang.bdm import bdm_files
    from groundlang.pair_corpus import read_pair_corpus

    copy = tmp_path / "copy" / "small.txt"
    copy.parent.mkdir()
    copy.write_bytes((FIXTURE / "small.bdm").read_bytes())
    assert bdm_files(copy) == [] and bdm_files(copy, any_name=True) == [copy]
    assert bdm_files(copy.parent) == [] and bdm_files(copy.parent, any_name=True) == [copy]
    assert [c.text for c in read_pair_corpus(copy.parent, any_name=True).commands] == \
        ["go to the largest room", "go next to the chair"]
    with pytest.raises(CorpusError, match="no .bdm file there"):
        read_pair_corpus(copy)
    done = subprocess.run([sys.executable, "-m", "groundlang.cli", "check", str(copy), "--format", "williams2018"],
                          capture_output=True, text=True)
    assert done.returncode == 0 and "commands: 2 (2 distinct texts)" in done.stdout, done.stderr
    from groundlang.cli import main

    assert main(["--quiet", "train", str(copy), "--format", "williams2018", "-o", str(tmp_path / "model"),
                 "--no-cache"]) == 0
    assert (tmp_path / "model" / "model.json").is_file()


def test_the_published_figure_goes_with_the_corpus_library_only():
    from groundlang.bdm_check import default_library, is_corpus_library
    from groundlang.logic.tasks import TaskLibrary

    assert is_corpus_library(default_library()) and is_corpus_library(TaskLibrary.load(["williams2018"]))
    materials = Path(__file__).parent / "fixtures" / "materials" / "materials_pfs.lp"
    assert not is_corpus_library(TaskLibrary.load(["williams2018", str(materials)]))


def test_objects_sharing_a_cell_are_named_as_the_line_names_them():
    room = "room0 (room): [top: {4} left: {0} bottom: {0} right: {4} colour: {red} ]"
    block = "block3 (block): [x: {1} y: {1} shape: {chair} colour: {red} ]"
    with pytest.raises(CorpusError, match=r"^here: me and block3 share the cell \(1,1\)$"):
        parse_bdm_state("{me (agent): [x: {1} y: {1} ] , " + room + " , " + block + " , }", where="here")
