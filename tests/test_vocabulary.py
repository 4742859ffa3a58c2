"""Vocabularies: indices, misspellings read as the word meant (model.vocabulary), and the roles an
interpretation offers the objects of a layout."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pytest

from groundlang.corpus import read_state_file
from groundlang.learner import Learner
from groundlang.model.vocabulary import UNK, Vocabulary

WORDS = ["orange", "white", "through", "room", "peach", "reach", "right", "light", "star"]


def vocabulary(counts: dict[str, int]) -> Vocabulary:
    vocab = Vocabulary()
    vocab.add_words(counts)
    vocab.read_misspellings(Counter(counts))
    return vocab


def test_a_rare_word_one_edit_from_one_common_word_reads_as_it():
    counts = {"orange": 30, "white": 5, "through": 9, "orage": 1, "whlite": 1, "throught": 1, "ornge": 1}
    vocab = vocabulary(counts)
    assert vocab.aliases == {"orage": "orange", "ornge": "orange", "whlite": "white", "throught": "through"}
    assert vocab.word_id("orage") == vocab.word_id("orange") != 0
    assert vocab.word_id("whlite") == vocab.word_id("white")


def test_real_words_and_short_words_are_left_alone():
    # "reach"/"peach" and "light"/"right" differ in the first letter; in training, "star"/"stars" is
    # too short to tell from another word; "white" is common itself.
    counts = {"peach": 5, "reach": 1, "right": 9, "light": 1, "stars": 4, "star": 1, "white": 5, "whites": 1,
              "whitey": 1}
    vocab = vocabulary(counts)
    assert vocab.aliases == {"whites": "white", "whitey": "white"}
    assert vocab.word_id("reach") != vocab.word_id("peach")


def test_an_unknown_word_reads_as_its_one_known_neighbour_or_unk():
    vocab = vocabulary({w: 5 for w in WORDS})
    assert vocab.word_id("orangey") == vocab.word_id("orange")
    assert vocab.word_id("rigth") == vocab.word_id("right")  # a transposition
    assert vocab.word_id("peaches") == 0  # two edits
    assert vocab.word_id("lighd") == vocab.word_id("light")
    assert vocab.word_id("xyzzy") == 0 and vocab.words[0] == UNK
    assert vocab.word_id("stat") == vocab.word_id("star")  # four letters, one neighbour
    assert vocab.word_id("rom") == 0  # shorter than four letters: never corrected
    short = vocabulary({w: 5 for w in ("green", "gray", "red", "room")})
    assert short.word_id("gren") == short.word_id("green")  # "gray" is two edits away
    both = vocabulary({w: 5 for w in ("green", "grey")})
    assert both.word_id("gren") == 0  # one edit from "green" and from "grey": which one is not known


def test_words_the_lexicon_lists_as_other_kinds_stay_apart():
    vocab = vocabulary({"white": 9, "there": 9, "black": 9, "while": 1, "three": 1, "block": 1})
    assert vocab.aliases == {}
    for word in ("while", "three", "block"):
        assert vocab.word_id(word) != vocab.word_id({"while": "white", "three": "there", "block": "black"}[word])
    unseen = vocabulary({"white": 9, "orange": 9})
    assert unseen.word_id("while") == 0  # unknown, but not a typo of "white"
    assert unseen.word_id("orangey") == unseen.word_id("orange")  # both colours in the lexicon


def test_aliases_survive_a_round_trip_through_json():
    vocab = vocabulary({"orange": 30, "orage": 1})
    again = Vocabulary.from_json(vocab.to_json())
    assert again.aliases == {"orage": "orange"}
    assert again.word_id("orage") == again.word_id("orange")


def test_a_saved_learner_keeps_its_aliases_and_its_lexicon_leaves_them_out(tmp_path):
    import dataclasses

    from groundlang.corpus import example_corpus_path, read_corpus
    from groundlang.learner import Learner

    corpus = read_corpus(example_corpus_path(), "sokoban")
    green = next(i for i in corpus.instances if "green" in i.command)
    typo = dataclasses.replace(green, command=green.command.replace("green", "greeen"))
    learner = Learner("bow").fit(list(corpus.instances) + [typo])
    assert learner.vocab.aliases == {"greeen": "green"}
    assert "greeen" not in learner.lexicon() and "green" in learner.lexicon()
    again = Learner.load(learner.save(tmp_path / "model"))
    assert again.vocab.aliases == {"greeen": "green"}
    assert again.vocab.word_id("greeen") == again.vocab.word_id("green")



def test_lifted_tasks_are_indexed_apart_from_tokens_and_survive_json():
    vocab = Vocabulary()
    vocab.add_tokens(["roomIsRed"])
    vocab.add_tasks(["agentToRoom", "toyToRoom"])
    assert vocab.tasks == ["agentToRoom", "toyToRoom"]
    assert [vocab.task_id(t) for t in vocab.tasks] == [0, 1]
    assert vocab.has_token("toyToRoom")  # a task is also a token: the words it explains
    again = Vocabulary.from_json(vocab.to_json())
    assert again.tasks == vocab.tasks and again.task_id("toyToRoom") == 1
    with pytest.raises(ValueError, match="agentToDoor.*not in the vocabulary.*agentToRoom, toyToRoom"):
        vocab.task_id("agentToDoor")


def test_the_room_the_agent_starts_in_has_a_role_of_its_own():
    """Inside a room: that room is the start room and nothing else. On a door cell (the novel layouts):
    every room not bound may be the start room or another room."""
    from groundlang.corpus import example_corpus_path, read_corpus
    from groundlang.model.interpretations import START_ROLE, interpretations, start_rooms

    library = Learner("parse").library
    from groundlang.logic.atoms import Atom
    from groundlang.model.features import atoms_hold
    from groundlang.model.pf_tables import pf_tables

    inside = read_corpus(example_corpus_path(), "sokoban").instances[0].initial_state
    (room,), known = start_rooms(inside)
    assert known and atoms_hold(inside, [Atom("agentInRoom", ("agent0", room))], pf_tables(inside.layout)).all()
    for interp in interpretations(inside, library, enumerate_constraints=False):
        roles = {(rb.role, rb.obj) for rb in interp.roles if rb.cls == "room"}
        bound = {rb.obj for rb in interp.roles if rb.cls == "room" and not rb.role.startswith("other:")}
        assert ((START_ROLE, room) in roles) == (room not in bound)
        assert ("other:room", room) not in roles
    door = read_state_file(Path(__file__).parent / "fixtures" / "novel_envs" / "novel_a.state", "sokoban")
    starts, known = start_rooms(door)
    assert not known and starts == set(door.layout.room_names)
    for interp in interpretations(door, library, enumerate_constraints=False):
        bound = {rb.obj for rb in interp.roles if rb.cls == "room" and not rb.role.startswith("other:")}
        free = set(door.layout.room_names) - bound
        assert {rb.obj for rb in interp.roles if rb.role == START_ROLE} == free
        assert {rb.obj for rb in interp.roles if rb.role == "other:room"} == free
