"""Tests for groundlang.grammar.logical_form and the composition of logical forms from phrases."""

from __future__ import annotations

import json

import pytest

from groundlang.grammar.composition import compose
from groundlang.grammar.logical_form import Clause, Entity, LogicalForm, Reading, Relation
from groundlang.grammar import parser
from groundlang.grammar.phrases import NP, PP, VP, Sub
from groundlang.model.domain_words import domain_lexicon


def parse(command, **options):
    """The parser with the Cleanup World's words, as a learner reads commands."""
    return parser.parse(command, word_lexicon=domain_lexicon(), **options)


def test_relation_printing_and_instantiation_flag():
    assert str(Relation("P1", ("room1", "green"), "green")) == "P1(room1, green)"
    assert not Relation("P1", ("room1", "green"), "green").instantiated
    assert Relation("roomIsGreen", ("room1",), "green").instantiated
    assert not Relation("isa", ("star1", "star"), "star", "isa").instantiated
    assert str(Relation("enter", ("room1",), "enter", "verb", negated=True)) == "not enter(room1)"


def test_compose_names_variables_like_the_paper():
    clauses = (
        VP(verb="pushing", obj=NP(det="the", head="star"),
           comps=(PP("into", NP(mods=("green",), head="room")),)),
        VP(verb="take", obj=NP(pron="it"), comps=(PP("to", NP(mods=("tan",))), PP("into", NP(head="room")))),
    )
    lf = compose(clauses, ("w",), ("NOUN",), fallback=False)
    assert [e.var for e in lf.entities] == ["star1", "room1", "it1", "tan1", "room2"]
    assert lf.verbs == ("push", "take")
    assert lf.paper_str() == "push(star1, room1), P1(room1, green), take(it1, tan1, room2), P2(tan1, tan)"
    assert lf.entity("it1").pronoun == "it" and lf.entity("tan1").head is None
    with pytest.raises(KeyError, match="nope"):
        lf.entity("nope")


def test_compose_noun_attachment_and_subordinate_clause_order():
    star = NP(head="star", attached=(PP("into", NP(head="room")),))
    clauses = (VP(verb="push", obj=star, comps=(Sub("until", VP(verb="reach", subject=NP(head="star"))),)),)
    lf = compose(clauses, (), (), fallback=False)
    assert lf.attachments == (("into", "star1", "room1"),)
    assert [(c.verb, c.connective, c.subject) for c in lf.clauses] == [("push", None, None), ("reach", "until", "star2")]
    assert lf.entity("room1").role == "npp" and lf.entity("room1").parent == "star1"
    assert lf.paper_str() == "push(star1), into(star1, room1), reach()"


def test_verbless_clause_prints_underscore_and_headless_fallback_name():
    lf = compose((VP(obj=NP(det="the")),), (), (), fallback=True)
    assert lf.entities[0].var == "x1" and lf.paper_str() == "_(x1)" and lf.fallback


def test_to_json_is_json_serialisable_and_complete():
    reading = parse("Push the star into the green room")[1]
    data = reading.logical_form.to_json()
    assert json.loads(json.dumps(data)) == data
    assert data["logical_form"] == "push(star1), P1(room1, green), into(star1, room1)"
    assert data["attachments"] == [["into", "star1", "room1"]]
    assert data["clauses"][0] == {"verb": "push", "args": ["star1"], "preps": [], "negated": False,
                                  "subject": None, "connective": None, "adverbs": []}
    assert data["entities"][1]["role"] == "npp"
    assert reading.to_json() == {"logical_form": data["logical_form"], "probability": pytest.approx(0.35),
                                 "fallback": False}


def test_dataclasses_are_frozen_and_hashable():
    lf = LogicalForm((Clause("go", ("room1",), (("to", "room1"),)),),
                     (Entity("room1", "room", (), None, 0, "vpp", "to"),), (), (), ("go",))
    assert hash(lf) == hash(Reading(lf, 1.0).logical_form)
    with pytest.raises(AttributeError):
        lf.fallback = True  # type: ignore[misc]
