"""The harder corpus (palette sokoban2): two toys picked by colour or shape, conjunctive goals.

``tests/fixtures/sokoban2_corpus`` is written by ``tests/fixtures/build_sokoban2_corpus.py``
(three layouts, 30 tasks, 120 hand-written commands, shortest-path demonstrations).
The numbers asserted here were measured with this code (the runs are
deterministic: the same counts with 1 or 2 torch threads).
"""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest

from groundlang.logic.atoms import parse_goal

from groundlang.cli import main
from groundlang.corpus import Corpus, Instance, read_corpus, read_state_file
from groundlang.evaluation import NovelEnvironmentError, evaluate
from groundlang.labels import goal_holds, read_labels
from groundlang.learner import Learner
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.interpretations import interpretations, unbroken_held_parts
from groundlang.model.pf_tables import library_pf_tables
from groundlang.model.statespace import enumerate_states
from groundlang.model.world import Action, replay

FIXTURES = Path(__file__).parent / "fixtures"
CORPUS = FIXTURES / "sokoban2_corpus"

# One test process for the module (make test's --dist loadgroup): the train-protocol evaluation and the
# behaviour cache its module fixtures build are then built once, not once in each process.
pytestmark = pytest.mark.xdist_group("harder_corpus")
LAYOUTS = ("L1", "L2", "L3")


