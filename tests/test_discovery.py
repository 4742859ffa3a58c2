"""Task discovery from scratch (inference/discovery.py) and ``groundlang discover``."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

from groundlang.model.tasks import attribute_pfs
from groundlang.cli import main
from groundlang.corpus import example_corpus_path, read_corpus
from groundlang.inference.discovery import (
    DiscoverySettings,
    discover_tasks,
    lift_goal,
    lifted_key,
    singling_out,
    structure_key,
    task_name,
    write_library,
)
from groundlang.inference.library_search import select_library
from groundlang.logic.atoms import Atom, parse_atom, parse_goal
from groundlang.logic.tasks import AspError, TaskLibrary, Variable
from groundlang.model.pf_tables import TabulationError
from groundlang.model.tasks import candidate_tasks

CLASSES = {"agent0": "agent", "block0": "toy", "block1": "toy", "room0": "room", "room1": "room",
           "room2": "room", "door0": "door", "door1": "door"}


def _default(name: str):
    return TaskLibrary.load().task(name)


# ---------------------------------------------------------------- lifting


def test_lift_goal_replaces_objects_by_typed_variables():
    lifted = lift_goal([parse_atom("toyInRoom(block0, room2)")], CLASSES)
    assert lifted.name == "toyToRoom"
    assert lifted.variables == (Variable("T", "toy"), Variable("R", "room"))
    assert lifted.goal == (("toyInRoom", ("T", "R")),)
    assert lifted_key(lifted) == lifted_key(_default("toyToRoom"))


def test_lifted_structures_are_equal_up_to_renaming_objects():
    a = [parse_atom("toyInRoom(block0, room2)"), parse_atom("agentInRoom(agent0, room0)")]
    b = [parse_atom("agentInRoom(agent0, room1)"), parse_atom("toyInRoom(block1, room0)")]
    same_room = [parse_atom("toyInRoom(block0, room1)"), parse_atom("agentInRoom(agent0, room1)")]
    assert structure_key([(x.predicate, x.args) for x in a], CLASSES) == \
        structure_key([(x.predicate, x.args) for x in b], CLASSES)
    lifted = lift_goal(a, CLASSES)
    assert lifted.name == "toyToRoomAgentToRoom"  # toy's goal first, as tasks.lp names it
    assert {v.name for v in lifted.variables} == {"A", "T", "R", "R2"}
    # The default library's RT/RA task is the same structure.
    assert lifted_key(lifted) == lifted_key(_default("toyToRoomAgentToRoom"))
    # One room for both atoms is another structure: one variable, not two.
    shared = lift_goal(same_room, CLASSES)
    assert {v.name for v in shared.variables} == {"A", "T", "R"}
    assert lifted_key(shared) != lifted_key(lifted)


def test_task_names_come_from_goal_predicates():
    assert task_name([("agentInRoom", ("A", "R"))], {"A": "agent", "R": "room"}) == "agentToRoom"
    assert task_name([("agentTouchingToy", ("A", "T"))], {"A": "agent", "T": "toy"}) == "agentToToy"
    assert task_name([("agentInDoor", ("A", "D")), ("toyInRoom", ("T", "R"))],
                     {"A": "agent", "D": "door", "T": "toy", "R": "room"}) == "toyToRoomAgentToDoor"


def test_singling_out_finds_the_smallest_distinguishing_conjunction():
    corpus = read_corpus(example_corpus_path(), "sokoban")
    state = corpus.instances[0].initial_state
    layout = state.layout
    attributes = attribute_pfs(state, TaskLibrary.load())
    assert singling_out(layout, "room0", ["room1", "room2"], attributes) == (Atom("roomIsGreen", ("room0",)),)
    assert singling_out(layout, "block0", [], attributes) == ()  # a lone toy needs no description
    assert singling_out(layout, "door0", ["door1"], attributes) is None  # doors have no colour or shape


# ---------------------------------------------------------------- library search


def test_library_search_prefers_a_shared_structure_over_a_near_tie():
    # Three toy demonstrations; in the third, "toy to door" fits 0.1 nats better than "toy to room"
    # (the star2teal situation). Columns: agentToRoom, toyToRoom, toyToDoor.
    table = np.array([[-1.0, -np.inf, -np.inf],
                      [-50.0, -2.0, -30.0],
                      [-50.0, -3.0, -25.0],
                      [-60.0, -12.1, -12.0]])
    ranked = select_library(table, np.array([1, 1, 1]), math.log(5), max_tasks=3)
    (best, score), (runner_up, second) = ranked[0], ranked[1]
    assert best == (0, 1)
    assert score == pytest.approx(-1 - 2 - 3 - 12.1 - 4 * math.log(2) - 2 * math.log(5))
    assert runner_up == (0, 1, 2)  # buys 0.1 nats for 4 log(3/2) + log 5 more
    assert score - second == pytest.approx(4 * math.log(1.5) + math.log(5) - 0.1)


def test_library_search_refuses_what_no_library_covers():
    table = np.array([[-1.0, -np.inf], [-np.inf, -1.0]])
    assert select_library(table, np.array([1, 1]), 1.0, max_tasks=1) == []
    assert select_library(table, np.array([1, 1]), 1.0, max_tasks=2)[0][0] == (0, 1)


def test_settings_are_checked():
    with pytest.raises(ValueError, match="weight_margin"):
        DiscoverySettings(weight_margin=0.0)
    with pytest.raises(ValueError, match="max_conjuncts"):
        DiscoverySettings(max_conjuncts=0)
    with pytest.raises(ValueError, match="at least one instance"):
        discover_tasks([])


# ---------------------------------------------------------------- the example corpus (no ../shared needed)


@pytest.fixture(scope="module")
def example_discovery(tmp_path_factory):
    corpus = read_corpus(example_corpus_path(), "sokoban")
    return corpus, discover_tasks(corpus.instances, cache_dir=tmp_path_factory.mktemp("cache"))


@pytest.mark.slow
def test_discovery_on_the_example_corpus_finds_agent_and_toy_to_room(example_discovery, tmp_path):
    corpus, found = example_discovery
    assert len(corpus) == 24 and len(found.demonstrations) == 6
    assert [lifted_key(t) for t in found.tasks] == [lifted_key(_default("agentToRoom")),
                                                   lifted_key(_default("toyToRoom"))]
    assert [t.name for t in found.tasks] == ["agentToRoom", "toyToRoom"]
    with open(example_corpus_path() / "labels.csv") as f:
        gold = {row["prefix"]: parse_goal(row["goal"]) for row in csv.DictReader(f)}
    for report in found.demonstrations:
        assert len(report.instances) == 4
        assert report.grounding.goal == gold[report.instances[0][:-1]], report.instances[0]
        assert report.log_likelihood > -3.0
    # star2green: MLIRL weighs the agent's door highest, the behaviour likelihood still picks the room.
    green = found.report_for("star2green_2")
    assert green.top_features[0][0] == parse_atom("agentInDoor(agent0, door1)")
    assert green.task == "toyToRoom" and dict(green.singled_out)["R"] == (parse_atom("roomIsGreen(room0)"),)
    # The winner beats the runner-up library by more than two nats.
    assert found.alternatives[0][0] == ("agentToRoom", "toyToRoom")
    assert found.score - found.alternatives[1][1] > 2.0
    path = write_library(found, tmp_path / "discovered.lp")
    loaded = TaskLibrary.load([path])
    assert loaded.names == ["agentToRoom", "toyToRoom"]
    state = corpus.instances[0].initial_state
    goals = [g.goal_text for g, _ in candidate_tasks(state, loaded)]
    default_goals = [g.goal_text for g, _ in candidate_tasks(state, TaskLibrary.load())
                     if g.task in ("agentToRoom", "toyToRoom")]
    assert goals == default_goals and len(goals) == 4


# ---------------------------------------------------------------- the commands-to-tasks corpus


@pytest.mark.slow
def test_discovery_on_the_six_corpus_demonstrations(shared_corpus, tmp_path):
    corpus = read_corpus(shared_corpus / "allTurkTrain", "sokoban")
    found = discover_tasks(corpus.instances, cache_dir=tmp_path / "cache")
    assert len(corpus) == 240 and len(found.demonstrations) == 6
    assert sorted(len(r.instances) for r in found.demonstrations) == [40] * 6
    # Exactly two lifted tasks, equivalent to the default library's agent-to-room and toy-to-room.
    assert sorted(lifted_key(t) for t in found.tasks) == sorted(
        [lifted_key(_default("agentToRoom")), lifted_key(_default("toyToRoom"))])
    with open(shared_corpus / "labels.csv") as f:
        gold = {row["prefix"]: parse_goal(row["goal"]) for row in csv.DictReader(f)}
    for report in found.demonstrations:
        assert report.grounding.goal == gold[report.instances[0].rsplit("_", 1)[0] + "_"]
    # star2teal: toyInDoor(block0, door0) outweighs toyInRoom(block0, room2) in MLIRL (4.46 vs 4.43),
    # but the path is e^3 times likelier under "toy into room2", which the other toy demos share.
    teal = found.report_for("star2teal_0")
    assert [str(a) for a, _ in teal.top_features[:2]] == ["toyInDoor(block0, door0)", "toyInRoom(block0, room2)"]
    scores = dict(teal.scores)
    assert scores["toyToRoom"] - scores["toyToDoor"] == pytest.approx(3.45, abs=0.1)
    assert teal.log_likelihood == pytest.approx(-12.19, abs=0.05)
    assert found.score == pytest.approx(-37.58, abs=0.05)
    assert found.score - found.alternatives[1][1] == pytest.approx(2.64, abs=0.05)
    # The written .lp loads back and grounds.
    path = write_library(found, tmp_path / "tasks.lp")
    text = path.read_text()
    assert text.startswith("% Lifted tasks discovered") and "star2teal_0 (+39 more)" in text
    loaded = TaskLibrary.load([path])
    grounded = candidate_tasks(teal_state(corpus), loaded)
    assert [g.goal_text for g, _ in grounded] == [
        "agentInRoom(agent0, room0)", "agentInRoom(agent0, room2)",
        "toyInRoom(block0, room1)", "toyInRoom(block0, room2)"]


def teal_state(corpus):
    return next(i for i in corpus.instances if i.name == "star2teal_0").initial_state


# ---------------------------------------------------------------- CLI


def test_cli_discover_writes_a_library_that_groundlang_tasks_reads(tmp_path, capsys):
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    for name in ("agent2red_0.txt", "agent2red_1.txt", "star2blue_0.txt"):
        (corpus / name).write_text((example_corpus_path() / name).read_text())
    out = tmp_path / "tasks.lp"
    argv = ["discover", str(corpus), "--palette", "sokoban", "-o", str(out), "--cache-dir", str(tmp_path / "cache")]
    assert main(argv + ["--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["output"] == str(out)
    assert [t["name"] for t in result["lifted_tasks"]] == ["agentToRoom", "toyToRoom"]
    assert result["lifted_tasks"][1]["goal"] == [["toyInRoom", ["T", "R"]]]
    assert result["lifted_tasks"][0]["demonstrations"] == ["agent2red_0"]
    assert [d["instances"] for d in result["demonstrations"]] == [["agent2red_0", "agent2red_1"], ["star2blue_0"]]
    assert result["demonstrations"][1]["goal"] == "toyInRoom(block0, room2)"
    assert main(["tasks", str(corpus / "star2blue_0.txt"), "--palette", "sokoban", "--library", str(out),
                 "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert listed["lifted_tasks"] == ["agentToRoom", "toyToRoom"]
    assert "toyInRoom(block0, room2)" in [g["goal"] for g in listed["groundings"]]
    # Table output; the behaviour likelihoods now come from the cache.
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "toyToRoom(T: toy, R: room) := toyInRoom(T, R)" in text and f"written: {out}" in text


def test_cli_discover_on_an_empty_folder_is_exit_code_2(tmp_path, capsys):
    assert main(["discover", str(tmp_path), "--palette", "sokoban", "-o", str(tmp_path / "t.lp")]) == 2
    assert "groundlang discover: error" in capsys.readouterr().err
    assert not (tmp_path / "t.lp").exists()


# ---------------------------------------------------------------- restrictions: what every demonstration shares

# room,COLOUR,LEFT,TOP,RIGHT,BOTTOM (green=5, red=10, blue=1); block,COLOUR,SHAPE,X,Y; the first toy goes to room0.
_ROOMS = "room,5,0,7,8,4 room,10,0,4,4,0 room,1,4,4,8,0 door,2,4,2,4 door,6,4,6,4 door,4,2,4,2 "
# A library's own colour family: a toy's tone, warm (red, orange, yellow) or cool.
_TONE = """tone(warm). tone(cool).
pf(colour, toyTone(V), (toy,)) :- tone(V).
holds(toyTone(warm), (T,)) :- toy(T), colour(T, C), warm(C).
holds(toyTone(cool), (T,)) :- toy(T), colour(T, C), not warm(C).
warm(red). warm(orange). warm(yellow).
"""


def _push_first_toy(name: str, toys: str):
    from groundlang.corpus import Instance, parse_state
    from groundlang.examples.build import shortest_demonstration
    from groundlang.model.world import replay

    start = parse_state(_ROOMS + toys + " agent,5,6", "sokoban")
    actions = shortest_demonstration(start, parse_goal("toyInRoom(block0, room0)"))
    return Instance(Path(f"{name}.txt"), "push it into the green room", actions, replay(start, actions))


def _toy_restrictions(found) -> list[str]:
    task = next(t for t in found.tasks if t.name == "toyToRoom")
    return [term for var, term in task.restrictions if var == "T"]


def test_a_restriction_is_what_singles_the_object_out_in_every_demonstration():
    """A yellow star beside a magenta moon, a red star beside a blue moon: the star is what both share
    (the smallest conjunction of each, its colour, differs)."""
    demos = [_push_first_toy("yellow_star", "block,12,0,4,2 block,7,1,7,6"),
             _push_first_toy("red_star", "block,10,0,4,2 block,1,1,7,6")]
    found = discover_tasks(demos, DiscoverySettings(restrict=True), cache_dir=False)
    assert [t.name for t in found.tasks] == ["toyToRoom"]
    assert [dict(r.singled_out)["T"] for r in found.demonstrations] == [
        (parse_atom("toyIsYellow(block0)"),), (parse_atom("toyIsRed(block0)"),)]
    assert found.tasks[0].restrictions == (("R", "roomIs(green)"), ("T", "toyIs(star)"))
    # Two stars each time (only the colour tells them apart) and different colours: nothing is shared.
    stars = [_push_first_toy("red_star", "block,10,0,4,2 block,1,0,7,6"),
             _push_first_toy("yellow_star", "block,12,0,4,2 block,5,0,7,6")]
    assert _toy_restrictions(discover_tasks(stars, DiscoverySettings(restrict=True), cache_dir=False)) == []


def test_restrictions_may_use_a_colour_family_of_the_users_own(tmp_path):
    """Red star beside a blue star, yellow star beside a green star: pfs.lp's colours share nothing,
    the user's toyTone(warm) is what both moved toys have and their peers lack."""
    tone = tmp_path / "tone.lp"
    tone.write_text(_TONE)
    stars = [_push_first_toy("red_star", "block,10,0,4,2 block,1,0,7,6"),
             _push_first_toy("yellow_star", "block,12,0,4,2 block,5,0,7,6")]
    found = discover_tasks(stars, DiscoverySettings(restrict=True), cache_dir=False, pfs=TaskLibrary.load([tone]))
    assert _toy_restrictions(found) == ["toyTone(warm)"]
    assert dict(found.demonstrations[0].singled_out)["T"] == (parse_atom("toyIsRed(block0)"),)
    path = write_library(found, tmp_path / "discovered.lp")
    assert 'restrict(toyToRoom, "T", toyTone(warm)).' in path.read_text()
    # Loaded with the family's file, the task binds only a warm toy: an orange moon, not a cyan star.
    library = TaskLibrary.load([path, tone])
    from groundlang.corpus import parse_state

    state = parse_state(_ROOMS + "block,2,0,6,2 block,8,1,1,2 agent,5,6", "sokoban")
    toys = {dict(g.binding)["T"] for g, _ in candidate_tasks(state, library) if g.task == "toyToRoom"}
    assert toys == {"block1"}


