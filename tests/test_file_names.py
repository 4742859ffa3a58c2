"""A BURLAP state file's own names for its objects (``block3`` where the layout numbers it ``block1``): what
``follow``, ``tasks`` and ``show`` print names the objects as the file does."""

from __future__ import annotations

import json
import logging
import re
import subprocess
import sys
from pathlib import Path

import pytest

from groundlang.bdm import format_bdm_state, object_names, parse_bdm_state
from groundlang.corpus import file_names

FIXTURE = Path(__file__).parent / "fixtures" / "williams2018"
# The fixture's one-line state with its objects named as a file may: the chair block3, the rooms room4..room6
# (in the order of their numbers), the agent robot.
RENAMED = ((FIXTURE / "one.state").read_text().strip().replace("block0 (block)", "block3 (block)")
           .replace("room0 (room)", "room4 (room)").replace("room1 (room)", "room5 (room)")
           .replace("room2 (room)", "room6 (room)").replace("agent0 (agent)", "robot (agent)"))


def test_object_names_say_the_files_name_of_each_of_the_layouts_objects():
    assert object_names(RENAMED) == {"agent0": "robot", "room0": "room4", "room1": "room5", "room2": "room6",
                                     "door0": "door0", "door1": "door1", "block0": "block3"}


def test_a_state_written_with_the_files_names_reads_back_as_the_same_state_and_names():
    state, toys = parse_bdm_state(RENAMED)
    written = format_bdm_state(state, names=object_names(RENAMED))
    assert parse_bdm_state(written) == (state, toys) and object_names(written) == object_names(RENAMED)
    # without names, the layout's
    assert set(object_names(format_bdm_state(state)).values()) == {"agent0", "room0", "room1", "room2", "door0",
                                                                  "door1", "block0"}


def test_file_names_keeps_only_the_renamed_and_is_empty_for_the_corpus_format(tmp_path):
    path = tmp_path / "renamed.bdm"
    path.write_text(RENAMED + "\n")
    assert file_names(path) == {"agent0": "robot", "room0": "room4", "room1": "room5", "room2": "room6",
                                "block0": "block3"}
    assert file_names(FIXTURE / "one.state") == {}
    assert file_names(Path(__file__).parent / "fixtures" / "small.state") == {}


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "groundlang.cli", *args], capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("model") / "m"
    run = _cli("train", str(FIXTURE / "small.bdm"), "-o", str(out))
    assert run.returncode == 0, run.stderr
    return out


def test_follow_names_goals_and_the_final_state_as_the_file_does(tmp_path, model):
    env = tmp_path / "renamed.bdm"
    env.write_text(RENAMED + "\n")
    run = _cli("follow", "--model", str(model), "--env", str(env), "go next to the chair", "--json")
    assert run.returncode == 0, run.stderr
    data = json.loads(run.stdout)
    assert data["goal"] == "agentNextToToy(robot, block3)"
    named = {name for g in data["interpretations"] for name in re.findall(r"\w+(?=[,)])", g["goal"])}
    assert named <= {"robot", "room4", "room5", "room6", "block3"}  # no name the file does not have
    final, _ = parse_bdm_state(data["final_state"])
    assert object_names(data["final_state"]) == object_names(RENAMED)
    assert (final.agent.x, final.agent.y) != (2, 2)  # it moved, and the state is written in the file's names
    text = _cli("follow", "--model", str(model), "--env", str(env), "go next to the chair")
    assert "agentNextToToy(robot, block3): reached" in text.stdout and "block0" not in text.stdout


def test_what_planning_logs_names_objects_as_the_file_does(tmp_path, model):
    """In a 16x16 layout planning logs the abstraction it plans in ("moving agent0, block5"): the layout
    numbers the blocks from 0, and the log names the one it moves as the file does, as the goal beside it."""
    line = (Path(__file__).parent / "fixtures" / "large" / "sixteen.bdm").read_text().splitlines()[1]
    env = tmp_path / "sixteen.bdm"  # the corpus fixture's first start state as a one-line state file, its box block5
    env.write_text(line.replace("block1 (block)", "block5 (block)") + "\n")
    assert file_names(env) == {"block1": "block3", "block2": "block5"}
    run = _cli("follow", "--model", str(model), "--env", str(env), "--guess", "go next to the large box")
    assert run.returncode == 0, run.stderr
    (said,) = [t for t in run.stderr.splitlines() if t.startswith("state space: relevance abstraction")]
    moving = re.search(r"moving agent0((?:, block\d)*), \d toy\(s\) as walls", said).group(1)
    goal = re.search(r"^goal .*\((agent0, (block\d))\)", run.stdout, re.MULTILINE)
    assert goal.group(2) == "block5" and moving == ", block5"


