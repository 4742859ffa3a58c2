"""A language model is one module and one registry entry: a toy model added here, and nothing else.

The toy is a unigram over the logical form's predicates: every word of a command is drawn from a
uniform mixture of the goal's predicates (``agentInRoom``, ``toyInRoom``), ``P(words | goal) = prod_w
mean_p phi[p, w]``. It encodes its own batch (a subclass of the shared ``Batch`` with one field, filled
by ``encode_fields``) and uses only the base's Pyro site (``phi``); the learner trains it, reads commands
with it and saves and loads it by name.
"""

from __future__ import annotations

from dataclasses import dataclass

import pytest
import torch

from groundlang.corpus import example_corpus_path, read_state_file
from groundlang.learner import Learner
from groundlang.model.encoding import Batch, Encoder
from groundlang.model.language_model_base import LanguageModel, gather_mixtures, mixture_log_emissions
from groundlang.model.language_models import LANGUAGE_MODELS, get_language_model, register_language_model


@dataclass
class PredicateBatch(Batch):
    goal_mix: torch.Tensor  # [I, J] the mixture of the goal's predicates


class PredicateUnigram(LanguageModel):
    name = "predicate-unigram-test"
    starts_from_bag_of_words = False
    batch_type = PredicateBatch

    def encode_fields(self, enc: Encoder) -> dict:
        goal_mix = enc.per_interpretation(enc.null_mixture)
        for i, j, interp in enc.interpretations():
            goal_mix[i, j] = enc.mixture({enc.vocab.token_id(atom.predicate) for atom in interp.goal})
        return {"goal_mix": goal_mix}

    def log_likelihood(self, g: dict, batch: PredicateBatch) -> torch.Tensor:
        per_word = gather_mixtures(mixture_log_emissions(g, batch), batch.goal_mix, batch.uniq)  # [I, J, U]
        return (per_word * batch.word_counts[:, None, :]).sum(-1)


@pytest.fixture()
def registered():
    register_language_model(PredicateUnigram)
    yield PredicateUnigram
    LANGUAGE_MODELS.pop(PredicateUnigram.name)


def test_a_new_language_model_trains_reads_and_round_trips_by_name(registered, corpus, tmp_path):
    learner = Learner(PredicateUnigram.name).fit(corpus.instances)
    state = read_state_file(example_corpus_path() / "novel_a.state", "sokoban")
    tasks = learner.posterior("go to the room", state).lifted_tasks()
    moved = learner.posterior("push the star", state).lifted_tasks()
    # The example corpus sends the agent to rooms and pushes the star: the task's words tell them apart.
    assert max(tasks, key=tasks.get) == "agentToRoom"
    assert max(moved, key=moved.get) != "agentToRoom"
    assert learner.posterior("go to the room", state).reading_probabilities is None  # it reads no parse
    assert learner.alignments("go to the room", state) == []  # it aligns no phrase
    again = Learner.load(learner.save(tmp_path / "m"))
    assert type(again.lm) is PredicateUnigram
    assert again.posterior("go to the room", state).lifted_tasks() == pytest.approx(tasks)


def test_the_registry_refuses_a_second_model_of_one_name_and_what_is_no_model(registered):
    assert get_language_model(PredicateUnigram.name).name == PredicateUnigram.name
    assert register_language_model(PredicateUnigram) is PredicateUnigram  # the same class again is fine

    class Impostor(LanguageModel):
        name = PredicateUnigram.name

    with pytest.raises(ValueError, match="exists already"):
        register_language_model(Impostor)
    with pytest.raises(TypeError, match="LanguageModel subclass"):
        register_language_model(dict)


def test_each_model_encodes_only_what_it_reads(corpus):
    """The bag of words reads the shared batch; IBM Model 2 adds machine strings, the parse model readings
    and roles; none carries another's fields."""
    learner = Learner("parse").fit(corpus.instances[:6], observations=None)
    observations = learner.observe(corpus.instances[:6])
    own = {}
    for name in ("bow", "ibm2", "parse"):
        lm = get_language_model(name)
        batch = lm.encode(observations, learner.vocab)
        assert isinstance(batch, lm.batch_type)
        own[name] = set(vars(batch)) - set(vars(get_language_model("bow").encode(observations, learner.vocab)))
    assert own["bow"] == set()
    assert own["ibm2"] == {"words", "word_mask", "machine", "machine_mask"}
    assert {"role", "reading_logp", "cover_slot"} <= own["parse"] and not own["parse"] & own["ibm2"]


def test_fit_refuses_a_batch_another_model_encoded(corpus):
    learner = Learner("parse").fit(corpus.instances[:6])
    observations = learner.observe(corpus.instances[:6])
    bag = get_language_model("bow").encode(observations, learner.vocab)
    with pytest.raises(TypeError, match=r"language model parse reads a ParseBatch \(lm.encode\), not a Batch"):
        learner.fit(corpus.instances[:6], batch=bag)
    refit = learner.fit(corpus.instances[:6], batch=learner.lm.encode(observations, learner.vocab))
    assert refit.globals is not None