def test_cli_discover_restrict_reads_the_users_pfs(tmp_path, capsys):
    from groundlang.corpus import write_instance

    corpus = tmp_path / "corpus"
    for instance in (_push_first_toy("red_star_0", "block,10,0,4,2 block,1,0,7,6"),
                     _push_first_toy("yellow_star_0", "block,12,0,4,2 block,5,0,7,6")):
        write_instance(corpus / instance.path.name, instance)
    tone = tmp_path / "tone.lp"
    tone.write_text(_TONE)
    out = tmp_path / "tasks.lp"
    argv = ["discover", str(corpus), "--palette", "sokoban", "-o", str(out), "--no-cache", "--restrict"]
    assert main(argv + ["--pfs", str(tone), "--json"]) == 0
    assert 'restrict(toyToRoom, "T", toyTone(warm)).' in out.read_text()
    capsys.readouterr()
    # A broken PF file is reported with its name, before any work, and nothing is written.
    broken = tmp_path / "broken.lp"
    broken.write_text("pf(colour, toyTone(V), (toy,)) :- \n")
    out.unlink()
    assert main(argv + ["--pfs", str(broken)]) == 2
    assert "broken.lp" in capsys.readouterr().err
    assert not out.exists()


def test_a_restriction_may_need_a_conjunction_shared_by_every_demonstration(tmp_path):
    """Red star beside a red moon and a blue star; yellow star beside a yellow moon and a blue star:
    neither toyTone(warm) nor toyIs(star) alone excludes every peer, both together do."""
    tone = tmp_path / "tone.lp"
    tone.write_text(_TONE)
    demos = [_push_first_toy("red_star", "block,10,0,4,2 block,10,1,7,6 block,1,0,1,2"),
             _push_first_toy("yellow_star", "block,12,0,4,2 block,12,1,7,6 block,1,0,1,2")]
    found = discover_tasks(demos, DiscoverySettings(restrict=True), cache_dir=False, pfs=TaskLibrary.load([tone]))
    assert sorted(_toy_restrictions(found)) == ["toyIs(star)", "toyTone(warm)"]
    # The report's smallest conjunction (the first found, colour PFs before shape PFs).
    assert dict(found.demonstrations[0].singled_out)["T"] == (parse_atom("toyIsRed(block0)"),
                                                             parse_atom("toyIsStar(block0)"))
    blue_moon = [_push_first_toy("red_star", "block,10,0,4,2 block,1,1,7,6")]
    single = discover_tasks(blue_moon, DiscoverySettings(restrict=True), cache_dir=False,
                            pfs=TaskLibrary.load([tone]))
    # Several single PFs tell it apart (toyIsRed, toyIsStar, toyToneWarm): the first colour PF by name.
    assert _toy_restrictions(single) == ["toyIs(red)"]
    assert "beside the PFs it names" in single.text and "tone.lp" in single.text