def test_log_lines_are_renamed_only_within_the_context_and_by_whole_names(caplog):
    from groundlang.commands import logged_by_file_names

    log = logging.getLogger("groundlang.test")
    with caplog.at_level(logging.INFO, logger="groundlang"):
        with logged_by_file_names({"block2": "block3", "agent0": "robot"}):
            log.info("moving %s, %s; %s", "agent0", "block2", "block20")
        log.info("moving agent0, block2")
    assert [r.getMessage() for r in caplog.records] == ["moving robot, block3; block20", "moving agent0, block2"]
    # a chain of renamings (block0 -> block1, block1 -> block2), read by two handlers: each name renamed once
    second = logging.Handler()
    seen = []
    second.emit = lambda record: seen.append(record.msg)  # the text the filter left (a bad call: its format)
    logging.getLogger().addHandler(second)
    caplog.clear()
    try:
        with caplog.at_level(logging.INFO, logger="groundlang"):
            with logged_by_file_names({"block0": "block1", "block1": "block2"}):
                log.info("moving block0 then block1")
    finally:
        logging.getLogger().removeHandler(second)
    assert seen[0] == "moving block1 then block2" and caplog.records[0].getMessage() == "moving block1 then block2"
    assert second.filters == [] and all(not h.filters for h in logging.getLogger().handlers)
    # a call whose arguments do not fit its format is left to logging (which says so and goes on), not raised
    from groundlang.commands import _FileNames

    bad = logging.LogRecord("groundlang", logging.INFO, __file__, 1, "block0 %d", ("x",), None)
    assert _FileNames({"block0": "block1"}).filter(bad) is True and bad.msg == "block0 %d"


def test_tasks_say_which_objects_they_renumbered_and_show_draws_the_files_names(tmp_path):
    env = tmp_path / "renamed.bdm"
    env.write_text(RENAMED + "\n")
    note = ("objects are numbered from 0 in each class here; in the file: agent0 is robot, room0 is room4, room1 is "
            "room5, room2 is room6, block0 is block3")
    run = _cli("tasks", str(env))
    assert run.returncode == 0 and note in run.stdout.splitlines(), run.stdout
    assert json.loads(_cli("tasks", str(env), "--json").stdout)["file_names"]["block0"] == "block3"
    shown = _cli("show", str(env))
    assert shown.returncode == 0 and "legend: # wall, + door, A robot" in shown.stdout, shown.stdout
    legend = shown.stdout.split("legend:")[1]
    assert "block3 (" in legend and "room4 (" in legend and "block0" not in legend and "room0" not in legend
    assert "numbered from 0" not in _cli("show", str(FIXTURE / "one.state")).stdout


def test_a_picture_of_a_burlap_state_names_its_objects_as_the_file_does(tmp_path):
    pytest.importorskip("matplotlib")
    from groundlang.corpus import file_names, read_state_file
    from groundlang.render import draw_state

    env = tmp_path / "renamed.bdm"
    env.write_text(RENAMED + "\n")
    ax = draw_state(read_state_file(env, "williams2018"), names=file_names(env))
    drawn = {t.get_text() for t in ax.texts} | {t.get_text() for t in ax.get_legend().get_texts()}
    assert {"room4", "room5", "room6"} <= drawn and any(t.startswith("block3 (") for t in drawn)
    assert not any(t.startswith(("block0", "room0", "agent0")) for t in drawn)


def test_two_chairs_told_apart_by_id_are_named_and_answered_by_the_files_names(tmp_path, model):
    """Where two objects read alike the words carry their ids: those too are the file's, and an answer naming
    one by the file's name acts on that one (the file's block1 is the layout's block0, its block2 block1)."""
    chairs = (FIXTURE / "one.state").read_text().strip().replace(
        "block0 (block): [x: {2} y: {6} shape: {chair} colour: {green} ]",
        # each in a corner, where no push moves it: no state is next to both, which would satisfy either reading
        "block1 (block): [x: {1} y: {7} shape: {chair} colour: {green} ] , "
        "block2 (block): [x: {7} y: {1} shape: {chair} colour: {green} ]")
    env = tmp_path / "chairs.bdm"
    env.write_text(chairs + "\n")
    asked = _cli("follow", "--model", str(model), "--env", str(env), "go next to the chair", "--json")
    data = json.loads(asked.stdout)
    assert "the green chair block1 or the green chair block2" in data["question"]
    assert {(c["words"], c["goal"]) for c in data["choices"]} == {
        ("the green chair block1", "agentNextToToy(agent0, block1)"),
        ("the green chair block2", "agentNextToToy(agent0, block2)")}
    for answer, goal in (("the green chair block2", "block2"), ("the green chair block1", "block1")):
        run = subprocess.run([sys.executable, "-m", "groundlang.cli", "follow", "--model", str(model), "--env",
                              str(env), "go next to the chair", "--ask"], input=answer + "\n", capture_output=True,
                             text=True, timeout=600)
        assert run.returncode == 0, run.stderr
        assert f"goal the agent next to the green chair {goal} — agentNextToToy(agent0, {goal}): reached" in run.stdout


def test_a_very_long_name_is_drawn_shortened(tmp_path):
    """A file may name an object with 60,000 letters; drawn whole, the legend widened the picture to match
    (420,331 pixels). The text output keeps the name whole."""
    pytest.importorskip("matplotlib")
    from groundlang.corpus import file_names, read_state_file
    from groundlang.render import draw_state

    env = tmp_path / "long.bdm"
    env.write_text(RENAMED.replace("block3", "b" * 60_000) + "\n")
    ax = draw_state(read_state_file(env, "williams2018"), names=file_names(env))
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(t.startswith("b" * 39 + "\u2026 (") for t in labels) and max(map(len, labels)) < 100
