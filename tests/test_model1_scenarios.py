"""The paper's three Model 1 scenarios (MacGlashan, Babeş-Vroman et al. 2012), on "Push the star into the green room".

One small world: a green room along the north, red (south-west) and blue
(south-east) rooms below it, doors green-red, green-blue and red-blue. The
yellow star stands in the red-blue doorway (in no room, so all three
toy-to-room groundings of the star are open); a magenta moon sits in a corner
of the green room. The demonstration is the shortest path that takes the star
into the green room: through the blue room, push the star west into the red
room, go round it, push it north through the door into the green room
(13 moves; on the way the star is in the red room, so "into the red room"
would have stopped there).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import torch

from groundlang.corpus import Instance, parse_state
from groundlang.examples.build import shortest_demonstration
from groundlang.grammar import parser
from groundlang.grammar.lexicon import SemanticLexicon
from groundlang.inference.discovery import discover_tasks, lifted_key, write_library
from groundlang.inference.likelihoods import behaviour_likelihood_table
from groundlang.inference.mlirl import MLIRLProblem, mlirl
from groundlang.logic.atoms import Atom, parse_atom, parse_goal
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.domain_words import domain_lexicon
from groundlang.model.features import feature_matrix, position_atoms
from groundlang.model.pf_tables import pf_tables
from groundlang.model.statespace import enumerate_states, trajectory_indices
from groundlang.model.tasks import candidate_tasks, narrow_by_known
from groundlang.model.world import replay


def parse(command, **options):
    """The parser with the Cleanup World's words, as a learner reads commands."""
    return parser.parse(command, word_lexicon=domain_lexicon(), **options)

COMMAND = "Push the star into the green room"
# room,COLOUR,LEFT,TOP,RIGHT,BOTTOM (green=5, red=10, blue=1); block,COLOUR,SHAPE,X,Y (yellow star, magenta moon).
WORLD = ("room,5,0,7,8,4 room,10,0,4,4,0 room,1,4,4,8,0 door,2,4,2,4 door,6,4,6,4 door,4,2,4,2 "
         "block,12,0,4,2 block,7,1,7,6 agent,5,6")
GOLD = parse_goal("toyInRoom(block0, room0)")
# Same MLIRL settings as ``groundlang irl`` and discovery.
IRL = dict(temperature=0.5, l1=0.1, nonnegative=True)


@pytest.fixture(scope="module")
def demo() -> Instance:
    start = parse_state(WORLD, "sokoban")
    actions = shortest_demonstration(start, GOLD)
    return Instance(Path("push_star_green_0.txt"), COMMAND, actions, replay(start, actions))


@pytest.fixture(scope="module")
def library() -> TaskLibrary:
    return TaskLibrary.load()


def _mlirl_weights(demo: Instance, atoms) -> np.ndarray:
    """The MLIRL optimum, solved to where it no longer depends on the machine: in float64, each value
    iteration to 1e-10. At the defaults (float32, 1e-4) the gradient is inexact by about that much, and
    along the flat direction of features that become true together the weights stop where rounding
    leaves them (7.46 on one CPU, 7.40 on another, for the 7.44 below)."""
    space = enumerate_states(demo.initial_state)
    features = feature_matrix(space, atoms, pf_tables(space.layout))
    states = trajectory_indices(space, list(demo.states))
    problem = MLIRLProblem(space.next_state, features, [(states, [int(a) for a in demo.actions])], tol=1e-10,
                           max_sweeps=100_000, dtype=torch.float64)
    return mlirl(None, None, None, problem=problem, max_steps=500, tol=1e-10, **IRL).weights


def test_the_demonstration(demo):
    assert len(demo.actions) == 13
    assert enumerate_states(demo.initial_state).num_states == 1121
    # Halfway, the star is in the red room: a "red room" demonstrator would have stopped there.
    assert [tuple(s.positions[1]) for s in demo.states[7:9]] == [(3, 2), (2, 2)]
    assert tuple(demo.final_state.positions[1]) == (2, 5)


