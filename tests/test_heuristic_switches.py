"""The parse model's heuristics as switches: the preposition keys' marks, the start room's role and the
bystanders' roles (``--lm-setting NAME=false``), and the held-out likelihood that measures each
(``groundlang ablate --held-out-likelihood``)."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import pytest

from groundlang.cli import main
from groundlang.corpus import example_corpus_path, read_corpus, read_state_file
from groundlang.grammar.parser import parse
from groundlang.learner import Learner
from groundlang.model.interpretations import BYSTANDER_ROLE, START_ROLE, interpretations
from groundlang.model.language_models import get_language_model
from groundlang.model.phrase_keys import PhraseKeys, entity_words

EXAMPLES = example_corpus_path()
NOVEL_A = Path(__file__).parent / "fixtures" / "novel_envs" / "novel_a.state"
SWITCHES = ("last_phrase_key", "object_key", "last_passes_over_source", "noun_attached_key", "negation_key",
            "last_passes_over_negated", "start_role", "bystander_roles", "largest_constraint", "negated_verbs_frame", "mention_task_objects")


def _keys(command: str, **switches) -> list:
    return [key for key, _, _ in entity_words(parse(command)[0].logical_form, keys=PhraseKeys(**switches))]


@pytest.mark.parametrize("command, switches, keys", [
    ("take the star to the red room", {}, [None, "to+obj|last"]),
    ("take the star to the red room", {"last_phrase_key": False}, [None, "to+obj"]),
    ("take the star to the red room", {"object_key": False}, [None, "to|last"]),
    ("take the star to the red room", {"object_key": False, "last_phrase_key": False}, [None, "to"]),
    ("walk to the white room from the orange room", {}, ["to|last", "from"]),
    ("walk to the white room from the orange room", {"last_passes_over_source": False}, ["to", "from|last"]),
    ("go to the beige room with the star", {"last_passes_over_source": False}, ["to", "with|last"]),
    # passing over means nothing without a last phrase's key
    ("walk to the white room from the orange room", {"last_phrase_key": False, "last_passes_over_source": False},
     ["to", "from"]),
    ("go to the room that has the chair", {}, ["to", "with@np|last"]),
    ("go to the room that has the chair", {"noun_attached_key": False}, ["to", "with|last"]),
    # a command saying only what not to do says nowhere things end: no phrase is its last
    ("do not enter the green room", {}, ["not:dobj"]),
    ("do not enter the green room", {"last_passes_over_negated": False}, ["not:dobj|last"]),
    ("do not enter the green room", {"negation_key": False, "last_passes_over_negated": False}, ["dobj|last"]),
    ("take the star to the green room, but do not enter the green room", {}, [None, "to+obj|last", "not:dobj"]),
    ("take the star to the green room, but do not enter the green room", {"last_passes_over_negated": False},
     [None, "to+obj", "not:dobj|last"]),
])
def test_each_key_switch_removes_its_mark(command, switches, keys):
    assert _keys(command, **switches) == keys


def test_the_model_encodes_with_its_own_keys_and_defaults_are_todays():
    assert get_language_model("parse").phrase_keys() == PhraseKeys()
    assert get_language_model("bow").phrase_keys() == PhraseKeys()
    lm = get_language_model("parse", object_key=False, last_passes_over_source=False)
    assert lm.phrase_keys() == PhraseKeys(last_phrase_key=True, object_key=False, last_passes_over_source=False)
    assert all(get_language_model("parse").settings()[name] is True for name in SWITCHES)


def _roles(state, **switches) -> list[list[tuple[str, str]]]:
    library = Learner("parse").library
    return [[(rb.role, rb.obj) for rb in interp.roles]
            for interp in interpretations(state, library, enumerate_constraints=False, **switches)]


def test_without_the_start_role_the_start_room_is_another_room():
    """On a door cell every free room is offered twice (start and other) with the role; once without."""
    door = read_state_file(NOVEL_A, "sokoban")
    with_role, without = _roles(door), _roles(door, start_role=False)
    assert len(with_role) == len(without)
    for on, off in zip(with_role, without):
        assert any(role == START_ROLE for role, _ in on)
        assert not any(role == START_ROLE for role, _ in off)
        assert [x for x in on if x[0] != START_ROLE] == off  # the same objects, each once


def test_without_bystander_roles_every_bystander_shares_one_role():
    state = read_corpus(EXAMPLES, "sokoban").instances[0].initial_state
    for on, off in zip(_roles(state), _roles(state, bystander_roles=False)):
        assert [obj for _, obj in on] == [obj for _, obj in off]
        for (role_on, _), (role_off, _) in zip(on, off):
            if role_on.startswith("other:") and role_on != START_ROLE and role_on != "other:agent":
                assert role_off == BYSTANDER_ROLE
            else:
                assert role_off == role_on  # the task's own roles, the start room and the addressee kept


@pytest.fixture(scope="module")
def examples():
    return read_corpus(EXAMPLES, "sokoban").instances


def test_a_learner_trained_with_switches_off_knows_neither_mark_nor_role(examples):
    lm = get_language_model("parse", last_phrase_key=False, object_key=False, start_role=False,
                            bystander_roles=False)
    learner = Learner(language_model=lm, steps=20).fit(examples[::3])
    assert not any("|last" in p or "+obj" in p for p in learner.vocab.preps)
    assert START_ROLE not in learner.vocab.roles and "other:room" not in learner.vocab.roles
    assert BYSTANDER_ROLE in learner.vocab.roles
    post = learner.posterior("take the star to the red room", examples[0].initial_state)
    assert math.isclose(float(post.probabilities.sum()), 1.0, rel_tol=1e-5)
    default = Learner("parse", steps=20).fit(examples[::3])
    assert "to+obj|last" in default.vocab.preps and START_ROLE in default.vocab.roles


def test_a_model_saved_before_the_switches_loads_with_the_defaults(examples):
    learner = Learner("parse", steps=5).fit(examples[:4])
    state = learner.state_dict()
    for name in SWITCHES:  # as a model saved before these settings existed
        del state["language_model_settings"][name]
    loaded = Learner.from_state_dict(state)
    # all but one: a model saved before the last phrase passed over a negated one reads with the keys it learned
    assert all(loaded.lm.settings()[name] is (name != "last_passes_over_negated") for name in SWITCHES)
    assert loaded.lm.phrase_keys() == PhraseKeys(last_passes_over_negated=False)


def test_a_model_saved_before_habit_prior_weighs_its_habits_as_it_did(examples):
    """Such a model shrank its habits towards a relation's overall rate; loaded, it follows as it did, while a
    model saved with the setting keeps its own (the default, absent, for one trained now)."""
    learner = Learner("parse", steps=5).fit(examples[:4])
    state = learner.state_dict()
    assert state["language_model_settings"]["habit_prior"] == "absent"
    assert Learner.from_state_dict(state).lm.habit_prior == "absent"
    del state["language_model_settings"]["habit_prior"]
    assert Learner.from_state_dict(state).lm.habit_prior == "overall"


def test_a_model_saved_before_success_confidence_asks_as_it_did(examples):
    learner = Learner("parse", steps=5).fit(examples[:4])
    state = learner.state_dict()
    assert Learner.from_state_dict(state).lm.success_confidence is True
    del state["language_model_settings"]["success_confidence"]
    assert Learner.from_state_dict(state).lm.success_confidence is False


def test_a_model_saved_before_held_goals_confidence_asks_as_it_did(examples):
    learner = Learner(get_language_model("parse", held_goals_confidence=True), steps=5).fit(examples[:4])
    state = learner.state_dict()
    assert Learner.from_state_dict(state).lm.held_goals_confidence is True
    del state["language_model_settings"]["held_goals_confidence"]
    assert Learner.from_state_dict(state).lm.held_goals_confidence is False


@pytest.mark.parametrize("name", SWITCHES)
def test_train_accepts_each_switch_off_and_refuses_a_wrong_value_in_one_line(name, tmp_path, capsys):
    model = tmp_path / "model"
    assert main(["--quiet", "train", str(EXAMPLES), "--palette", "sokoban", "-o", str(model),
                 "--lm-setting", f"{name}=false"]) == 0
    assert Learner.load(model).lm.settings()[name] is False
    assert main(["--quiet", "train", str(EXAMPLES), "--palette", "sokoban", "-o", str(tmp_path / "bad"),
                 "--lm-setting", f"{name}=maybe"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"groundlang train: error: language model parse, setting {name}: expected true or false, not 'maybe'"


def test_evaluate_accepts_a_switch_off_and_records_it(tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["--quiet", "evaluate", "--corpus", str(EXAMPLES), "--palette", "sokoban", "--labels",
                 str(EXAMPLES / "labels.csv"), "--limit", "2", "--json", str(out),
                 "--lm-setting", "start_role=false"]) == 0
    assert json.loads(out.read_text())["language_model_settings"] == {"start_role": False}
    assert main(["--quiet", "evaluate", "--corpus", str(EXAMPLES), "--palette", "sokoban", "--labels",
                 str(EXAMPLES / "labels.csv"), "--lm-setting", "object_key=0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["groundlang evaluate: error: language model parse, setting object_key: expected true or false, not 0"]


def test_with_every_constraint_each_grounding_is_offered_once_per_constraint_with_its_share(examples):
    state = examples[0].initial_state
    lm = get_language_model("parse", largest_constraint=False)
    assert lm.enumerates_constraints and not get_language_model("parse").enumerates_constraints
    library = Learner("parse").library
    largest = interpretations(state, library, enumerate_constraints=False)
    every = interpretations(state, library, enumerate_constraints=True)
    assert len(every) > len(largest)
    # one per grounding either way; the constraints of a grounding split its prior
    assert {i.task for i in every} == {i.task for i in largest}
    assert math.isclose(sum(math.exp(i.log_prior) for i in every), sum(math.exp(i.log_prior) for i in largest),
                        rel_tol=1e-9)
    every_obs = Learner(language_model=lm).observe(examples[:1])[0].interpretations
    largest_obs = Learner("parse").observe(examples[:1])[0].interpretations
    assert len(every_obs) > len(largest_obs)  # the learner offers what the setting says
    assert {i.task for i in every_obs} == {i.task for i in largest_obs}


def _encoded(examples, command, **settings):
    lm = get_language_model("parse", **settings)
    said = replace(examples[0], command=command)
    learner = Learner(language_model=lm, steps=5).fit([*examples[::3], said])
    return learner, lm.encode(learner.observe([said]), learner.vocab)


def test_a_negated_verb_is_a_frame_word_unless_switched_off(examples):
    for frame in (True, False):
        learner, batch = _encoded(examples, "go to the red room and do not enter the green room",
                                  negated_verbs_frame=frame)
        col = {int(w): u for u, w in enumerate(batch.uniq[0])}
        enter, go = col[learner.vocab.word_id("enter")], col[learner.vocab.word_id("go")]
        verbs, frames = batch.verb_counts[0].sum(0), batch.frame_counts[0].sum(0)
        assert verbs[go] > 0
        if frame:
            assert verbs[enter] == 0 and frames[enter] > 0
        else:
            assert verbs[enter] > 0


def test_without_task_objects_the_mention_model_asks_only_about_toys(examples):
    _, on = _encoded(examples, "go to the red room")
    learner, off = _encoded(examples, "go to the red room", mention_task_objects=False)
    obs = learner.observe([replace(examples[0], command="go to the red room")])[0]
    for j, interp in enumerate(obs.interpretations):
        toys = sum(1 for rb in interp.roles if rb.cls == "toy")
        assert int(off.cover_mask[0, j].sum()) == toys
        rooms_bound = sum(1 for rb in interp.roles if rb.cls == "room" and not rb.role.startswith("other:"))
        assert int(on.cover_mask[0, j].sum()) == toys + rooms_bound


def test_the_grammar_s_rule_weights_are_a_setting_that_weighs_the_readings_training_sees(examples, tmp_path,
                                                                                           capsys):
    """``parser_weights`` overrides DEFAULT_WEIGHTS by rule name: the readings of an ambiguous command
    change their probabilities, in what the learner observes and in a saved model."""
    command = "go to the room with white / cream floor"
    plain = [r.probability for r in parse(command)]
    favoured = [r.probability for r in parse(command, weights={"nmods_coord": 2.0})]
    assert plain != favoured
    lm = get_language_model("parse", parser_weights={"nmods_coord": 2.0})
    learner = Learner(language_model=lm, steps=5).fit(examples[:4])
    state = examples[0].initial_state
    seen = [r.probability for r in learner._command_observation(command, state).readings]
    assert seen == [r.probability for r in parse(command, weights={"nmods_coord": 2.0},
                                                 word_lexicon=learner.word_lexicon)]
    assert seen != [r.probability for r in Learner(steps=5)._command_observation(command, state).readings]
    again = Learner.from_state_dict(learner.state_dict())
    assert again.lm.parser_weights == {"nmods_coord": 2.0}
    assert [r.probability for r in again._command_observation(command, state).readings] == seen
    assert main(["--quiet", "train", str(EXAMPLES), "--palette", "sokoban", "-o", str(tmp_path / "bad"),
                 "--lm-setting", 'parser_weights={"nmods_cord": 2}']) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown grammar rule(s) 'nmods_cord'; the rules are c_adv" in err[0]
