"""What a domain author writes wrong, in a task library or a palette, is refused in one line naming the file
and what is wrong, before it can train a model on something else than was meant."""

from __future__ import annotations

import re
from importlib.resources import files
from pathlib import Path

import pytest

from groundlang.corpus import example_corpus_path, read_state_file
from groundlang.logic.palette_files import PaletteError, read_palette
from groundlang.logic.program import AspError
from groundlang.logic.sources import file_source
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.pf_tables import TabulationError, pf_tables

STATE = example_corpus_path() / "novel_a.state"
_SOKOBAN = Path(str(files("groundlang.logic"))) / "palettes" / "sokoban.lp"


def _library(tmp_path, text: str, name: str = "mine.lp") -> TaskLibrary:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return TaskLibrary([file_source(path)])


def test_a_task_named_as_a_constant_and_as_a_string_is_refused(tmp_path):
    """task(t) and task("t") are two atoms of one name: their variables were mixed (KeyError: 'A')."""
    text = ('task(t). var(t, "A", agent). var(t, "R", room). goal(t, agentInRoom, ("A", "R")).\n'
            'task("t"). var("t", "B", agent). var("t", "Q", room). goal("t", agentInRoom, ("B", "Q")).\n')
    with pytest.raises(AspError, match=r'mine.lp: task t is declared twice, as task\(t\) and task\("t"\)'):
        _library(tmp_path, text)


def test_a_pf_of_more_objects_than_the_domain_reads_is_refused_by_its_arity(tmp_path):
    """It had been said to have "no argument of a class that moves", though it had an agent and a toy."""
    text = ("pf(position, agentWithAll, (agent, toy, toy, room)).\n"
            "holds(agentWithAll, (A, T, U, R)) :- agent(A), toy(T), toy(U), room(R), T != U.\n")
    with pytest.raises(AspError, match=r"mine.lp: .*PF agentWithAll has 4 arguments; a PF relates 1 to 3 objects"):
        _library(tmp_path, text)


@pytest.mark.parametrize("rule, message", [
    # the objects not written as a tuple: an AttributeError from inside the table's reader
    ("pf(position, agentNear, (agent,)). holds(agentNear, A) :- agent(A), at(A, X, Y), X > 3.",
     r"mine.lp: holds\(agentNear,v\(agent0,\d+,\d+\)\): the objects of holds/2 must be a tuple"),
    # said of doors, declared over rooms: the error named no file
    ("pf(position, agentNear, (agent, room)). holds(agentNear, (A, D)) :- agent(A), at(A, X, Y), door_cell(D, X, Y).",
     r"mine.lp: holds\(agentNear, \(agent0, door\d\)\): door\d is a door, but pf/3 declares agentNear over "
     r"\(agent, room\)"),
    # a colour PF of toys said of rooms: silently never true of a toy
    ("pf(colour, toyBright, (toy,)). holds(toyBright, (R,)) :- room(R).",
     r"mine.lp: holds\(toyBright, \(room\d,\)\): room\d is a room, but pf/3 declares toyBright over \(toy,\)"),
])
def test_a_pf_whose_rules_disagree_with_its_declaration_is_named_with_its_file(tmp_path, rule, message):
    library = _library(tmp_path, rule + "\n")
    state = read_state_file(STATE, "sokoban")
    with pytest.raises(TabulationError, match=message):
        pf_tables(state.layout, library.tabulation_program)


def test_a_palette_value_of_two_attributes_is_refused(tmp_path):
    """A shape called red made toyIs(red) both a colour PF and a shape PF: a yellow toy was listed as red."""
    palette = tmp_path / "clash.lp"
    palette.write_text(_SOKOBAN.read_text().replace("value(shape, 0, star).", "value(shape, 0, red)."))
    with pytest.raises(PaletteError, match=r"clash.lp: red is both a colour and a shape"):
        read_palette(str(palette))


@pytest.mark.parametrize("glyph", ['""', '" "'])
def test_an_empty_glyph_is_refused_where_the_palette_is_read(tmp_path, glyph):
    """It had failed only when drawing, with matplotlib's mathtext error naming no file."""
    palette = tmp_path / "blank.lp"
    palette.write_text(_SOKOBAN.read_text() + f"glyph(star, {glyph}).\n")
    with pytest.raises(PaletteError, match=r"blank.lp: glyph\(star,\"\s?\"\): the text is empty"):
        read_palette(str(palette))