def test_learning_a_new_colour_name(demo, library):
    """Everything known but "green": the demonstration picks the room, and "green" is tied to roomIsGreen."""
    lexicon = SemanticLexicon({"push": {"toyToRoom": 1.0}, "star": {"toyIsStar": 1.0}})
    readings = parse(COMMAND, lexicon=lexicon)
    lf = readings[0].logical_form
    assert readings[0].probability == pytest.approx(0.65, abs=1e-9)
    assert lf.paper_str() == "toyToRoom(star1, room1), toyIsStar(star1), P1(room1, green)"
    # The verb names the lifted task; its arguments are the task's variables in order (toy, room).
    verb = next(r for r in lf.relations if r.kind == "verb")
    task = library.task(verb.name)
    variable_of = dict(zip(verb.args, (v.name for v in task.variables)))
    assert variable_of == {"star1": "T", "room1": "R"}
    known: dict[str, set[str]] = {}
    for r in lf.relations:
        if r.kind in ("isa", "modifier") and r.instantiated and r.args[0] in variable_of:
            known.setdefault(variable_of[r.args[0]], set()).add(r.name)
    unknown = [r for r in lf.relations if r.kind == "modifier" and not r.instantiated]
    assert known == {"T": {"toyIsStar"}}
    assert [(r.name, r.args, r.word) for r in unknown] == [("P1", ("room1", "green"), "green")]

    # TA: all groundings of the library, narrowed to the star's three toy-to-room groundings.
    candidates = candidate_tasks(demo.initial_state, library)
    assert len(candidates) == 19
    narrowed = narrow_by_known(candidates, known, task=verb.name)
    assert [n.grounded.goal_text for n in narrowed] == [
        "toyInRoom(block0, room0)", "toyInRoom(block0, room1)", "toyInRoom(block0, room2)"]
    assert [n.probability for n in narrowed] == pytest.approx([1 / 3] * 3)

    # IRL over the induced features toyIn(star, r): the green room's grounding takes the weight.
    weights = _mlirl_weights(demo, [n.grounded.goal[0] for n in narrowed])
    assert weights[0] == pytest.approx(14.29, abs=0.01)
    assert weights[1:].max() < 0.01

    # Behaviour likelihoods pick the green room; the red room was passed through, not stopped in.
    table = behaviour_likelihood_table([demo], [[n.grounded.goal for n in narrowed]], cache_dir=False)[0]
    assert table == pytest.approx([-2.332, -219.582, -213.298], abs=0.01)
    prior = np.array([n.probability for n in narrowed])
    posterior = prior * np.exp(table - table.max())
    posterior /= posterior.sum()
    assert posterior[1:].sum() < 1e-80

    # "green" is tied to the colour/shape PFs true of R's object, weighted by the posterior.
    room_var = variable_of[unknown[0].args[0]]
    meaning: dict[str, float] = {}
    for n, p in zip(narrowed, posterior):
        room = n.grounded.object_of(room_var)
        for atom in n.constraints[0].atoms:  # the largest consistent constraint: every PF true of it
            if atom.args == (room,):
                meaning[atom.predicate] = meaning.get(atom.predicate, 0.0) + float(p)
    assert sorted(meaning) == ["roomIsBlue", "roomIsGreen", "roomIsRed"]
    assert max(meaning, key=meaning.get) == "roomIsGreen"
    assert meaning["roomIsGreen"] == pytest.approx(1.0) and meaning["roomIsBlue"] < 1e-80
    chosen = narrowed[int(np.argmax(posterior))]
    assert parse_atom("roomIsGreen(room0)") in chosen.constraints[0].atoms
    # The description "the green star"-room pair: the constraint the known word and the new word form.
    assert "toyIsStar(block0) ∧ roomIsGreen(room0)" in [str(c) for c in chosen.constraints]


def test_processing_a_new_command_with_a_known_task(demo, library):
    """No word known, the task library known: the behaviour picks toyToRoom(star, green room)."""
    readings = parse(COMMAND)
    assert [round(r.probability, 2) for r in readings] == [0.65, 0.35]
    assert [r.logical_form.paper_str() for r in readings] == [
        "push(star1, room1), P1(room1, green)", "push(star1), P1(room1, green), into(star1, room1)"]

    candidates = candidate_tasks(demo.initial_state, library)
    counts = {t: sum(g.task == t for g, _ in candidates) for t in library.names}
    assert counts == {"agentToRoom": 2, "toyToRoom": 5, "toyToRoomAgentToRoom": 12}
    table = behaviour_likelihood_table([demo], [[g.goal for g, _ in candidates]], cache_dir=False)[0]
    # Generative prior: lifted task uniform, grounding uniform within it.
    log_prior = np.array([-math.log(len(counts)) - math.log(counts[g.task]) for g, _ in candidates])
    log_post = log_prior + table
    posterior = np.exp(log_post - log_post.max())
    posterior /= posterior.sum()
    order = np.argsort(-posterior, kind="stable")
    best = candidates[order[0]][0]
    assert best.task == "toyToRoom" and best.goal == GOLD
    assert table[order[0]] == pytest.approx(-2.332, abs=0.01)
    assert table[order[0]] - table[order[1]] == pytest.approx(24.49, abs=0.05)
    assert posterior[order[0]] > 1 - 1e-9

    # MLIRL over every position PF: the features with the highest weights, as the paper lists them
    # (1.91 toyIn(t1, r1), 1.12 agentTouchingToy(t1), 0.80 agentIn(r1)). Here the agent ends in the
    # green room's doorway behind the star, so its third feature is agentInDoor.
    atoms = position_atoms(demo.initial_state.layout)
    weights = _mlirl_weights(demo, atoms)
    ranked = sorted(zip(atoms, weights.tolist()), key=lambda aw: -aw[1])[:4]
    assert [str(a) for a, _ in ranked[:3]] == [
        "toyInRoom(block0, room0)", "agentTouchingToy(agent0, block0)", "agentInDoor(agent0, door0)"]
    assert [w for _, w in ranked[:3]] == pytest.approx([7.44, 3.99, 3.10], abs=0.01)
    assert ranked[3][1] < 0.01


