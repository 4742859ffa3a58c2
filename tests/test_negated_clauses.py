"""A phrase in a negated clause says where things must not go, so it is not where a command ends
(``PhraseKeys.last_passes_over_negated``): "go to the red room, do not go to the blue room" said in the red
room reads as the red room it is in, and is asked about, rather than as the blue room the words forbid. Nor
does it name, a priori, what the task binds (``negated_phrases_unbiased``): a model whose training never
negated anything reads it so too."""

from __future__ import annotations

import pytest
import torch

from groundlang.corpus import read_corpus, read_state_file
from groundlang.learner import Learner
from groundlang.logic.atoms import Atom
from groundlang.model.generative import global_sizes
from groundlang.model.language_models import get_language_model
from groundlang.model.vocabulary import NEGATED_PREP, Vocabulary

RED = (Atom("agentInRoom", ("agent0", "room2")),)


def _trained(shared_corpus, **settings) -> Learner:
    corpus = read_corpus(shared_corpus / "allTurkTrain", "sokoban")
    return Learner(get_language_model("parse", **settings)).fit(corpus.instances)


@pytest.fixture(scope="module")
def in_red_room(tmp_path_factory):
    from groundlang.corpus import example_corpus_path

    layout = (example_corpus_path() / "novel_a.state").read_text().split(" agent,")[0]
    path = tmp_path_factory.mktemp("negated") / "inside.state"
    path.write_text(layout + " agent,3,3\n")  # in the red room, room2
    return read_state_file(path, "sokoban")


# The second asks with the switch off too (its held reading 0.87 then): it states what following does, and
# the switched-off test below is the first's.
@pytest.mark.parametrize("command", ["go to the red room, do not go to the blue room",
                                     "go to the red room without going through the blue room"])
def test_a_negated_phrase_after_the_goal_does_not_take_its_place(shared_corpus, in_red_room, command):
    asked = _trained(shared_corpus).follow(command, in_red_room, min_confidence=0.7)
    assert asked.already_true and asked.abstained and asked.goal == RED and asked.actions == []
    assert asked.held_reading[0] == RED and asked.held_reading[1] > 0.7


@pytest.mark.parametrize("settings, asks", [
    ({"last_passes_over_negated": False, "negated_phrases_unbiased": False}, False),
    ({"last_passes_over_negated": False}, True),  # the negated phrase's prior alone reads it so
    ({"negated_phrases_unbiased": False}, True),  # and so does the last phrase alone
])
def test_switched_off_the_negated_phrase_is_the_last_and_the_red_room_is_not_asked(shared_corpus, in_red_room,
                                                                                  settings, asks):
    learner = _trained(shared_corpus, **settings)
    result = learner.follow("go to the red room, do not go to the blue room", in_red_room, min_confidence=0.7)
    assert result.already_true == asks and (result.goal == RED) == asks


def test_a_negated_phrase_training_never_saw_reads_as_an_unseen_negated_one():
    vocab = Vocabulary()
    vocab.add_preps(["to|last", "not:to"])
    assert vocab.prep_id("not:to") == vocab.preps.index("not:to")
    assert vocab.prep_id("not:onto|last") == vocab.preps.index(NEGATED_PREP)
    assert vocab.prep_id("onto|last") == 0  # an unseen preposition, as before
    saved_before = Vocabulary.from_json({**vocab.to_json(), "preps": ["<other>", "<dobj>", "to|last", "not:to"]})
    assert saved_before.prep_id("not:onto|last") == 0  # a vocabulary saved before the key existed reads as it did


@pytest.mark.parametrize("on", [True, False])
def test_the_alignment_prior_of_a_negated_phrase_does_not_favour_the_tasks_own_roles(learner, on):
    import pyro

    vocab = learner.vocab
    lm = get_language_model("parse", negated_phrases_unbiased=on)
    trace = pyro.poutine.trace(lm.sample_globals).get_trace(**global_sizes(vocab))
    prior = trace.nodes["align"]["fn"]
    prior = getattr(prior, "base_dist", prior).concentration.reshape(len(vocab.tasks), len(vocab.preps), -1)
    t, to, negated = vocab.task_id("agentToRoom"), vocab.prep_id("to|last"), vocab.prep_id("not:to")
    goal_room, other_room = vocab.roles.index("agentInRoom.1"), vocab.roles.index("other:room")
    assert prior[t, to, goal_room] > prior[t, to, other_room]  # an unnegated phrase: the task's own role
    if on:  # what a negated phrase names may be the toy's goal room ("... without walking into the teal room")
        assert float(prior[t, negated, goal_room]) == float(prior[t, negated, other_room]) == lm.align_concentration
        assert float(prior[t, to, goal_room]) == lm.align_concentration + lm.argument_bonus
    else:
        assert torch.equal(prior[t, negated], prior[t, to])


def test_a_model_that_never_saw_negation_asks_about_the_room_the_words_name(learner, in_red_room):
    """The example corpus's 24 commands negate nothing: what the negated phrase names is read by the prior."""
    asked = learner.follow("go to the red room, do not go to the blue room", in_red_room, min_confidence=0.7)
    assert asked.already_true and asked.abstained and asked.goal == RED and asked.actions == []
    assert asked.held_reading[0] == RED and asked.held_reading[1] > 0.8


def test_switched_off_a_model_that_never_saw_negation_walks_into_the_room_the_words_forbid(corpus, in_red_room):
    learner = Learner(get_language_model("parse", negated_phrases_unbiased=False)).fit(corpus.instances)
    result = learner.follow("go to the red room, do not go to the blue room", in_red_room, min_confidence=0.7)
    assert not result.already_true and result.goal == (Atom("agentInRoom", ("agent0", "room0")),)
