"""Phrase keys: how a noun phrase's place in the parse (its preposition, whether it says where a motion
ends, whether its clause is negated) becomes the key its alignment table is read by, and how a key backs off
to its preposition (``model.phrase_keys``)."""

from __future__ import annotations

import pytest
import torch

from groundlang.learner import Learner
from groundlang.model.language_models import ParseAligned


@pytest.mark.parametrize("command, keys", [
    ("take the star to the red room", [None, "to+obj|last"]),  # where the object goes
    ("go to the red room", ["to|last"]),  # where the agent goes
    ("go into the green room and push it to the blue room", ["into", None, "to+obj|last"]),
    ("take the star to the red room with you", [None, "to+obj|last", "with+obj"]),  # "you" has no words
    ("push the star", ["dobj|last"]),
    # what must not be done is not where a command ends: |last passes over a negated clause
    ("do not enter the green room", ["not:dobj"]),
    ("go to the red room, do not go to the blue room", ["to|last", "not:to"]),
    # where a motion starts or what goes along is never where it ends: |last passes over it
    ("go to the beige room with the star", ["to|last", "with"]),
    ("walk to the white room from the orange room", ["to|last", "from"]),
    ("push the star into the red room from the blue room", [None, "into+obj|last", "from+obj"]),
])
def test_preposition_keys_tell_transitive_clauses_apart(command, keys):
    from groundlang.grammar.parser import parse
    from groundlang.model.phrase_keys import entity_words

    assert [key for key, _, _ in entity_words(parse(command)[0].logical_form)] == keys


def test_a_noun_attached_with_phrase_may_say_where_things_end():
    """Only a verb-attached "with" is comitative; in "the room with the green floor" it names the room."""
    from groundlang.grammar.parser import parse
    from groundlang.model.phrase_keys import entity_words

    readings = {tuple(key for key, _, _ in entity_words(r.logical_form)) for r in parse("enter the room with the green floor")}
    assert (None, "with@np|last") in readings  # the floor is the room's
    assert ("dobj|last", "with+obj") in readings  # "with" attached to the verb: passed over


@pytest.mark.parametrize("key, base", [
    ("from+obj|last", "from"), ("to+obj", "to"), ("to|last", "to"), ("dobj|last", "<dobj>"), ("<dobj>", "<dobj>"),
    ("not:dobj|last", "not:dobj"), ("to@np|last", "to@np"), ("into", "into"),
])
def test_a_key_backs_off_to_its_preposition(key, base):
    from groundlang.model.phrase_keys import backoff_key

    assert backoff_key(key) == base


def test_em_with_back_off_never_lowers_the_objective():
    """EM's M step (weights * gradient = expected counts) holds for the mixture: every step climbs, and
    the weights of a key that backs off to another ("to|last" to "to") move away from their start."""
    import dataclasses

    from groundlang.corpus import example_corpus_path, read_corpus
    from groundlang.model.phrase_keys import backoff_key

    instances = {i.name: i for i in read_corpus(example_corpus_path(), "sokoban").instances}
    train = []
    for colour in ("red", "green", "blue"):
        for n, command in enumerate((f"go to the {colour} room", f"walk to the {colour} room",
                                     f"go to the {colour} room and stop in the middle",
                                     f"walk to the {colour} room and wait by the door")):
            train.append(dataclasses.replace(instances[f"agent2{colour}_{n % 4}"], command=command))
    learner = Learner(ParseAligned(align_backoff=True)).fit(train)
    losses = learner.fit_result.losses
    assert len(losses) > 3 and all(b <= a + 1e-6 * abs(a) for a, b in zip(losses, losses[1:]))
    assert learner.fit_result.converged
    vocab, weights = learner.vocab, learner.globals["backoff"]
    assert torch.allclose(weights.sum(-1), torch.ones(1))
    assert backoff_key("to|last") == "to" and {"to", "to|last"} <= set(vocab.preps)
    row = vocab.task_id("agentToRoom") * len(vocab.preps) + vocab.preps.index("to|last")
    assert abs(float(weights[row, 0]) - 0.5) > 0.05, weights[row]


def test_the_reserved_keys_are_never_shown_as_prepositions_learned():
    """``<other>``, ``<dobj>`` and ``<not>`` are keys of the vocabulary, not prepositions anyone says: even with
    mass on them (a table learned otherwise) ``lexicon --prepositions`` lists only said ones."""
    from groundlang.model.prepositions import preposition_table
    from groundlang.model.vocabulary import NEGATED_PREP, Vocabulary

    vocab = Vocabulary()
    vocab.add_tasks(["agentToRoom", "toyToRoom", "both"])
    vocab.add_preps(["to", "into"])
    table = torch.full((3, len(vocab.preps)), 0.001)
    for task, keys in enumerate([(NEGATED_PREP,), ("to",), ("<other>", "<dobj>")]):
        for key in keys:  # each well above the share that counts as learned
            table[task, vocab.preps.index(key)] = 1.0
    tasks, preps, given = preposition_table({"preposition": table / table.sum(-1, keepdim=True)}, vocab)
    assert preps == ["to"] and tasks == ["agentToRoom", "toyToRoom", "both"] and given.shape == (3, 1)