def _load_builder():
    spec = importlib.util.spec_from_file_location("build_sokoban2_corpus", FIXTURES / "build_sokoban2_corpus.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def corpus():
    return read_corpus(CORPUS, "sokoban2")


@pytest.fixture(scope="module")
def labels():
    return read_labels(CORPUS / "labels.csv")


@pytest.fixture(scope="module")
def options(tmp_path_factory):
    # One behaviour-likelihood cache for the module: computed once, reused by every evaluation here.
    return {"cache_dir": tmp_path_factory.mktemp("behaviour-cache")}


@pytest.fixture(scope="module")
def train_result(corpus, labels, options):
    return evaluate(corpus, labels, protocol="train", learner_options=options)


def _gold_toy(instance, labels) -> int | None:
    toys = [a.args[0] for a in labels[instance.prefix] if a.predicate == "toyInRoom"]
    return int(toys[0][len("block"):]) if toys else None


def _toy_reference(instance, labels) -> str | None:
    """How the command picks the gold toy: ``colour`` (its colour word, which the other toy lacks),
    ``shape`` (no colour that tells the toys apart), or None for agent-only goals."""
    k = _gold_toy(instance, labels)
    if k is None:
        return None
    attributes = instance.initial_state.layout.toy_attributes
    colour = attributes[k][0]
    said = re.search(r"\b(\w+) (?:chair|bag|backpack|basket|one)\b", instance.command.lower())
    if said and said.group(1) == colour and attributes[1 - k][0] != colour:
        return "colour"
    return "shape"


def _records(result) -> dict[str, dict]:
    return {r["instance"]: r for r in result.records}


# ---------------------------------------------------------------- the corpus


@pytest.mark.slow
def test_generator_reproduces_the_fixture_byte_for_byte(tmp_path):
    paths = _load_builder().build(tmp_path)
    assert len(paths) == 120 + 1 + 3
    for path in paths:
        assert path.read_bytes() == (CORPUS / path.name).read_bytes(), path.name
    assert sorted(p.name for p in CORPUS.iterdir()) == sorted(p.name for p in paths)


def test_the_corpus_checks_clean(capsys):
    code = main(["check", str(CORPUS), "--palette", "sokoban2", "--labels", str(CORPUS / "labels.csv")])
    out = capsys.readouterr().out
    assert code == 0
    assert "instances: 120" in out
    assert "distinct layouts: 3" in out
    assert "distinct demonstrations: 30" in out
    assert "inconsistent demonstrations: 0" in out
    assert "labelled: 120/120 files (30 prefixes" in out
    assert "goal holds in final state: 120/120" in out


def test_the_corpus_has_two_toys_and_conjunctions_with_distinct_rooms(corpus, labels):
    for inst in corpus.instances:
        assert len(inst.initial_state.toys) == 2
        colours = [r.colour for r in inst.initial_state.layout.rooms]
        assert len(set(colours)) == 3
    kinds = {}
    for prefix, goal in labels.items():
        kind = "+".join(sorted(a.predicate for a in goal))
        kinds[kind] = kinds.get(kind, 0) + 1
        if len(goal) == 2:  # toy in one room, agent in another
            assert goal[0].args[1] != goal[1].args[1]
    assert kinds == {"agentInRoom": 6, "toyInRoom": 9, "agentInRoom+toyInRoom": 15}
    # L2's toys share their colour (shape picks), L3's their shape (colour picks).
    attrs = {i.prefix[:2]: i.initial_state.layout.toy_attributes for i in corpus.instances}
    assert attrs["L1"] == (("red", "chair"), ("blue", "bag"))
    assert attrs["L2"] == (("red", "chair"), ("red", "bag"))
    assert attrs["L3"] == (("blue", "bag"), ("yellow", "bag"))


def test_state_spaces_stay_small(corpus):
    sizes = {inst.prefix: len(enumerate_states(inst.initial_state)) for inst in corpus.instances}
    # Measured: 68,850 reachable states in L1 and L3; 324..50,444 in L2 (toys pushed against a wall stay on it).
    assert max(sizes.values()) == 68_850
    assert min(sizes.values()) == 324


# ---------------------------------------------------------------- evaluation


@pytest.mark.slow
def test_train_protocol(train_result, corpus, labels):
    result = train_result
    assert result.n == 120 and not result.failed_folds
    # Measured: 120/120 (59/72 of the first 72 commands before a toy's head noun could name its shape).
    assert result.correct >= 118
    assert result.per_goal_size[1]["n"] == 60 and result.per_goal_size[2]["n"] == 60
    per_task = result.per_task
    assert per_task["toyInRoom(chair, blue) agentInRoom(agent, magenta)"]["correct"] == 4
    assert per_task["toyInRoom(chair, green) agentInRoom(agent, blue)"]["correct"] == 4
    assert per_task["toyInRoom(bag, magenta) agentInRoom(agent, red)"]["correct"] == 4
    agent_only = [row for task, row in per_task.items() if task.startswith("agentInRoom")]  # gold conjunctions start with toyInRoom
    assert sum(r["correct"] for r in agent_only) >= 23 and sum(r["n"] for r in agent_only) == 24
    records = _records(result)
    assert all(records[i.name]["correct"] for i in corpus.instances if i.prefix.startswith("L3"))


@pytest.mark.slow
def test_conjunctions_whose_agent_part_holds_at_the_start(train_result, corpus, labels):
    # The agent starts inside the room it must end in: that part holds at the start and the plan breaks
    # it ("take the bag to the blue room and then come back to the green room"). Read as the toy goal
    # alone, the agent would be left wherever the push ends.
    records = _records(train_result)
    held = [i for i in corpus.instances
            if len(labels[i.prefix]) == 2 and any(goal_holds((a,), i.initial_state) for a in labels[i.prefix])]
    assert len(held) == 12
    assert [i.name for i in held if not records[i.name]["correct"]] == []
    assert all(set(parse_goal(records[i.name]["predicted_task"])) == set(parse_goal(records[i.name]["gold_task"]))
               for i in held)  # read as the conjunction, not merely ending where it holds


HELD_OUT = "L1bag2blue_agent2green_"


@pytest.fixture(scope="module")
def l1_learner(corpus, options):
    """Trained on layout L1 without the commands of one conjunction whose agent starts in the room it
    must return to (the agent in the green room, the bag in the red one)."""
    return Learner(cache_dir=options["cache_dir"]).fit(
        [i for i in corpus.instances if i.prefix.startswith("L1") and i.prefix != HELD_OUT])


def _start(corpus, prefix):
    return next(i for i in corpus.instances if i.prefix == prefix).initial_state


@pytest.mark.slow
@pytest.mark.parametrize("command", [
    "push the blue bag into the blue room and then come back to the green room",  # toy clause first
    "come back to the green room after you take the bag to the blue room",  # agent clause first
])
def test_a_conjunction_held_out_is_followed_so_both_parts_hold(l1_learner, corpus, labels, command):
    # The learner meets the held-out task's start state and a command it never saw, in either order.
    start, gold = _start(corpus, HELD_OUT), labels[HELD_OUT]
    assert any(goal_holds((a,), start) for a in gold) and not goal_holds(gold, start)
    result = l1_learner.follow(command, start)
    assert set(result.goal) == set(gold)
    assert result.reached and goal_holds(gold, result.states[-1])
    assert not goal_holds(gold[1:], result.states[len(result.states) // 2])  # the agent left the room on the way


@pytest.mark.slow
def test_a_clause_the_goal_does_not_need_is_not_forced_onto_a_part(l1_learner, corpus):
    # "... and then come back", said in a doorway, names no room: the words are the frame's, and the
    # reading stays the toy goal alone, as probable as without the clause.
    start = _start(corpus, "L1chair2red_agent2blue_")
    plain = l1_learner.posterior("push the chair into the red room", start)
    longer = l1_learner.posterior("push the chair into the red room and then come back", start)
    assert [str(a) for a in longer.best_goal] == ["toyInRoom(block0, room1)"] == [str(a) for a in plain.best_goal]
    assert abs(longer.goals()[0][1] - plain.goals()[0][1]) < 0.02


def test_a_goal_that_holds_at_the_start_is_a_reading_only_where_the_demonstration_leaves_and_returns(corpus):
    # The agent starts in the green room of L1. One demonstration steps out through the door and back in
    # ("step out of the green room and come back in"): the whole goal "the agent in the green room" holds
    # at the start and is broken and restored, so it is a reading of that instance, the one its
    # demonstration explains best. A demonstration that stays inside never breaks it, and a command
    # alone (no demonstration) asks nothing of a goal that holds: neither offers it.
    start = _start(corpus, HELD_OUT)
    green = parse_goal("agentInRoom(agent0, room0)")
    assert goal_holds(green, start)
    leave_and_return = [Action.EAST, Action.NORTH, Action.EAST, Action.EAST, Action.WEST, Action.WEST]
    stay_inside = [Action.NORTH, Action.SOUTH]
    instances = [Instance(Path(f"d{n}.txt"), "step out of the green room and come back in", tuple(a), replay(start, a))
                 for n, a in enumerate((leave_and_return, stay_inside))]
    assert goal_holds(green, instances[0].states[-1]) and not goal_holds(green, instances[0].states[3])
    learner = Learner()
    returned, stayed = learner.observe(instances)
    behaviour = dict(zip((i.goal for i in returned.interpretations), returned.behaviour))
    assert max(behaviour, key=behaviour.get) == green
    assert green not in [i.goal for i in stayed.interpretations]
    assert green not in [i.goal for i in learner._command_observation("go to the green room", start).interpretations]
    # Its prior is its lifted task's share for one grounding: the others' priors are as without it.
    other = {i.goal: i.log_prior for i in stayed.interpretations}
    assert all(other[i.goal] == pytest.approx(i.log_prior) for i in returned.interpretations if i.goal in other)


def test_unbroken_held_parts_rule_readings_out_of_training(corpus):
    # A conjunction whose held part the demonstration never breaks explains nothing it shows (the chair
    # sits in the green room throughout "push the bag ... then go back to the green room"); the gold
    # reading, whose held part the agent breaks and restores, stays.
    inst = next(i for i in corpus.instances if i.prefix == "L1bag2blue_agent2green_")
    library = TaskLibrary.load()
    interps = interpretations(inst.initial_state, library, enumerate_constraints=False, held_parts=True)
    assert len(interps) > len(interpretations(inst.initial_state, library, enumerate_constraints=False))
    out = unbroken_held_parts(interps, inst.states, library_pf_tables(inst.initial_state.layout, library))
    goals = {frozenset(i.goal): o for i, o in zip(interps, out)}
    gold = frozenset(parse_goal("toyInRoom(block1, room2) agentInRoom(agent0, room0)"))
    chair_stays = frozenset(parse_goal("toyInRoom(block0, room0) agentInRoom(agent0, room1)"))
    assert goals[gold] is np.False_ and goals[chair_stays] is np.True_
    assert not any(o for i, o in zip(interps, out) if not i.task.holding)


@pytest.mark.slow
def test_toys_named_by_colour_are_picked_right(train_result, corpus, labels):
    records = _records(train_result)
    by_colour = [i for i in corpus.instances if _toy_reference(i, labels) == "colour"]
    assert len(by_colour) == 48  # L1 'red chair'/'blue bag', all of L3
    assert [i.name for i in by_colour if not records[i.name]["correct"]] == []


@pytest.mark.slow
def test_toys_named_by_shape_alone_are_picked_right(train_result, corpus, labels):
    records = _records(train_result)
    by_shape = [i for i in corpus.instances if _toy_reference(i, labels) == "shape"]
    assert len(by_shape) == 48
    # A head noun may name a toy's shape PF ("bag" -> toyIsBag), so shape alone picks the toy:
    # the toy of the executed goal is the gold toy (the room may still be misread, as in
    # "push the chair in to the blue room", measured a near tie with a conjunctive reading).
    def toy(goal_text):
        return next(a.args[0] for a in parse_goal(goal_text) if a.predicate == "toyInRoom")

    assert [i.name for i in by_shape if toy(records[i.name]["predicted"]) != toy(records[i.name]["gold"])] == []


@pytest.mark.slow
def test_leave_one_out(corpus, labels, options):
    # Two worker processes: the machine's second core, which pytest leaves idle (the folds are the same).
    result = evaluate(corpus, labels, protocol="loo", learner_options=options, workers=2)
    assert result.n == 120 and not result.failed_folds
    # Measured: 120/120; without held parts (held_parts=false) 108/120, every conjunction whose agent
    # part holds at the start (12) read as the toy goal alone.
    assert result.correct >= 118
    records = _records(result)
    by_colour = [i for i in corpus.instances if _toy_reference(i, labels) == "colour"]
    assert [i.name for i in by_colour if not records[i.name]["correct"]] == []
    single, conjunction = result.per_goal_size[1], result.per_goal_size[2]
    assert single["n"] == 60 and conjunction["n"] == 60
    assert single["correct"] >= 59  # the goal of issue 25: no loss on single goals
    assert conjunction["correct"] >= 57  # and at least 95% of conjunctions


# ---------------------------------------------------------------- novel layouts


@pytest.mark.slow
@pytest.mark.parametrize("layout, train, novel", [("L1", 40, 40), ("L2", 39, 37), ("L3", 40, 40)])
def test_novel_layouts(corpus, labels, options, layout, train, novel):
    # A novel layout carries the goals of one training layout only (its room colours and toys), so
    # each is evaluated with that layout's 40 instances. Measured: 40/40, 39/37, 40/40 (L2's novel misses
    # read a conjunction as its agent part alone, "put the bag in the magenta room then go to the blue room").
    sub = Corpus(corpus.directory, corpus.palette, [i for i in corpus.instances if i.prefix.startswith(layout)])
    state = read_state_file(CORPUS / f"{layout}_novel.state", "sokoban2")
    result = evaluate(sub, labels, protocol="train", novel_states=[(f"{layout}_novel", state)], learner_options=options)
    assert result.n == 40 and result.novel_n == 40 and not result.failed_folds
    assert result.correct >= train
    assert result.novel_correct >= novel


def test_a_novel_layout_lacking_another_layouts_colours_is_refused(corpus, labels):
    state = read_state_file(CORPUS / "L1_novel.state", "sokoban2")
    with pytest.raises(NovelEnvironmentError, match="0 counterparts"):
        evaluate(corpus, labels, protocol="train", novel_states=[("L1_novel", state)])