def test_a_glyph_given_twice_is_refused_and_a_negative_index_is_named(tmp_path):
    """One of two glyphs had won silently; an index of -1 was reported as a gap at the end of the indices."""
    palette = tmp_path / "twice.lp"
    palette.write_text(_SOKOBAN.read_text() + 'glyph(star, "S").\n')  # the file gives star a glyph already
    with pytest.raises(PaletteError, match=r'twice.lp: glyph\(star, \.\.\.\) is given twice, "[^"]+" and "[^"]+"; '
                                           r"keep one"):
        read_palette(str(palette))
    palette.write_text(_SOKOBAN.read_text() + "value(colour, -1, pink).\n")
    with pytest.raises(PaletteError, match=r"twice.lp: value\(colour,-1,pink\): an index is 0 or more"):
        read_palette(str(palette))


def test_a_goal_over_a_viewpoint_pf_is_refused_at_load(tmp_path):
    """A side seen from the agent is no goal (tabulate.lp tabulates goal classes only): it had loaded, and
    every follow then said no reachable state satisfies it."""
    with pytest.raises(AspError, match=r"mine.lp: task t: goal doorWestOfAgent is not a declared PF of a goal class"):
        _library(tmp_path, 'task(t). var(t, "D", door). goal(t, doorWestOfAgent, ("D",)).\n')



@pytest.mark.parametrize("language_model", ["parse", "bow"])
def test_a_demonstration_no_task_explains_is_named_for_every_language_model(tmp_path, language_model):
    """One room, the agent in it: the parse model (which keeps goals that hold at the start, for
    "... and come back") had failed with "max() arg is an empty sequence"; bow named the file."""
    from groundlang.corpus import read_corpus
    from groundlang.learner import Learner
    from groundlang.model.interpretations import NoTaskError

    folder = tmp_path / "oneroom"
    folder.mkdir()
    (folder / "agent2blue_0.txt").write_text("go to the blue room\nnorth,south\nroom,1,0,4,4,0 agent,1,1\n"
                                             "room,1,0,4,4,0 agent,1,2\nroom,1,0,4,4,0 agent,1,1\n")
    corpus = read_corpus(folder, "sokoban")
    with pytest.raises(NoTaskError, match=r"oneroom/agent2blue_0.txt: no task of the library"):
        Learner(language_model, steps=5, cache_dir=False).fit(corpus.instances)


def test_a_library_of_many_facts_loads_and_its_rules_are_still_placed_by_file_and_line(tmp_path):
    """Ground facts are not walked to name their places (a library of 40,000 facts had taken a minute and
    then been refused as a solve over its time limit); a rule's messages still name its file and line."""
    facts = "".join(f"fact({i}, \"x\", f(a)).\n" for i in range(20_000))
    library = _library(tmp_path, facts + 'task(t). var(t, "A", agent). var(t, "R", room). '
                                          'goal(t, agentInRoom, ("A", "R")).\n')
    assert [t.name for t in library.tasks] == ["t"]
    with pytest.raises(AspError, match=r"mine.lp:20002:\d+-\d+: error: unsafe variables"):
        _library(tmp_path, facts + "fact(0, x, f(a)).\nbad(X) :- fact(0, _, _).\n")


def test_a_task_declared_in_two_files_is_refused_naming_both(tmp_path):
    """A user's agentToRoom beside the package's had joined it: "go to the red room" planned for the agent in
    the red room and the star in another."""
    path = tmp_path / "mine.lp"
    path.write_text('task(agentToRoom). var(agentToRoom, "T", toy). var(agentToRoom, "Q", room).\n'
                    'goal(agentToRoom, toyInRoom, ("T", "Q")).\n')
    with pytest.raises(AspError, match=r"task agentToRoom is declared in both groundlang.logic/tasks.lp and "
                                       r".*mine.lp: its atoms would join into one task"):
        TaskLibrary.load(["tasks", path])
    assert [t.name for t in TaskLibrary.load([path]).tasks] == ["agentToRoom"]  # alone, it is the user's own