def test_pfs_for_discovery_are_checked(tmp_path):
    demos = [_push_first_toy("red_star", "block,10,0,4,2 block,1,0,7,6")]
    # A family declared for toys but written true of rooms too is refused, as training refuses it (its position
    # PFs are candidate goals, so the file is tabulated: it had been read as describing toys only)
    loose = tmp_path / "loose.lp"
    loose.write_text("pf(colour, anyTone(warm), (toy,)).\nholds(anyTone(warm), (O,)) :- colour(O, red).\n")
    with pytest.raises(TabulationError, match=r"loose.lp: holds\(anyToneWarm, \(room\d,\)\): room\d is a room, but "
                                              r"pf/3 declares anyToneWarm over \(toy,\)"):
        discover_tasks(demos, DiscoverySettings(restrict=True), cache_dir=False, pfs=TaskLibrary.load([loose]))
    # Two PFs groundlang would name alike.
    clash = tmp_path / "clash.lp"
    clash.write_text("pf(colour, toyIsRed, (toy,)).\nholds(toyIsRed, (T,)) :- toy(T).\n")
    with pytest.raises(AspError, match="toyIs\\(red\\) and toyIsRed are both called toyIsRed"):
        discover_tasks(demos, DiscoverySettings(restrict=True), cache_dir=False, pfs=TaskLibrary.load([clash]))
    # A file whose constraint leaves the environment no answer set is reported, not read as "no PFs".
    unsat = tmp_path / "unsat.lp"
    unsat.write_text(":- room(R).\n")
    with pytest.raises(ValueError, match="unsat.lp: describes no object of the initial state of red_star"):
        discover_tasks(demos, DiscoverySettings(restrict=True), cache_dir=False, pfs=TaskLibrary.load([unsat]))
    # Tasks belong in a task library, not here.
    with pytest.raises(ValueError, match="declares tasks"):
        discover_tasks(demos, DiscoverySettings(restrict=True), cache_dir=False, pfs=TaskLibrary.load())


