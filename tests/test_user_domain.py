"""A domain authored in data files only: a palette, PFs, tasks and words a user writes, end to end.

Nothing in groundlang's Python names what these files add: a toy shape ("mug"), a PF of two objects
used as a goal (agentNextToToy: the agent on one of the eight cells around a toy), a superlative PF
(roomIsLargest, by area) and the words for them. The learner trains on a handful of commands with
planner-made demonstrations and follows new commands, in a layout it never saw, whose meaning needs
each of them.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from groundlang import Learner
from groundlang.corpus import Instance, parse_state
from groundlang.labels import goal_holds
from groundlang.logic.atoms import parse_goal
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.pf_tables import pf_tables
from groundlang.model.world import get_palette

PALETTE = """\
% A toy shop: three colours, stars and mugs.
value(colour, 0, red). value(colour, 1, green). value(colour, 2, blue).
value(shape, 0, star). value(shape, 1, mug).
"""

PFS = """\
% The agent on one of the eight cells around a toy.
pf(position, agentNextToToy, (agent, toy)).
holds(agentNextToToy, (A, T)) :- agent(A), toy(T), at(A, X, Y), at(T, U, V),
                                 |X - U| <= 1, |Y - V| <= 1, |X - U| + |Y - V| > 0.
% The room of the largest area (superlatives are PFs like any other).
pf(size, roomIsLargest, (room,)).
area(R, (Rt - L) * (T - B)) :- room(R), rect(R, L, T, Rt, B).
holds(roomIsLargest, (R,)) :- area(R, A), A = #max { A2 : area(_, A2) }.
"""

TASKS = """\
task(agentToRoom). var(agentToRoom, "A", agent). var(agentToRoom, "R", room).
goal(agentToRoom, agentInRoom, ("A", "R")).
task(toyToRoom). var(toyToRoom, "T", toy). var(toyToRoom, "R", room).
goal(toyToRoom, toyInRoom, ("T", "R")).
task(agentToToy). var(agentToToy, "A", agent). var(agentToToy, "T", toy).
goal(agentToToy, agentNextToToy, ("A", "T")).
"""

WORDS = """\
# The toy shop's words ("mug" and "star" are also the palette's shapes: the schema names them).
NOUN: mugs
ADJ: largest biggest
PREP: beside
"""

# room,COLOUR,LEFT,TOP,RIGHT,BOTTOM; door,LEFT,TOP,RIGHT,BOTTOM; block,COLOUR,SHAPE,X,Y; agent,X,Y.
# Colours: red 0, green 1, blue 2; shapes: star 0, mug 1. Three rooms in a row, one of them wide.
LAYOUT_A = "room,0,0,4,4,0 room,1,4,4,12,0 room,2,12,4,16,0 door,4,2,4,2 door,12,2,12,2"  # green largest
LAYOUT_B = "room,0,0,4,8,0 room,1,8,4,12,0 room,2,12,4,16,0 door,8,2,8,2 door,12,2,12,2"  # red largest
LAYOUT_C = "room,2,0,4,8,0 room,0,8,4,12,0 room,1,12,4,16,0 door,8,2,8,2 door,12,2,12,2"  # blue largest

TRAINING = [  # (layout, star, mug, agent, command, goal)
    (LAYOUT_A, (13, 1), (6, 3), (2, 2), "go to the largest room", "agentInRoom(agent0, room1)"),
    (LAYOUT_A, (13, 1), (6, 3), (14, 2), "go to the red room", "agentInRoom(agent0, room0)"),
    (LAYOUT_A, (13, 1), (10, 1), (2, 2), "go next to the mug", "agentNextToToy(agent0, block1)"),
    (LAYOUT_A, (6, 2), (13, 3), (2, 1), "take the star to the blue room", "toyInRoom(block0, room2)"),
    (LAYOUT_B, (2, 3), (14, 1), (10, 2), "go to the largest room", "agentInRoom(agent0, room0)"),
    (LAYOUT_B, (2, 3), (14, 1), (6, 2), "go to the green room", "agentInRoom(agent0, room1)"),
    (LAYOUT_B, (2, 3), (14, 1), (10, 2), "go next to the star", "agentNextToToy(agent0, block0)"),
    (LAYOUT_B, (6, 1), (10, 2), (14, 2), "take the mug to the red room", "toyInRoom(block1, room0)"),
    (LAYOUT_B, (2, 3), (6, 1), (10, 3), "go to the blue room", "agentInRoom(agent0, room2)"),
    (LAYOUT_A, (6, 1), (10, 2), (14, 2), "move the mug to the red room", "toyInRoom(block1, room0)"),
]


def state(layout: str, star, mug, agent, palette):
    return parse_state(f"{layout} block,0,0,{star[0]},{star[1]} block,2,1,{mug[0]},{mug[1]} "
                       f"agent,{agent[0]},{agent[1]}", palette)


@pytest.fixture(scope="module")
def domain(tmp_path_factory):
    folder = tmp_path_factory.mktemp("toyshop")
    # The words sit beside the PF file they name things of (pfs.words beside pfs.lp).
    for name, text in (("toyshop.lp", PALETTE), ("pfs.lp", PFS), ("tasks.lp", TASKS), ("pfs.words", WORDS)):
        (folder / name).write_text(text, encoding="utf-8")
    return folder


@pytest.fixture(scope="module")
def library(domain):
    return TaskLibrary.load([domain / "pfs.lp", domain / "tasks.lp"])


@pytest.fixture(scope="module")
def trained(domain, library, tmp_path_factory, shortest_plan):
    palette = str(domain / "toyshop.lp")
    instances = []
    for n, (layout, star, mug, agent, command, goal) in enumerate(TRAINING):
        start = state(layout, star, mug, agent, palette)
        assert not goal_holds(parse_goal(goal), start, library), command
        states, actions = shortest_plan(start, parse_goal(goal), library)
        instances.append(Instance(Path(f"shop{n}.txt"), command, tuple(actions), tuple(states)))
    learner = Learner(library=library, cache_dir=tmp_path_factory.mktemp("cache"), steps=200)
    return learner.fit(instances), palette


def test_the_words_come_from_the_files_and_the_schema(trained):
    learner, _ = trained
    lexicon = learner.word_lexicon
    assert lexicon.listed("mugs") == {"NOUN"} and lexicon.listed("largest") == {"ADJ"}  # pfs.words
    assert "NOUN" in lexicon.listed("mug")  # the palette's shape, named by the schema
    assert "PREP" in lexicon.listed("next_to")  # closed-class English
    assert learner.lexicon_words["NOUN"][:1] == ["mugs"]  # saved with the model


def test_the_palette_file_is_read(domain):
    palette = get_palette(str(domain / "toyshop.lp"))
    assert (palette.name, palette.colours, palette.shapes) == ("toyshop", ("red", "green", "blue"), ("star", "mug"))


def test_user_pfs_are_tabulated_and_described(domain, library):
    start = state(LAYOUT_C, (10, 2), (2, 3), (14, 2), str(domain / "toyshop.lp"))
    tables = pf_tables(start.layout, library.tabulation_program)
    assert "agentNextToToy" in tables.tabulated and tables.signatures["roomIsLargest"] == ("room",)
    # The superlative holds of the blue room only, in every state.
    from groundlang.logic.atoms import Atom

    assert [r for r in ("room0", "room1", "room2") if tables.column(Atom("roomIsLargest", (r,)), start.positions[None])[0]] == ["room0"]
    # Next to: the eight cells around the mug at (2, 3) that the agent can stand on.
    movers, grid = tables.grids[Atom("agentNextToToy", ("agent0", "block1"))]
    assert movers == (0, 2) and grid.shape == start.layout.walkable.shape * 2
    assert {(x, y) for x, y in zip(*np.nonzero(grid[:, :, 2, 3]))} == {(1, 2), (1, 3), (2, 2), (3, 2), (3, 3)}


def test_follows_new_commands_in_a_new_layout(trained, library):
    learner, palette = trained
    unseen = [  # (star, mug, agent, command, goal); layout C: blue is the largest room
        ((10, 2), (2, 3), (14, 2), "go to the largest room", "agentInRoom(agent0, room0)"),
        ((10, 2), (2, 3), (14, 2), "go next to the mug", "agentNextToToy(agent0, block1)"),
        ((2, 3), (10, 2), (14, 1), "go next to the mug", "agentNextToToy(agent0, block1)"),
        ((10, 2), (2, 3), (6, 1), "go to the green room", "agentInRoom(agent0, room2)"),
    ]
    for star, mug, agent, command, goal in unseen:
        start = state(LAYOUT_C, star, mug, agent, palette)
        result = learner.follow(command, start)
        assert result.reached and goal_holds(parse_goal(goal), result.final_state, library), (command, result.goal)


def test_tasks_lists_the_user_pfs_per_object(domain):
    env = domain / "c.state"
    env.write_text(f"{LAYOUT_C} block,0,0,10,2 block,2,1,2,3 agent,3,2\n", encoding="utf-8")
    done = subprocess.run([sys.executable, "-m", "groundlang.cli", "tasks", str(env), "--palette",
                           str(domain / "toyshop.lp"), "--library", str(domain / "pfs.lp"), "--library", str(domain / "tasks.lp")],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "room0: colour roomIsBlue; size roomIsLargest" in done.stdout
    assert "block1: colour toyIsBlue; shape toyIsMug" in done.stdout
    assert "agentToToy: agentNextToToy(agent0, block0)" in done.stdout  # the mug is next to it already
    relations = done.stdout.split("PFs of two or more objects")[1]
    assert "block1: toyInRoom(block1, room0), agentNextToToy(agent0, block1)" in relations


def test_the_schema_is_read_from_the_files(domain, library):
    from groundlang.logic.schema import domain_schema

    schema = domain_schema(library, str(domain / "toyshop.lp"))
    assert schema.classes == ("agent", "toy", "room", "door") and schema.movable == {"agent", "toy"}
    assert schema.values == {"colour": ("red", "green", "blue"), "shape": ("star", "mug")}
    assert [d.name for d in schema.pfs_of_class("position")] == [
        "agentInRoom", "toyInRoom", "agentInDoor", "toyInDoor", "agentTouchingToy", "agentNextToToy"]
    assert [str(d) for d in schema.pfs_of_class("size")] == ["roomIsLargest(room) [size]"]
    assert [d.name for d in schema.pfs_of_class("shape")] == ["toyIsStar", "toyIsMug"]
    assert [t.name for t in schema.tasks] == ["agentToRoom", "agentToToy", "toyToRoom"]
    done = subprocess.run([sys.executable, "-m", "groundlang.cli", "domain", "--palette", str(domain / "toyshop.lp"),
                           "--library", str(domain / "pfs.lp"), "--library", str(domain / "tasks.lp")],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "  size (property): roomIsLargest(room)" in done.stdout
    assert "  shape (property): toyIsStar(toy), toyIsMug(toy)" in done.stdout
    assert "  position (goal): agentInRoom(agent, room)" in done.stdout
    assert [schema.roles.part(c) for c in ("position", "spatial", "size")] == ["goal", "viewpoint", "property"]


def test_the_worlds_kinds_of_object_are_the_classes_domain_lp_declares():
    from groundlang.logic.classes import domain_classes
    from groundlang.model.world import TOY_CLASS, WORLD_CLASSES, object_class

    classes = domain_classes()
    assert set(WORLD_CLASSES) == set(classes.classes)
    assert classes.movable == {"agent", TOY_CLASS} and classes.addressee == {"agent"}
    assert classes.mentioned == {TOY_CLASS}
    assert [object_class(n) for n in ("agent0", "room12", "door0", "block3")] == ["agent", "room", "door", "toy"]
    with pytest.raises(ValueError):
        object_class("blocky")


def test_parse_reads_the_words_beside_the_library(domain):
    """``parse --library`` parses as a learner trained with that library: its word file's nouns are nouns."""
    def readings(*library):
        done = subprocess.run([sys.executable, "-m", "groundlang.cli", "parse", "go to the biggest mugs", *library],
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        return [line.strip() for line in done.stdout.splitlines()[1:]]

    # Without the file "mugs" is an unknown word, read as a noun or as a modifier of an elided one.
    assert readings() == ["0.667  go(mugs1), P1(mugs1, biggest)", "0.333  go(mugs1), P1(mugs1, biggest), P2(mugs1, mugs)"]
    assert readings("--library", str(domain / "pfs.lp")) == ["1.000  go(mugs1), P1(mugs1, biggest)"]


def test_a_word_file_beside_a_library_that_is_not_a_file_is_refused_not_passed_over(tmp_path, capsys):
    """``mine.words`` beside ``mine.lp`` is read with the library; a folder of that name is refused in one line,
    as ``--lexicon`` refuses it (it was silently ignored, and the words it was meant to add were missing)."""
    from groundlang.cli import main

    library = tmp_path / "mine.lp"
    library.write_text('task(t). var(t, "A", agent). var(t, "R", room). goal(t, agentInRoom, ("A", "R")).\n')
    (tmp_path / "mine.words").mkdir()
    assert main(["--quiet", "parse", "--library", str(library), "go"]) == 2
    assert capsys.readouterr().err == f"groundlang parse: error: {tmp_path / 'mine.words'}: Is a directory\n"


def test_a_position_pf_that_reads_another_objects_position_is_refused_by_tasks_and_train(tmp_path, capsys):
    """Tabulated with every other object standing everywhere, such a PF held wherever the cell east of the
    agent is walkable, while the state's own grounding said it did not: `tasks` listed it both ways."""
    from groundlang.cli import main
    from groundlang.corpus import example_corpus_path

    near = tmp_path / "near.lp"
    near.write_text('pf(position, agentNearToy, (agent, toy)).\n'
                    'holds(agentNearToy, (A, T)) :- agent(A), toy(T), at(A, X, Y), toy(T2), at(T2, X+1, Y).\n'
                    'task(near). var(near, "A", agent). var(near, "T", toy).\n'
                    'goal(near, agentNearToy, ("A", "T")).\n', encoding="utf-8")
    state = example_corpus_path() / "novel_b.state"
    assert main(["tasks", str(state), "--palette", "sokoban", "--library", "tasks", "--library", str(near)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "agentNearToy(agent0, block0) does not hold in the state, but its table" in err
    assert err.startswith(f"groundlang tasks: error: {near}: ") and err.rstrip().endswith(f"(in the layout of {state})")
    assert "a position PF may read the positions (at/3) of its own arguments only" in err
    # train refuses it too, naming the file of the first state in whose layout the table and grounding disagree
    # (it trained silently on tables that said otherwise than the groundings)
    corpus = example_corpus_path()
    assert main(["train", str(corpus), "--palette", "sokoban", "--library", "tasks", "--library", str(near), "-o",
                 str(tmp_path / "m")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "groundlang train: error: " in err and ".txt" in err
    assert "a position PF may read the positions (at/3) of its own arguments only" in err
    assert not (tmp_path / "m").exists()
    near.write_text(near.read_text().replace("toy(T2), at(T2, X+1, Y)", "at(T, X+1, Y)"), encoding="utf-8")
    assert main(["tasks", str(state), "--palette", "sokoban", "--library", "tasks", "--library", str(near)]) == 0