@pytest.mark.parametrize("declaration, message", [
    ("viewpoint_class(position).", r"mine.lp: PF class position is declared both goal_class and viewpoint_class"),
    ('goal_class("position").', r'mine.lp: goal_class\("position"\): a PF class is a name as pf/3 writes it'),
])
def test_the_part_of_a_pf_class_is_declared_once_and_by_name(tmp_path, declaration, message):
    """A class of two parts was described by neither and related by neither; a quoted class name is one
    the rules of groundings.lp would read as another class than pf/3's."""
    with pytest.raises(AspError, match=message):
        _library(tmp_path, declaration + '\ntask(t). var(t, "A", agent). var(t, "R", room). '
                                          'goal(t, agentInRoom, ("A", "R")).\n')


def test_a_goal_class_whose_pfs_no_move_can_change_is_refused_when_tabulated(tmp_path):
    library = _library(tmp_path, "goal_class(colour).\n")
    state = read_state_file(STATE, "sokoban")
    with pytest.raises(TabulationError, match=r"mine.lp: PF roomIsBlack is of a goal class .* but has no argument "
                                              r"of a class that moves \(agent, toy\)"):
        pf_tables(state.layout, library.tabulation_program)


def test_a_property_pf_that_reads_where_things_stand_is_refused(tmp_path):
    """A side of the agent declared in a class of its own with no viewpoint_class/1 had silently become a
    binding constraint: objects bound by where they happened to be at the start."""
    rule = "pf(bearing, toyEastOfAgent, (toy,)). holds(toyEastOfAgent, (T,)) :- toy(T), at(T, X, _), agent(A), " \
           "at(A, U, _), X > U.\n"
    state = read_state_file(STATE, "sokoban")
    with pytest.raises(TabulationError, match=r"mine.lp: PF toyEastOfAgent is of a property class .* changes as "
                                              r"objects move; declare its class with viewpoint_class/1"):
        pf_tables(state.layout, _library(tmp_path, rule).tabulation_program)
    viewpoint = _library(tmp_path, "viewpoint_class(bearing).\n" + rule, "mine2.lp")
    assert "toyEastOfAgent" in viewpoint.spatial_pfs
    pf_tables(state.layout, viewpoint.tabulation_program)  # read as a side of the agent, it is no property


def test_a_library_and_a_palette_with_a_byte_order_mark_read_as_without(tmp_path):
    """Corpus, word and state files read past a leading BOM; .lp files were refused at its character."""
    task = 'task(go). var(go, "A", agent). var(go, "R", room). goal(go, agentInRoom, ("A", "R")).\n'
    (tmp_path / "bom.lp").write_bytes(b"\xef\xbb\xbf" + task.encode())
    assert TaskLibrary.load([str(tmp_path / "bom.lp")]).names == TaskLibrary.load([_write(tmp_path, task)]).names
    (tmp_path / "palette.lp").write_bytes(b"\xef\xbb\xbf" + _SOKOBAN.read_bytes())
    assert read_palette(str(tmp_path / "palette.lp"))[1] == read_palette(str(_SOKOBAN))[1]


def _write(tmp_path, text: str) -> str:
    path = tmp_path / "plain.lp"
    path.write_text(text, encoding="utf-8")
    return str(path)


def test_a_pf_said_of_fewer_objects_than_declared_is_refused_in_every_layout(tmp_path):
    """holds(toyNextToDoor, (T,)) for a PF over (toy, door): groundings.lp names it only where it holds at the
    start; train had stopped with "toyNextToDoor(block0) has 1 arguments", naming no file."""
    library = _library(tmp_path, "pf(position, toyNextToDoor, (toy, door)).\n"
                                 "holds(toyNextToDoor, (T,)) :- toy(T), at(T, X, Y), door_cell(_, X + 1, Y).\n")
    state = read_state_file(STATE, "sokoban")
    with pytest.raises(TabulationError, match=r"mine.lp: holds\(toyNextToDoor, \(block0,\)\) says it of 1 object, "
                                              r"but pf/3 declares toyNextToDoor over \(toy, door\)"):
        pf_tables(state.layout, library.tabulation_program)