def test_a_users_family_singles_out_what_pfs_lp_cannot(tmp_path):
    """Two red stars: no colour or shape PF tells them apart, a user's family does (a property of each toy
    that stays as it moves: one that read where the toy lies is refused, as training refuses it)."""
    tag = tmp_path / "tag.lp"
    tag.write_text("tag(first). tag(second).\npf(shape, toyTag(S), (toy,)) :- tag(S).\n"
                   "holds(toyTag(first), (T,)) :- toy(T), T = block0.\n"
                   "holds(toyTag(second), (T,)) :- toy(T), T != block0.\n")
    demos = [_push_first_toy("west_star", "block,10,0,4,2 block,10,0,7,6")]
    plain = discover_tasks(demos, DiscoverySettings(restrict=True), cache_dir=False)
    assert dict(plain.demonstrations[0].singled_out)["T"] is None and _toy_restrictions(plain) == []
    found = discover_tasks(demos, DiscoverySettings(restrict=True), cache_dir=False, pfs=TaskLibrary.load([tag]))
    assert dict(found.demonstrations[0].singled_out)["T"] == (parse_atom("toyTagFirst(block0)"),)
    assert _toy_restrictions(found) == ["toyTag(first)"]
    assert [t.name for t in found.library.tasks] == ["toyToRoom"]  # loaded back with tag.lp: checked
    side = tmp_path / "side.lp"
    side.write_text("side(west). side(east).\npf(shape, toySide(S), (toy,)) :- side(S).\n"
                    "holds(toySide(west), (T,)) :- toy(T), at(T, X, _), X < 5.\n"
                    "holds(toySide(east), (T,)) :- toy(T), at(T, X, _), X >= 5.\n")
    with pytest.raises(TabulationError, match="side.lp: PF toySideWest is of a property class"):
        discover_tasks(demos, DiscoverySettings(restrict=True), cache_dir=False, pfs=TaskLibrary.load([side]))