def test_learning_from_scratch(demo, library, tmp_path):
    """No words, no tasks: one demonstration yields a toy-to-room lifted task."""
    readings = parse(COMMAND)
    assert [e.head for e in readings[0].logical_form.entities] == ["star", "room"]
    found = discover_tasks([demo], cache_dir=False)
    report = found.demonstrations[0]
    assert report.instances == ("push_star_green_0",)
    # Discovery runs MLIRL at its defaults (float32, value iteration to 1e-4): the likelihood is flat to
    # ~0.01 nats along these weights, so where the optimiser stops moves by a few 0.01 from one CPU to
    # another (7.40 and 7.46 seen) around the optimum of the scenario above (7.44, 3.99).
    assert [str(a) for a, _ in report.top_features] == [
        "toyInRoom(block0, room0)", "agentTouchingToy(agent0, block0)"]
    assert [w for _, w in report.top_features] == pytest.approx([7.40, 4.04], abs=0.1)
    assert [t.name for t in found.tasks] == ["toyToRoom"]
    task = found.tasks[0]
    assert lifted_key(task) == lifted_key(library.task("toyToRoom"))
    # Two objects of the kinds the parse mentions: a toy (the star) and a room.
    assert sorted(v.cls for v in task.variables) == ["room", "toy"]
    assert report.grounding.goal == GOLD and report.log_likelihood == pytest.approx(-2.332, abs=0.01)
    assert dict(report.singled_out) == {"T": (Atom("toyIsYellow", ("block0",)),),
                                        "R": (Atom("roomIsGreen", ("room0",)),)}
    # The runner-up adds agentTouchingToy: the path is 0.06 nats likelier under it, but it has one
    # grounding more (the moon's, 6 not 5: log 6/5 = 0.18 nats) and one atom more to write down.
    assert found.alternatives[1][0] == ("toyToRoomAgentToToy",)
    scores = dict(report.scores)
    assert scores["toyToRoom"] - scores["toyToRoomAgentToToy"] == pytest.approx(0.12, abs=0.02)
    assert found.score - found.alternatives[1][1] == pytest.approx(math.log(5) + 0.12, abs=0.02)
    loaded = TaskLibrary.load([write_library(found, tmp_path / "scratch.lp")])
    goals = [g.goal_text for g, _ in candidate_tasks(demo.initial_state, loaded)]
    # The moon already lies in the green room, so that grounding is left out.
    assert goals == ["toyInRoom(block0, room0)", "toyInRoom(block0, room1)", "toyInRoom(block0, room2)",
                     "toyInRoom(block1, room1)", "toyInRoom(block1, room2)"]


def test_learning_from_scratch_with_restrictions(demo, tmp_path):
    """With restrictions on, the discovered task keeps the PF that singled out the star."""
    from groundlang.inference.discovery import DiscoverySettings
    from groundlang.logic.tasks import TaskLibrary

    found = discover_tasks([demo], DiscoverySettings(restrict=True), cache_dir=False)
    task = found.tasks[0]
    assert task.name == "toyToRoom"
    # From one demonstration, each bound object is restricted by what tells it from its peers:
    # the star by its colour (the moon is magenta), the goal room by its colour.
    assert task.restrictions == (("R", "roomIs(green)"), ("T", "toyIs(yellow)"))
    path = write_library(found, tmp_path / "restricted.lp")
    assert 'restrict(toyToRoom, "T", toyIs(yellow)).' in path.read_text()
    library = TaskLibrary.load([path])
    groundings = candidate_tasks(demo.initial_state, library)
    assert [str(g.goal_text) for g, _ in groundings] == ["toyInRoom(block0, room0)"]
