"""A language model is one module and one registry entry: a toy model added here, and nothing else.

The toy is a unigram over the lifted task: every word of a command is drawn from one categorical per
lifted task, ``P(words | L) = prod_w phi[L, w]``. It uses only the base's Pyro site (``phi``) and the
batch's ``task_token``; the learner trains it, reads commands with it and saves and loads it by name.
"""

from __future__ import annotations

import pytest
import torch

from groundlang.corpus import example_corpus_path, read_corpus, read_state_file
from groundlang.learner import Learner
from groundlang.model.encoding import Batch
from groundlang.model.language_model_base import LanguageModel
from groundlang.model.language_models import LANGUAGE_MODELS, get_language_model, register_language_model


class TaskUnigram(LanguageModel):
    name = "task-unigram-test"
    starts_from_bag_of_words = False

    def log_likelihood(self, g: dict, batch: Batch) -> torch.Tensor:
        log_phi = g["phi"].clamp_min(1e-30).log()  # [tokens, W]
        per_word = log_phi[batch.task_token[:, :, None], batch.uniq[:, None, :]]  # [I, J, U]
        return (per_word * batch.word_counts[:, None, :]).sum(-1)


@pytest.fixture()
def registered():
    register_language_model(TaskUnigram)
    yield TaskUnigram
    LANGUAGE_MODELS.pop(TaskUnigram.name)


@pytest.fixture(scope="module")
def corpus():
    return read_corpus(example_corpus_path(), "sokoban")


def test_a_new_language_model_trains_reads_and_round_trips_by_name(registered, corpus, tmp_path):
    learner = Learner(TaskUnigram.name).fit(corpus.instances)
    state = read_state_file(example_corpus_path() / "novel_a.state", "sokoban")
    tasks = learner.posterior("go to the room", state).lifted_tasks()
    moved = learner.posterior("push the star", state).lifted_tasks()
    # The example corpus sends the agent to rooms and pushes the star: the task's words tell them apart.
    assert max(tasks, key=tasks.get) == "agentToRoom"
    assert max(moved, key=moved.get) != "agentToRoom"
    assert learner.posterior("go to the room", state).reading_probabilities is None  # it reads no parse
    assert learner.alignments("go to the room", state) == []  # it aligns no phrase
    again = Learner.load(learner.save(tmp_path / "m"))
    assert type(again.lm) is TaskUnigram
    assert again.posterior("go to the room", state).lifted_tasks() == pytest.approx(tasks)


def test_the_registry_refuses_a_second_model_of_one_name_and_what_is_no_model(registered):
    assert get_language_model(TaskUnigram.name).name == TaskUnigram.name
    assert register_language_model(TaskUnigram) is TaskUnigram  # the same class again is fine

    class Impostor(LanguageModel):
        name = TaskUnigram.name

    with pytest.raises(ValueError, match="exists already"):
        register_language_model(Impostor)
    with pytest.raises(TypeError, match="LanguageModel subclass"):
        register_language_model(dict)