def test_a_position_pf_of_the_users_own_may_be_the_goal_discovered(tmp_path, capsys):
    """--pfs: a file's position PFs are candidate goals (discovery had fitted pfs.lp's only, and explained
    demonstrations of pushing the star next to a door by agentTouchingToy and toyInRoom)."""
    from groundlang.examples.build import _state, write_tasks

    near = tmp_path / "near.lp"
    near.write_text("pf(position, toyNextToDoor, (toy, door)).\n"
                    "holds(toyNextToDoor, (T, D)) :- toy(T), door(D), at(T, X, Y), beside(X, Y, U, V), "
                    "door_cell(D, U, V).\n")
    library = TaskLibrary.load(["tasks", str(near)])
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    write_tasks(corpus, [("door1_", "toyNextToDoor(block0, door1)", _state((3, 3), (1, 1)), ["push it by the door"]),
                         ("door2_", "toyNextToDoor(block0, door2)", _state((8, 6), (10, 8)), ["push it by the door"])],
                library)
    out = tmp_path / "found.lp"
    argv = ["discover", str(corpus), "--palette", "sokoban", "-o", str(out), "--no-cache", "--json"]
    assert main([*argv, "--pfs", str(near)]) == 0
    found = json.loads(capsys.readouterr().out)
    assert [t for t in found["lifted_tasks"] if "toyNextToDoor(" in t["task"]], found["lifted_tasks"]
    assert "toyNextToDoor" in TaskLibrary.load([str(out), str(near)]).goal_relations
    assert main(argv) == 0  # without the file, another explanation: the PF is no candidate
    assert not [t for t in json.loads(capsys.readouterr().out)["lifted_tasks"] if "toyNextToDoor" in t["task"]]
