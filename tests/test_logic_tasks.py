"""Lifted task library, groundings and binding constraints (logic.tasks, model.tasks, `groundlang tasks`)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from groundlang.logic.atoms import Atom
from groundlang.logic.program import AspError, AspScriptRefused, AspSyntaxError
from groundlang.logic.groundings import binding_constraints, enumerate_groundings, ground_environment
from groundlang.logic.tasks import BindingConstraint, GroundedTask, LiftedTask, TaskLibrary, Variable, format_lifted_task
from groundlang.model.world import get_palette

# Two rooms (green room0 west, blue room1 east) joined by a door at (4,2); two toys:
# block0 a yellow star in room0, block1 a red moon in room1; the agent in room0.
TWO_TOYS = """
palette_colour(blue; green; red; yellow). palette_shape(star; moon).
room(room0). rect(room0, 0, 4, 4, 0). colour(room0, green).
room(room1). rect(room1, 4, 4, 8, 0). colour(room1, blue).
door(door0). rect(door0, 4, 2, 4, 2).
toy(block0). colour(block0, yellow). shape(block0, star). at(block0, 2, 2).
toy(block1). colour(block1, red). shape(block1, moon). at(block1, 6, 2).
agent(agent0). at(agent0, 1, 1).
"""
# The same without block1.
ONE_TOY = "\n".join(line for line in TWO_TOYS.splitlines() if "block1" not in line) + "\n"
NO_TOYS = """
palette_colour(blue; green). palette_shape(star).
room(room0). rect(room0, 0, 4, 4, 0). colour(room0, green).
room(room1). rect(room1, 4, 4, 8, 0). colour(room1, blue).
door(door0). rect(door0, 4, 2, 4, 2).
agent(agent0). at(agent0, 4, 2).
"""


def A(text: str) -> Atom:
    pred, args = text.rstrip(")").split("(")
    return Atom(pred, tuple(a.strip() for a in args.split(",")))


@pytest.fixture(scope="module")
def library() -> TaskLibrary:
    return TaskLibrary.load()


def test_default_library_lifted_tasks(library):
    assert library.tasks == (
        LiftedTask("agentToRoom", (Variable("A", "agent"), Variable("R", "room")),
                   (("agentInRoom", ("A", "R")),)),
        LiftedTask("toyToRoom", (Variable("T", "toy"), Variable("R", "room")),
                   (("toyInRoom", ("T", "R")),)),
        LiftedTask("toyToRoomAgentToRoom",
                   (Variable("A", "agent"), Variable("T", "toy"), Variable("RA", "room"), Variable("RT", "room")),
                   (("agentInRoom", ("A", "RA")), ("toyInRoom", ("T", "RT")))),
    )


def test_two_toy_groundings_in_order(library):
    found = enumerate_groundings(library, TWO_TOYS)
    assert [(g.task, g.goal_text) for g, _ in found] == [
        ("agentToRoom", "agentInRoom(agent0, room1)"),
        ("toyToRoom", "toyInRoom(block0, room1)"),
        ("toyToRoom", "toyInRoom(block1, room0)"),
        ("toyToRoomAgentToRoom", "agentInRoom(agent0, room0) toyInRoom(block0, room1)"),
        ("toyToRoomAgentToRoom", "agentInRoom(agent0, room1) toyInRoom(block0, room0)"),
        ("toyToRoomAgentToRoom", "agentInRoom(agent0, room1) toyInRoom(block1, room0)"),
    ]
    g, constraints = found[1]
    assert g == GroundedTask("toyToRoom", (("T", "block0"), ("R", "room1")), (A("toyInRoom(block0, room1)"),))
    assert [tuple(str(a) for a in c.atoms) for c in constraints] == [
        ("toyIsStar(block0)", "toyIsYellow(block0)", "roomIsBlue(room1)"),
        ("toyIsStar(block0)", "toyIsYellow(block0)"),
        ("toyIsStar(block0)", "roomIsBlue(room1)"),
        ("toyIsYellow(block0)", "roomIsBlue(room1)"),
        ("toyIsStar(block0)",),
        ("toyIsYellow(block0)",),
        ("roomIsBlue(room1)",),
        (),
    ]
    assert found[0][1] == [BindingConstraint((A("roomIsBlue(room1)"),)), BindingConstraint(())]
    # conjunction: toy (2 PFs) + two rooms (1 each) -> 2^4 conjunctions, none mentions an unbound object
    g, constraints = found[5]
    assert dict(g.binding) == {"A": "agent0", "T": "block1", "RA": "room1", "RT": "room0"}
    assert len(constraints) == 16 and constraints[-1].atoms == ()
    assert set(constraints[0].atoms) == {A("toyIsRed(block1)"), A("toyIsMoon(block1)"),
                                         A("roomIsBlue(room1)"), A("roomIsGreen(room0)")}


def test_task_already_true_initially_is_excluded(library):
    goals = {g.goal_text for g, _ in enumerate_groundings(library, TWO_TOYS)}
    assert "agentInRoom(agent0, room0)" not in goals  # the agent starts in room0
    assert "toyInRoom(block0, room0)" not in goals and "toyInRoom(block1, room1)" not in goals
    # both conjuncts true initially: agent in room0 and block1 in room1
    assert "agentInRoom(agent0, room0) toyInRoom(block1, room1)" not in goals
    # only one conjunct true initially: still a task
    assert "agentInRoom(agent0, room0) toyInRoom(block0, room1)" in goals


def test_task_needing_an_absent_class_is_not_permissible(library):
    found = enumerate_groundings(library, NO_TOYS)  # the agent stands in the door: in no room
    assert [(g.task, g.goal_text) for g, _ in found] == [
        ("agentToRoom", "agentInRoom(agent0, room0)"),
        ("agentToRoom", "agentInRoom(agent0, room1)"),
    ]


def test_user_task_added_by_rules_only():
    lib = TaskLibrary.from_text(
        '% agentToDoor(A, D): the agent stands in door D\n'
        'task(agentToDoor). var(agentToDoor, "A", agent). var(agentToDoor, "D", door).\n'
        'goal(agentToDoor, agentInDoor, ("A", "D")).\n', "door.lp")
    assert lib.names == ["agentToDoor"]
    found = enumerate_groundings(lib, TWO_TOYS)
    assert [g.goal_text for g, _ in found] == ["agentInDoor(agent0, door0)"]
    assert found[0][1] == [BindingConstraint(())]  # doors have no colour or shape PFs
    assert enumerate_groundings(lib, NO_TOYS) == []  # the agent is already in the door


def test_distinct_variables_of_one_class_take_distinct_objects():
    lib = TaskLibrary.from_text(
        'task(swap). var(swap, "T1", toy). var(swap, "T2", toy). var(swap, "R1", room). var(swap, "R2", room).\n'
        'goal(swap, toyInRoom, ("T1", "R2")). goal(swap, toyInRoom, ("T2", "R1")).\n', "swap.lp")
    found = enumerate_groundings(lib, TWO_TOYS)
    # 2 orders of toys x 2 orders of rooms; two of the four bindings say "block0 in room0 and
    # block1 in room1", which holds initially
    assert len(found) == 2
    assert {g.goal_text for g, _ in found} == {"toyInRoom(block0, room1) toyInRoom(block1, room0)"}
    for g, _ in found:
        b = dict(g.binding)
        assert b["T1"] != b["T2"] and b["R1"] != b["R2"]


def test_lifted_tasks_round_trip_through_asp(library):
    text = "".join(format_lifted_task(t) for t in library.tasks)
    assert TaskLibrary.from_text(text).tasks == library.tasks
    assert TaskLibrary.from_tasks(library.tasks).tasks == library.tasks


@pytest.mark.parametrize("text, message", [
    ('task(t). var(t, "A", agent). goal(t, agentInRoom, ("A", "R")).', r"uses variable 'R'"),
    ('task(t). var(t, "A", agent). var(t, "B", agent). goal(t, agentInRoom, ("A", "B")).', r"classes \('agent', 'room'\)"),
    ('task(t). var(t, "A", agent).', r"task t has no goal"),
    ('var(t, "A", agent).', r"names no task\(t\)"),
])
def test_malformed_library_is_an_asp_error(text, message):
    with pytest.raises(AspError, match=message):
        TaskLibrary.from_text(text, "bad.lp")


def test_library_syntax_error_and_script(tmp_path):
    path = tmp_path / "lib.lp"
    path.write_text('task(t).\nvar(t, "A" agent).\n')
    with pytest.raises(AspSyntaxError, match=rf"{path}:2:"):
        TaskLibrary.load([path])
    with pytest.raises(AspScriptRefused):
        TaskLibrary.from_text("#script (python)\n#end.\n", "s.lp")


def test_binding_constraints_are_all_subsets_largest_first():
    atoms = [A("toyIsStar(block0)"), A("roomIsRed(room1)"), A("toyIsRed(block0)")]
    cs = binding_constraints(atoms)
    assert len(cs) == 8 and len(set(cs)) == 8
    assert [len(c.atoms) for c in cs] == [3, 2, 2, 2, 1, 1, 1, 0]
    assert binding_constraints([]) == [BindingConstraint(())]
    # indexed as listed, from either end and by slices, without making the others
    assert [cs[i] for i in range(-8, 8)] == list(cs) * 2 and cs[2:5] == list(cs)[2:5] and cs.largest == cs[0]
    with pytest.raises(IndexError):
        cs[8]
    many = binding_constraints(A(f"roomIsRed(room{k})") for k in range(40))  # 2^40: made only as read
    assert len(many) == 2 ** 40 and len(many[0].atoms) == 40 and many[-1].atoms == () and many[1].atoms[-1] == A("roomIsRed(room38)")
    # past what len() can hold (63 atoms and more) it is read all the same, its size said by count
    huge = binding_constraints(A(f"roomIsRed(room{k})") for k in range(70))
    assert huge and huge.count == 2 ** 70 and huge[0] == huge.largest and huge[-1].atoms == () and huge == huge
    with pytest.raises(TypeError, match="whole numbers"):
        cs[1.5]
    assert cs != tuple(cs) and cs == list(cs)  # equal to the list it replaced; a tuple's hash would disagree


def test_a_library_of_many_properties_is_refused_by_enumerating_models_and_bounded_for_the_parse_model(tmp_path, capsys):
    # 22 colours of the library's own on every room: 2^23 conjunctions per grounding had been built for
    # every grounding (memory without bound, past any --time-limit); now the parse model reads the largest
    # and a model that offers every conjunction as a reading is refused with one line
    library = tmp_path / "many.lp"
    library.write_text('task(t).\nvar(t, "A", agent).\nvar(t, "R", room).\ngoal(t, agentInRoom, ("A", "R")).\n'
                       "pf(colour, roomIsX(N), (room,)) :- N = 1..22.\nholds(roomIsX(N), (R,)) :- room(R), N = 1..22.\n")
    wide = tmp_path / "wide.lp"  # 70 of its own: more conjunctions than len() can say
    wide.write_text(library.read_text().replace("1..22", "1..69"))
    from groundlang.cli import main
    from groundlang.corpus import example_corpus_path, read_state_file
    from groundlang.model.interpretations import interpretations
    state = read_state_file(example_corpus_path() / "novel_a.state", "sokoban")
    lib = TaskLibrary.load([str(library)])
    read = interpretations(state, lib, enumerate_constraints=False)
    assert len(read) == 3 and all(len(i.constraint.atoms) == 23 for i in read)
    with pytest.raises(ValueError, match=r"23 property PFs, and this language model offers each of their 8,388,608 "
                                         r"conjunctions .* at most 12 PFs"):
        interpretations(state, lib, enumerate_constraints=True)
    read = interpretations(state, TaskLibrary.load([str(wide)]), enumerate_constraints=False)
    assert len(read) == 3 and all(len(i.constraint.atoms) == 70 for i in read)
    assert main(["tasks", str(example_corpus_path() / "novel_a.state"), "--palette", "sokoban", "--library", str(wide),
                 "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)["groundings"][0]
    assert listed["constraint_count"] == 2 ** 70 and len(listed["constraints"]) == 1 and len(listed["constraints"][0]) == 70


# --- model.tasks: the adapter for a model.world.State -------------------------------------------

def two_toy_state():
    from groundlang.model.world import Agent, Door, Layout, Room, State, Toy, get_palette

    layout = Layout((Room("green", 0, 4, 4, 0), Room("blue", 4, 4, 8, 0)), (Door(4, 2, 4, 2),),
                    (("yellow", "star"), ("red", "moon")), get_palette("sokoban"))
    return State(layout, Agent(1, 1), (Toy("yellow", "star", 2, 2), Toy("red", "moon", 6, 2)))


def test_candidate_tasks_for_a_state_match_the_asp_case(library):
    from groundlang.model.tasks import candidate_tasks

    found = candidate_tasks(two_toy_state(), library)
    expected = enumerate_groundings(library, TWO_TOYS)
    assert [g for g, _ in found] == [g for g, _ in expected]
    assert [c for _, c in found] == [c for _, c in expected]


def test_narrow_by_known_star_toy_leaves_a_uniform_room_choice():
    from groundlang.model.tasks import candidate_tasks, narrow_by_known
    from groundlang.model.world import Agent, Door, Layout, Room, State, Toy, get_palette

    # The paper's "new colour name": three rooms, a star and a moon; "the star" and the task are known.
    layout = Layout((Room("green", 0, 4, 4, 0), Room("red", 4, 4, 8, 0), Room("blue", 0, 8, 8, 4)),
                    (Door(4, 2, 4, 2), Door(2, 4, 2, 4)), (("yellow", "star"), ("red", "moon")),
                    get_palette("sokoban"))
    state = State(layout, Agent(1, 1), (Toy("yellow", "star", 2, 3), Toy("red", "moon", 6, 2)))
    candidates = candidate_tasks(state, TaskLibrary.load())
    narrowed = narrow_by_known(candidates, {"T": {"toyIsStar"}}, task="toyToRoom")
    assert [n.grounded.goal_text for n in narrowed] == ["toyInRoom(block0, room1)", "toyInRoom(block0, room2)"]
    assert [n.probability for n in narrowed] == [0.5, 0.5]
    for n in narrowed:  # every kept constraint mentions the star; the room's colour stays open
        assert all(A("toyIsStar(block0)") in c.atoms for c in n.constraints)
        assert len(n.constraints) == 4
    # without the task, the conjunction's groundings of the star survive too; agentToRoom has no T
    wide = narrow_by_known(candidates, {"T": {"toyIsStar"}})
    assert {n.grounded.task for n in wide} == {"toyToRoom", "toyToRoomAgentToRoom"}
    assert all(dict(n.grounded.binding)["T"] == "block0" for n in wide)
    assert sum(n.probability for n in wide) == pytest.approx(1.0)
    assert narrow_by_known(candidates, {"T": {"toyIsSquare"}}) == []


def test_cli_tasks_json(tmp_path, capsys):
    from groundlang.cli import main
    from groundlang.corpus import format_state

    path = tmp_path / "two.state"
    path.write_text(format_state(two_toy_state()) + "\n")
    assert main(["tasks", str(path), "--palette", "sokoban", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["lifted_tasks"] == ["agentToRoom", "toyToRoom", "toyToRoomAgentToRoom"]
    assert out["groundings"][0] == {"task": "agentToRoom", "goal": "agentInRoom(agent0, room1)",
                                    "constraints": [["roomIsBlue(room1)"], []], "constraint_count": 2}
    assert len(out["groundings"]) == 6
    # the agent at (1,1), the door at (4,2)
    assert list(out["descriptions"]) == ["room0", "room1", "door0", "block0", "block1"]  # the layout's order
    assert out["descriptions"] == {
        "room0": {"colour": ["roomIsGreen"]},
        "room1": {"colour": ["roomIsBlue"]},
        "door0": {"spatial": ["doorEastOfAgent", "doorNorthOfAgent"]},
        "block0": {"colour": ["toyIsYellow"], "shape": ["toyIsStar"]},
        "block1": {"colour": ["toyIsRed"], "shape": ["toyIsMoon"]},
    }


def test_cli_tasks_bad_library_is_one_line(tmp_path, capsys):
    from groundlang.cli import main
    from groundlang.corpus import format_state

    state = tmp_path / "two.state"
    state.write_text(format_state(two_toy_state()) + "\n")
    lib = tmp_path / "bad.lp"
    lib.write_text("task(t).\n#script (python)\n#end.\n")
    assert main(["tasks", str(state), "--palette", "sokoban", "--library", str(lib)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{lib}:2:" in err[0] and "#script" in err[0]


def test_cli_tasks_runaway_library_stops_at_the_time_limit(tmp_path, capsys):
    from groundlang.cli import main
    from groundlang.corpus import format_state

    state = tmp_path / "two.state"
    state.write_text(format_state(two_toy_state()) + "\n")
    lib = tmp_path / "forever.lp"
    lib.write_text('task(t). var(t, "A", agent). var(t, "R", room). goal(t, agentInRoom, ("A", "R")).\n'
                   "n(1). n(X+1) :- n(X).\n")
    assert main(["tasks", str(state), "--palette", "sokoban", "--library", str(lib), "--time-limit", "0.5"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "forever.lp" in err[0] and "did not finish within 0.5 s" in err[0]


def test_restricted_task_grounds_only_objects_with_the_pf_and_round_trips():
    from groundlang.corpus import example_corpus_path, read_state_file
    from groundlang.model.tasks import candidate_tasks

    text = ('task(starToRed). var(starToRed, "T", toy). var(starToRed, "R", room). '
            'goal(starToRed, toyInRoom, ("T", "R")). restrict(starToRed, "R", roomIs(red)).')
    library = TaskLibrary.from_text(text)
    assert library.tasks[0].restrictions == (("R", "roomIs(red)"),)
    assert TaskLibrary.from_text(library.to_lp()).tasks == library.tasks
    state = read_state_file(example_corpus_path() / "novel_a.state", "sokoban")
    red = next(f"room{i}" for i, r in enumerate(state.layout.rooms) if r.colour == "red")
    goals = [g.goal_text for g, _ in candidate_tasks(state, library)]
    assert goals == [f"toyInRoom(block0, {red})"]


def test_restriction_on_an_undeclared_variable_is_refused():
    text = ('task(t). var(t, "T", toy). var(t, "R", room). goal(t, toyInRoom, ("T", "R")). '
            'restrict(t, "X", toyIs(star)).')
    with pytest.raises(AspError, match="restrict uses variable 'X'"):
        TaskLibrary.from_text(text)


_TOY_TO_ROOM = 'task(toyToRoom). var(toyToRoom, "T", toy). var(toyToRoom, "R", room). goal(toyToRoom, toyInRoom, ("T", "R")).\n'


@pytest.mark.parametrize("restriction, pieces", [
    # a position PF: where an object ends up is the goal's business
    ('restrict(toyToRoom, "R", toyInRoom).',
     ('restrict(toyToRoom, "R", toyInRoom)', "toyInRoom is a position PF", "needs a property PF")),
    # a spatial PF: where an object lies seen from the agent is no property it keeps
    ('restrict(toyToRoom, "T", doorWestOfAgent).',
     ('restrict(toyToRoom, "T", doorWestOfAgent)', "doorWestOfAgent is a spatial PF")),
    # a colour PF of rooms on a toy variable
    ('restrict(toyToRoom, "T", roomIs(red)).',
     ('restrict(toyToRoom, "T", roomIs(red))', "roomIs(red) is a colour PF of arguments (room,)",
      "variable 'T' is a toy")),
    # a shape PF of toys on a room variable
    ('restrict(toyToRoom, "R", toyIs(star)).',
     ('restrict(toyToRoom, "R", toyIs(star))', "variable 'R' is a room")),
])
def test_restriction_by_a_pf_that_is_not_a_colour_or_shape_pf_of_its_variable_is_refused(tmp_path, restriction, pieces):
    path = tmp_path / "mine.lp"
    path.write_text(_TOY_TO_ROOM + restriction + "\n")
    with pytest.raises(AspError) as caught:
        TaskLibrary.load([path])
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: task toyToRoom: ")  # the user's file, not groundlang's own sources
    for piece in pieces:
        assert piece in message


def test_restriction_by_a_colour_or_shape_pf_of_the_library_or_its_variable_class_loads():
    # Palette values need not be known at load time (grounding refuses roomIs(mauve) where the palette lacks it);
    # a user's own colour PF, declared beside the tasks, restricts like pfs.lp's.
    library = TaskLibrary.from_text(
        _TOY_TO_ROOM + 'restrict(toyToRoom, "R", roomIs(mauve)). restrict(toyToRoom, "T", toyIs(star)).\n'
        'restrict(toyToRoom, "T", toyIsShiny).\n'
        'pf(colour, toyIsShiny, (toy,)). holds(toyIsShiny, (T,)) :- toy(T), colour(T, yellow).\n', "mine.lp")
    assert library.tasks[0].restrictions == (("R", "roomIs(mauve)"), ("T", "toyIs(star)"), ("T", "toyIsShiny"))
    shiny = TaskLibrary.from_text(
        _TOY_TO_ROOM + 'restrict(toyToRoom, "T", toyIsShiny).\n'
        'pf(colour, toyIsShiny, (toy,)). holds(toyIsShiny, (T,)) :- toy(T), colour(T, yellow).\n', "shiny.lp")
    assert [g.goal_text for g, _ in enumerate_groundings(shiny, TWO_TOYS)] == ["toyInRoom(block0, room1)"]


_AGENT_TO_ROOM = 'task(agentToRoom). var(agentToRoom, "A", agent). var(agentToRoom, "R", room). goal(agentToRoom, agentInRoom, ("A", "R")).\n'
# A PF class of the user's own, true of yellow toys.
_SHINY_TOYS = "pf(material, toyIsShiny, (toy,)). holds(toyIsShiny, (T,)) :- toy(T), colour(T, yellow).\n"


def _descriptions(library, facts):
    """What groundings.lp says words may say of each object (the second part of ground_environment)."""
    return ground_environment(library, facts)[1]


def test_spatial_pfs_describe_objects_but_never_bind_them(library):
    """Spatial PFs (pfs.lp) are read per environment for the language model and stay out of C."""
    assert library.spatial_pfs == ("doorEastOfAgent", "doorNorthOfAgent", "doorSouthOfAgent", "doorWestOfAgent")
    # agent at (1,1), door0 at (4,2): east and north of the agent
    described = _descriptions(library, TWO_TOYS)
    assert described["door0"] == {"spatial": ("doorEastOfAgent", "doorNorthOfAgent")}
    assert described["block1"] == {"colour": ("toyIsRed",), "shape": ("toyIsMoon",)}
    assert described["room0"] == {"colour": ("roomIsGreen",)}
    assert "agent0" not in described
    assert "door0" not in _descriptions(library, NO_TOYS)  # the agent stands in the door
    doors = TaskLibrary.from_text(
        'task(agentToDoor). var(agentToDoor, "A", agent). var(agentToDoor, "D", door).'
        ' goal(agentToDoor, agentInDoor, ("A", "D")).'
    )
    ((grounded, constraints),) = enumerate_groundings(doors, TWO_TOYS)
    assert grounded.goal_text == "agentInDoor(agent0, door0)"
    assert constraints == [BindingConstraint(())]  # a side is not a binding constraint


def test_descriptions_ignore_what_a_user_library_shows_and_non_unary_spatial_pfs():
    mine = TaskLibrary.from_text(
        _AGENT_TO_ROOM + ' #show var/3.'
        ' pf(spatial, near, (agent, door)). holds(near, (A, D)) :- agent(A), door(D).'
    )
    assert mine.spatial_pfs == ("doorEastOfAgent", "doorNorthOfAgent", "doorSouthOfAgent", "doorWestOfAgent")
    assert _descriptions(mine, TWO_TOYS)["door0"] == {"spatial": ("doorEastOfAgent", "doorNorthOfAgent")}
    assert not any("near" in names for d in _descriptions(mine, TWO_TOYS).values() for names in d.values())


def test_a_pf_class_a_user_library_declares_describes_bystanders_too():
    """What words may say of an object comes from clingo: a user's PF class describes every object it
    holds of, bound or not (bound objects also through the binding constraints)."""
    shiny = TaskLibrary.from_text(_AGENT_TO_ROOM + _SHINY_TOYS)
    described = _descriptions(shiny, TWO_TOYS)
    assert described["block0"] == {"colour": ("toyIsYellow",), "material": ("toyIsShiny",), "shape": ("toyIsStar",)}
    assert "material" not in described["block1"]

    from groundlang.model.interpretations import interpretations

    for interp in interpretations(two_toy_state(), shiny):  # agentToRoom: both toys are bystanders
        said = {rb.obj: rb.constraint_tokens for rb in interp.roles}
        assert set(said["block0"]) == {"toyIsYellow", "toyIsStar", "toyIsShiny"}
        assert set(said["block1"]) == {"toyIsRed", "toyIsMoon"}


def test_a_pf_that_only_describes_bystanders_gets_a_token_of_its_own():
    from groundlang.corpus import example_corpus_path, read_corpus
    from groundlang.learner import Learner

    shiny = TaskLibrary.from_text(_AGENT_TO_ROOM + _SHINY_TOYS)
    corpus = read_corpus(example_corpus_path(), "sokoban")
    toys = [i for i in corpus.instances if i.initial_state.toys and i.name.startswith("agent")]
    assert toys, "the example corpus has agent commands with a toy in the room"
    learner = Learner("parse", library=shiny, steps=5).fit(toys)
    assert learner.vocab.has_token("toyIsShiny")  # not read as NULL: words may learn it


def test_a_property_class_of_a_users_own_may_restrict_a_task():
    """A PF class that neither goal_class/1 nor viewpoint_class/1 declares is a property, as colour and shape
    are: restrict/3 may name its PFs (a size PF had been refused, "restrict needs a colour or shape PF")."""
    shiny = TaskLibrary.from_text(_TOY_TO_ROOM + 'restrict(toyToRoom, "T", toyIsShiny).\n' + _SHINY_TOYS)
    assert shiny.tasks[0].restrictions == (("T", "toyIsShiny"),)
    ((grounded, constraints),) = enumerate_groundings(shiny, TWO_TOYS)  # block0, the yellow star, in room0
    assert grounded.goal_text == "toyInRoom(block0, room1)"
    assert Atom("toyIsShiny", ("block0",)) in constraints[0].atoms


# A goal class and a viewpoint class of the library's own: beside a toy, and a toy east of the agent.
_OWN_PARTS = """goal_class(place). viewpoint_class(side).
pf(place, agentBesideToy, (agent, toy)).
holds(agentBesideToy, (A, T)) :- agent(A), toy(T), at(A, X, Y), beside(X, Y, U, V), at(T, U, V).
pf(side, toyEastOfAgent, (toy,)). holds(toyEastOfAgent, (T,)) :- toy(T), at(T, X, _), agent(A), at(A, U, _), X > U.
task(agentToToy). var(agentToToy, "A", agent). var(agentToToy, "T", toy). goal(agentToToy, agentBesideToy, ("A", "T")).
"""


def test_the_part_a_pf_class_plays_is_declared_in_asp():
    """goal_class/1 and viewpoint_class/1 (pfs.lp) say which PF classes goals are made of and which describe an
    object from where the agent stands; a library declares its own classes' parts with no Python edit."""
    from groundlang.model.pf_tables import pf_tables

    own = TaskLibrary.from_text(_OWN_PARTS)
    assert own.pf_roles.goal_classes == {"position", "place"}
    assert own.pf_roles.viewpoint_classes == {"spatial", "side"}
    assert "toyEastOfAgent" in own.spatial_pfs
    found = enumerate_groundings(own, TWO_TOYS)
    assert [g.goal_text for g, _ in found] == ["agentBesideToy(agent0, block0)", "agentBesideToy(agent0, block1)"]
    assert not any(a.predicate == "toyEastOfAgent" for _, cs in found for c in cs for a in c.atoms)  # no binding
    assert _descriptions(own, TWO_TOYS)["block1"]["side"] == ("toyEastOfAgent",)  # it describes
    tables = pf_tables(two_toy_state().layout, own.tabulation_program)
    assert "agentBesideToy" in tables.order  # tabulated over placements, so a plan can reach it
    assert not any(a.predicate == "toyEastOfAgent" for a in tables.static)
    with pytest.raises(AspError, match=r"goal agentBesideToy is not a declared PF of a goal class \(position\)"):
        TaskLibrary.from_text(_OWN_PARTS.replace("goal_class(place).", ""))