@pytest.mark.parametrize("rule, hint", [
    ("holds(toyNearDoor, T, D) :- toy(T), door(D).", r"a rule says holds/3 of it, but holds takes the PF and the "
                                                      r"tuple of its objects, holds\(toyNearDoor, \(A, B\)\)"),
    ("holds(toyNearDor, (T, D)) :- toy(T), door(D).", r"add holds\(toyNearDoor, \(A, B\)\) :- \.\.\. for it"),
])
def test_a_pf_no_rule_says_where_it_holds_is_refused_at_load(tmp_path, rule, hint):
    """A PF written holds/3 (or misspelt) never held anywhere, and a model trained on it without a word."""
    text = "pf(position, toyNearDoor, (toy, door)).\n" + rule + "\n"
    with pytest.raises(AspError, match=r"mine.lp: PF toyNearDoor is declared \(pf/3\) but no rule says where it "
                                       r"holds; " + hint):
        _library(tmp_path, text)
    # a PF family (roomIs(C)) and a holds/2 head whose PF is a variable are said to hold
    _library(tmp_path, "pf(colour, toyTinted(C), (toy,)) :- palette_colour(C).\n"
                       "holds(toyTinted(C), (T,)) :- toy(T), colour(T, C).\n")
    _library(tmp_path, "pf(position, toyNearDoor, (toy, door)).\nholds(P, (T, D)) :- P = toyNearDoor, toy(T), door(D).\n")
    # nor are a #const naming it, or an #external
    _library(tmp_path, "#const near = toyNearDoor.\npf(position, toyNearDoor, (toy, door)).\n"
                       "holds(near, (T, D)) :- toy(T), door(D), at(T, X, Y), beside(X, Y, U, V), door_cell(D, U, V).\n")
    _library(tmp_path, "pf(position, toyNearDoor, (toy, door)).\n#external holds(toyNearDoor, (block0, door0)).\n")