def test_cli_output_cut_short_by_its_reader_is_no_error(fixtures):
    """`groundlang tasks ... | head`: the reader leaves early; no error message, no traceback."""
    state = fixtures / "sokoban2_corpus" / "L1_novel.state"
    proc = subprocess.Popen([sys.executable, "-m", "groundlang.cli", "tasks", str(state), "--palette", "sokoban2"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # 12 kB of output will not fit the closed pipe
    err = proc.stderr.read().decode()
    assert proc.wait() == 1 and err == ""


def _sokoban_pfs(family: str, values) -> str:
    return ", ".join(sorted(f"{family}({v})" for v in values))


_SOKOBAN = get_palette("sokoban")


@pytest.mark.parametrize("term, tail", [
    # a palette value the palette lacks: no more a typo than a colour of another palette, until the palette is known
    ("toyIs(strar)", "it declares these of a toy: " + _sokoban_pfs("toyIs", _SOKOBAN.colours + _SOKOBAN.shapes)),
    ("roomIs(star)", "it declares these of a room: " + _sokoban_pfs("roomIs", _SOKOBAN.colours)),
    # groundlang's name instead of the family term pfs.lp declares
    ("toyIsStar", "write toyIs(star), the term pf/3 declares"),
    # a family no pf/3 declares, here or anywhere
    ("toyIz(star)", "it declares these of a toy: toyIs(black), toyIs(blue), "),
])
def test_a_restriction_the_environment_cannot_honour_is_refused_where_it_is_known(tmp_path, term, tail):
    """clingo cannot tell a palette value from a typo before the environment declares its PFs; grounding
    refuses such a task, naming the palette and what it offers, rather than binding nothing."""
    from groundlang.model.tasks import candidate_tasks

    var = "R" if term.startswith("room") else "T"
    path = tmp_path / "mine.lp"
    path.write_text('task(t). var(t, "T", toy). var(t, "R", room). goal(t, toyInRoom, ("T", "R")). '
                    f'restrict(t, "{var}", {term}).\n')
    library = TaskLibrary.load([path])  # loads: only an environment declares the palette's PFs
    with pytest.raises(AspError) as caught:
        candidate_tasks(two_toy_state(), library)
    message = str(caught.value)
    assert "\n" not in message
    cls = "room" if var == "R" else "toy"
    assert message.startswith(f'{path}: task t: restrict(t, "{var}", {term}): the environment (palette sokoban) '
                              f"declares no property PF (colour, shape, ...) {term} of a {cls}, so the task would bind nothing; ")
    assert tail in message


def test_a_users_colour_family_restricts_a_task_and_its_values_are_checked_where_the_palette_is_known():
    """A family of the user's own, declared like pfs.lp's for every palette colour: the library loads,
    grounding binds only the toys of that hue, and a value the palette lacks is refused there (before,
    only pfs.lp's roomIs/toyIs families were checked, so toyHue(purple) quietly bound nothing)."""
    hue = ('pf(colour, toyHue(C), (toy,)) :- palette_colour(C).\n'
           'holds(toyHue(C), (T,)) :- toy(T), colour(T, C).\n')
    library = TaskLibrary.from_text(_TOY_TO_ROOM + 'restrict(toyToRoom, "T", toyHue(red)).\n' + hue, "hue.lp")
    assert library.tasks[0].restrictions == (("T", "toyHue(red)"),)
    assert [g.goal_text for g, _ in enumerate_groundings(library, TWO_TOYS)] == ["toyInRoom(block1, room0)"]
    purple = TaskLibrary.from_text(_TOY_TO_ROOM + 'restrict(toyToRoom, "T", toyHue(purple)).\n' + hue, "hue.lp")
    with pytest.raises(AspError, match=r"hue.lp: task toyToRoom: .*the environment declares no property PF \(colour, shape, \.\.\.\) "
                                       r"toyHue\(purple\) of a toy.* toyHue\(blue\), toyHue\(green\), "
                                       r"toyHue\(red\), toyHue\(yellow\)"):
        enumerate_groundings(purple, TWO_TOYS)


def test_descriptions_survive_a_user_constraint_that_rules_out_the_answer_set_of_no_task():
    """":- toy(O), not bind(_, O)." (every command moves a toy) leaves no answer set without a task;
    the descriptions and the restriction check come with every answer set all the same."""
    every_toy_moves = ":- toy(O), not bind(_, O).\n"
    library = TaskLibrary.from_text(_TOY_TO_ROOM + _AGENT_TO_ROOM + every_toy_moves, "moves.lp")
    found, described, _, _ = ground_environment(library, ONE_TOY)
    assert found and all(g.task == "toyToRoom" for g, _ in found)
    assert described["block0"] == {"colour": ("toyIsYellow",), "shape": ("toyIsStar",)}
    mauve = TaskLibrary.from_text(_TOY_TO_ROOM + _AGENT_TO_ROOM + every_toy_moves
                                  + 'restrict(agentToRoom, "R", roomIs(mauve)).\n', "moves.lp")
    with pytest.raises(AspError, match=r'restrict\(agentToRoom, "R", roomIs\(mauve\)\)'):
        ground_environment(mauve, ONE_TOY)


def test_a_variable_outside_the_goal_is_refused_at_load_time():
    with pytest.raises(AspError, match=r"^x.lp: task toyToRoom: variable 'D' appears in no goal/3 atom; "):
        TaskLibrary.from_text(_TOY_TO_ROOM + 'var(toyToRoom, "D", door).\n', "x.lp")


def test_a_variable_of_a_class_the_domain_lacks_is_named_at_load_time():
    """A typo ("rooom") was reported only as a goal PF needing other classes, never as a class that is not one."""
    text = 'task(t). var(t, "A", agent). var(t, "R", rooom). goal(t, agentInRoom, ("A", "R")).\n'
    with pytest.raises(AspError, match=r"^x.lp: task t: var/3 names class 'rooom', which the domain does not "
                                       r"declare \(classes: agent, toy, room, door\)$"):
        TaskLibrary.from_text(text, "x.lp")


def test_a_pf_signature_that_is_no_tuple_is_refused_at_load_time(tmp_path):
    path = tmp_path / "glow.lp"
    path.write_text(_TOY_TO_ROOM + "pf(colour, toyGlows, (toy)). holds(toyGlows, (T,)) :- toy(T).\n")
    with pytest.raises(AspError) as caught:
        TaskLibrary.load([path])
    assert str(caught.value) == (f"{path}: pf(colour,toyGlows,toy): the signature of PF toyGlows must be a tuple of "
                                 "classes, written (toy,) for one argument (the comma makes it a tuple)")


def test_every_restriction_the_environment_cannot_honour_is_counted():
    library = TaskLibrary.from_text(_TOY_TO_ROOM + 'restrict(toyToRoom, "R", roomIs(mauve)).\n'
                                    'restrict(toyToRoom, "T", toyIs(strar)).\n', "two.lp")
    with pytest.raises(AspError) as caught:
        enumerate_groundings(library, TWO_TOYS)
    message = str(caught.value)
    assert message.startswith('two.lp: task toyToRoom: restrict(toyToRoom, "R", roomIs(mauve)): ')
    assert message.endswith("(1 more restrict/3 fact cannot be honoured here)")


def test_an_environment_where_nothing_can_be_asked_is_still_described():
    """The answer set that chooses no task carries the descriptions: here the only task is already done."""
    done = TaskLibrary.from_text(_AGENT_TO_ROOM + 'restrict(agentToRoom, "R", roomIs(green)).\n')
    found, described, _, _ = ground_environment(done, TWO_TOYS)
    assert found == []
    assert described["room0"] == {"colour": ("roomIsGreen",)}
    assert described["block1"] == {"colour": ("toyIsRed",), "shape": ("toyIsMoon",)}


def test_a_library_loaded_again_is_read_once_and_a_changed_or_broken_one_anew(monkeypatch):
    """Loading the same library text again (each model, each fold) reuses its lifted tasks; other text is
    read anew, and an error is raised on every load, never remembered as a library."""
    import uuid

    import groundlang.logic.tasks as tasks_module

    calls = []
    original = tasks_module._read_lifted_tasks
    monkeypatch.setattr(tasks_module, "_read_lifted_tasks", lambda *a: calls.append(1) or original(*a))
    tag = uuid.uuid4().hex  # a comment no other test's library has, so nothing is kept from before
    text = f'% {tag}\ntask(go). var(go, "A", agent). var(go, "R", room). goal(go, agentInRoom, ("A", "R")).\n'
    first = TaskLibrary.from_text(text, "mine.lp")
    again = TaskLibrary.from_text(text, "mine.lp")
    assert len(calls) == 1 and again.tasks == first.tasks and [t.name for t in again.tasks] == ["go"]
    changed = TaskLibrary.from_text(text.replace("task(go)", "task(go). task(went)")
                                    .replace('var(go, "A"', 'var(went, "A", agent). var(went, "R", room). '
                                             'goal(went, agentInRoom, ("A", "R")). var(go, "A"'), "mine.lp")
    assert len(calls) == 2 and sorted(t.name for t in changed.tasks) == ["go", "went"]
    broken = f"% {tag}\ntask(go). var(go, \"A\", agent). goal(go, noSuchPf, (\"A\",)).\n"
    for _ in range(2):
        with pytest.raises(AspError):
            TaskLibrary.from_text(broken, "broken.lp")
    assert len(calls) == 4
    # A long library is read anew each time, so that what is kept stays small.
    import groundlang.logic.sources as sources_module

    monkeypatch.setattr(sources_module, "KEPT_SOURCE_BYTES", 10)
    for _ in range(2):
        TaskLibrary.from_text(text.replace(tag, tag[::-1]), "mine.lp")
    assert len(calls) == 6
    assert sources_module._parsed.cache_info().currsize <= 64


def test_a_shipped_library_is_named_as_a_palette_is(tmp_path, monkeypatch):
    """``--library tasks`` / ``williams2018`` name the package's libraries wherever it is installed; a file of
    that name in the working folder still wins, and an unknown bare name lists the shipped ones."""
    default = TaskLibrary.load()
    assert TaskLibrary.load(["tasks"]).names == default.names
    assert [s.name for s in TaskLibrary.load(["tasks"]).sources] == [s.name for s in default.sources]
    williams = TaskLibrary.load(["williams2018"])
    assert {"agentLeftOfToy", "agentRightOfToy", "agentNextToToy"} <= set(williams.names)
    assert williams.sources[0].name == "groundlang.logic/domains/williams2018.lp"
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tasks").write_text("task(mine). var(mine, \"A\", agent). var(mine, \"R\", room).\n"
                                   "goal(mine, agentInRoom, (\"A\", \"R\")).\n")
    assert TaskLibrary.load(["tasks"]).sources[0].name == "tasks"  # the file, not the package's
    (tmp_path / "tasks").unlink()
    (tmp_path / "tasks").mkdir()  # a folder of that name is not a library file: the name is the package's
    assert TaskLibrary.load(["tasks"]).names == default.names
    with pytest.raises(FileNotFoundError) as caught:
        TaskLibrary.load(["taskz"])
    assert caught.value.filename == "taskz"
    assert caught.value.strerror == "no such file, nor a library the package ships (tasks, williams2018)"


def test_a_rule_with_a_long_name_is_told_from_a_ground_fact_at_once():
    """Every lowercase letter of a name could start another identifier inside the ground-fact pattern, and a
    rule (no fact) of a 20-letter name was tried split every way (48 s; 134 letters: never). Possessive
    quantifiers try one split."""
    from groundlang.logic.sources import _GROUND_FACT

    name = "agent" + "x" * 200
    assert _GROUND_FACT.fullmatch(f"{name}(A) :- agent(A).") is None
    assert _GROUND_FACT.fullmatch(f"{name}(a, 3, \"s\").") is not None
    assert _GROUND_FACT.fullmatch("value(colour, 0, red).") is not None


@pytest.mark.parametrize("name", ["tasks", "williams2018"])
def test_a_saved_library_that_is_a_shipped_one_word_for_word_is_solved_in_this_process(name):
    """A saved model keeps its library's text; the shipped library's text is the package's program again, solved
    in this process (a user's program is solved in a child process, a second or more a new layout). Any other
    text, an edit of a comment included, stays a user's."""
    shipped = TaskLibrary.load([name]) if name != "tasks" else TaskLibrary.load()
    text = shipped.source_text()
    again = TaskLibrary.from_saved_text(text, "model.json:task_library")
    assert not again.program.isolated and again.source_text() == text and again.names == shipped.names
    edited = TaskLibrary.from_saved_text(text + "% an edit\n", "model.json:task_library")
    assert edited.program.isolated and edited.names == shipped.names


def test_a_library_named_by_a_folder_is_said_to_be_a_folder(tmp_path, monkeypatch):
    # it had said "no such file" of a folder that is there
    from groundlang.logic.sources import library_source

    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine").mkdir()
    with pytest.raises(IsADirectoryError, match=r"a folder, not a library file \(name its .lp files\)"):
        library_source("mine")
    with pytest.raises(FileNotFoundError, match="no such file, nor a library the package ships"):
        library_source("theirs")