def test_the_commands_that_read_a_library_refuse_its_mistakes_as_train_does(tmp_path, capsys):
    """check, domain and tasks had passed (exit 0) what train refused: a goal-class PF nothing moves (tasks
    printed it as "not listed", as if the layout were too large), a PF said of too few objects, and a
    malformed word file beside the library."""
    from groundlang.cli import main

    corpus = example_corpus_path()
    still = tmp_path / "still.lp"
    still.write_text("pf(position, roomIsBig, (room,)).\nholds(roomIsBig, (R,)) :- room(R).\n")
    fewer = tmp_path / "fewer.lp"
    fewer.write_text("pf(position, toyNextToDoor, (toy, door)).\n"
                     "holds(toyNextToDoor, (T,)) :- toy(T), at(T, X, Y), door_cell(_, X + 1, Y).\n")
    for argv in (["tasks", str(STATE), "--palette", "sokoban"], ["check", str(corpus), "--palette", "sokoban"],
                 ["domain", "--palette", "sokoban"]):
        assert main([*argv, "--library", "tasks", "--library", str(still)]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith(f"groundlang {argv[0]}: error: {still}: PF roomIsBig is of a goal class") and "\n" not in err
    for argv in (["tasks", str(STATE), "--palette", "sokoban"], ["check", str(corpus), "--palette", "sokoban"]):
        assert main([*argv, "--library", "tasks", "--library", str(fewer)]) == 2
        err = capsys.readouterr().err.strip()
        assert f"{fewer}: holds(toyNextToDoor, (block0,)) says it of 1 object" in err and "(in the layout of " in err
    words = tmp_path / "mine"
    words.mkdir()
    (words / "mine.lp").write_text("pf(colour, toyBright, (toy,)). holds(toyBright, (T,)) :- toy(T), colour(T, red).\n")
    (words / "mine.words").write_text("NOUN: mug\nCOLOUR: lilac\n")
    for argv in (["tasks", str(STATE), "--palette", "sokoban"], ["check", str(corpus), "--palette", "sokoban"],
                 ["domain"]):
        assert main([*argv, "--library", "tasks", "--library", str(words / "mine.lp")]) == 2
        err = capsys.readouterr().err.strip()
        assert "mine.words" in err and ":2: unknown category 'COLOUR'" in err, err


def test_check_grounds_a_library_given_in_each_layout_as_train_does(tmp_path, capsys):
    """A PF over a class no object has passed check (a .txt corpus or a .bdm one), and a .bdm check never read
    the word file beside a library; train refused both."""
    from groundlang.cli import main

    fixtures = Path(__file__).parent / "fixtures"
    no_class = str(fixtures / "bad_input" / "pf_of_no_class.lp")
    for argv in (["check", str(example_corpus_path()), "--palette", "sokoban", "--library", "tasks"],
                 ["check", str(fixtures / "williams2018" / "small.bdm"), "--library", "williams2018"]):
        assert main([*argv, "--library", no_class]) == 2
        err = capsys.readouterr().err.strip()
        assert "PF toyHue(" in err and "is declared over class lamp, which no object has" in err, err
        assert "(in the layout of " in err and "\n" not in err
    words = tmp_path / "mine"
    words.mkdir()
    (words / "mine.lp").write_text("pf(colour, toyBright, (toy,)). holds(toyBright, (T,)) :- toy(T), colour(T, red).\n")
    (words / "mine.words").write_text("BOGUS: x\n")
    assert main(["check", str(fixtures / "williams2018" / "small.bdm"), "--library", "williams2018",
                 "--library", str(words / "mine.lp")]) == 2
    assert "mine.words:1: unknown category 'BOGUS'" in capsys.readouterr().err


@pytest.mark.parametrize("text, message", [
    # classical negation: -agentInRoom had been read as agentInRoom, a task meaning the opposite of what was written
    ('task(t1). var(t1, "A", agent). var(t1, "R", room). goal(t1, -agentInRoom, ("A", "R")).\n',
     r"mine.lp: PF name -agentInRoom is negated"),
    ('task(-t1). var(-t1, "A", agent). var(-t1, "R", room). goal(-t1, agentInRoom, ("A", "R")).\n',
     r"mine.lp: task\(-t1\): a task's name is negated"),
    ('pf(position, "AgentIn", (agent, room)).\n', r'mine.lp: PF name "AgentIn" must be a constant'),  # named its file
])
def test_a_negated_or_malformed_name_is_refused_naming_the_file(tmp_path, text, message):
    with pytest.raises(AspError, match=message):
        _library(tmp_path, text)


def test_a_pf_declared_again_with_other_classes_is_refused_naming_both_files(tmp_path):
    """It loaded, and a later error blamed a task of tasks.lp for its goal's classes."""
    path = tmp_path / "mine.lp"
    path.write_text("pf(position, agentInRoom, (agent, toy)).\n", encoding="utf-8")
    with pytest.raises(AspError, match=r"^PF agentInRoom is declared as pf\(position, agentInRoom, \(agent, room\)\) in "
                                       r"groundlang.logic/pfs.lp and as pf\(position, agentInRoom, \(agent, toy\)\) in "
                                       r".*mine.lp"):
        TaskLibrary.load(["tasks", path])
    path.write_text("pf(position, agentInRoom, (agent, toy)) :- #true.\n", encoding="utf-8")  # a rule's head too
    with pytest.raises(AspError, match=r"^PF agentInRoom is declared as .* and as pf\(position, agentInRoom, "
                                       r"\(agent, toy\)\) in .*mine.lp"):
        TaskLibrary.load(["tasks", path])
    path.write_text("pf(position, agentInRoom, (agent, room)).\n", encoding="utf-8")  # the same again: no conflict
    assert "agentToRoom" in TaskLibrary.load(["tasks", path]).names


@pytest.mark.parametrize("text, atom", [
    ("movable(room).\n", "movable(room): movable/1"),  # domain.lp writes movable(agent; toy): a pool, read as two
    ("walkable(X, Y) :- X = 0..3, Y = 0..3.\n", "walkable(X,Y): walkable/2"),
    ("class(ghost).\n", "class(ghost): class/1"),
    ("room(ghost).\n", "room(ghost): room/1 is a fact of the layout"),  # what the layout gives, too
    ("at(agent0, 1, 1) :- agent(agent0).\n", "at(agent0,1,1): at/3 is a fact of the layout"),
])
def test_a_library_that_adds_to_the_domains_own_predicates_is_refused(tmp_path, text, atom):
    """The world's moves are code that reads the layout: a room made movable or cells made walkable in ASP had
    trained without a word, its PF tables disagreeing with the moves."""
    with pytest.raises(AspError, match=rf"mine.lp: {re.escape(atom)}( is the domain's own \(groundlang.logic/domain.lp\))?"):
        _library(tmp_path, text)
