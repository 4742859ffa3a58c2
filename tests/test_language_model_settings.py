"""Language model settings from the API and the CLI (``--lm-setting KEY=VALUE``), for ablations."""

from __future__ import annotations

import json

import pytest

from groundlang.cli import main
from groundlang.commands import language_model_settings
from groundlang.corpus import example_corpus_path
from groundlang.learner import Learner
from groundlang.model.language_models import ParseAligned, get_language_model

EXAMPLES = example_corpus_path()


def test_settings_make_the_model_they_name():
    lm = get_language_model("parse", mention_phrases="any", argument_bonus=0, mention_concentration=None)
    assert isinstance(lm, ParseAligned)
    assert (lm.mention_phrases, lm.argument_bonus, lm.mention_concentration) == ("any", 0, None)
    assert get_language_model("bow", null_token=False).settings() == {"word_concentration": 1.05, "null_token": False,
                                                                        "schema_names": False, "achievable_goals": True,
                                                                        "expected_success": True, "step_cost": 0.005,
                                                                        "end_habits": True, "moved_toys": False,
                                                                        "habits_made_true": False, "bound_habits": True,
                                                                        "habit_prior": "absent", "success_confidence": True,
                                                                        "held_goals_confidence": False,
                                                                        "other_starts": True}


@pytest.mark.parametrize("name, settings, message", [
    ("parse", {"foo": 1}, "language model parse has no setting 'foo'; its settings: word_concentration, "),
    ("bow", {"mention_phrases": "any"}, "language model bow has no setting 'mention_phrases'"),
    ("parse", {"argument_bonus": "x"}, "language model parse, setting argument_bonus: expected a number, not 'x'"),
    ("parse", {"argument_bonus": None}, "setting argument_bonus: None is not allowed here"),
    ("parse", {"align_by_task": 1}, "setting align_by_task: expected true or false, not 1"),
    ("parse", {"mention_phrases": 3}, "setting mention_phrases: expected a string, not 3"),
    ("parse", {"mention_phrases": "all"}, "language model parse: mention_phrases must be 'referring' or 'any', "
                                          "not 'all'"),
    ("parse", {"habit_prior": "none"}, "language model parse: habit_prior must be one of absent, overall, not 'none'"),
    ("bow", {"habit_prior": 1}, "setting habit_prior: expected a string, not 1"),
    ("parse", {"word_concentration": -1}, "language model parse: word_concentration must be > 0 (a Dirichlet "
                                          "concentration), at most 1e+30 and at least 1e-30, not -1"),
    # Values the model's float32 tensors would round to 0 or to infinity (a torch error deep in training).
    ("parse", {"word_concentration": 1e-300}, "word_concentration must be > 0 (a Dirichlet concentration), at "
                                              "most 1e+30 and at least 1e-30, not 1e-300"),
    ("parse", {"mention_concentration": 1e38}, "mention_concentration must be > 0"),
    ("parse", {"argument_bonus": 1e308}, "argument_bonus must be >= 0 (added to a Dirichlet concentration), at "
                                         "most 1e+30, not 1e+308"),
    ("bow", {"word_concentration": 0}, "language model bow: word_concentration must be > 0"),
    ("parse", {"align_concentration": float("nan")}, "setting align_concentration: expected a number, not nan"),
    ("parse", {"argument_bonus": -0.5}, "language model parse: argument_bonus must be >= 0 (added to a Dirichlet concentration), "
                                           "at most 1e+30, not -0.5"),
    ("lstm", {}, "unknown language model 'lstm'; expected one of bow, ibm2, parse"),
])
def test_a_bad_setting_is_refused_with_the_model_and_the_setting_named(name, settings, message):
    with pytest.raises(ValueError) as caught:
        get_language_model(name, **settings)
    assert message in str(caught.value)


def test_cli_values_are_read_as_json_else_as_text():
    assert language_model_settings(["argument_bonus=0", "mention_phrases=any", "mention_concentration=null",
                                    "align_by_task=false", "word_concentration= 1.2"]) == {
        "argument_bonus": 0, "mention_phrases": "any", "mention_concentration": None, "align_by_task": False,
        "word_concentration": 1.2}
    with pytest.raises(ValueError, match="--lm-setting 'mention_phrases': expected KEY=VALUE"):
        language_model_settings(["mention_phrases"])


def test_cli_evaluate_runs_and_records_the_settings(tmp_path, capsys):
    out = tmp_path / "r.json"
    code = main(["--quiet", "evaluate", "--corpus", str(EXAMPLES), "--palette", "sokoban",
                 "--labels", str(EXAMPLES / "labels.csv"), "--limit", "3", "--json", str(out),
                 "--lm-setting", "mention_phrases=any", "--lm-setting", "argument_bonus=0"])
    assert code == 0
    assert "language model parse, mention_phrases='any', argument_bonus=0" in capsys.readouterr().out
    data = json.loads(out.read_text())
    assert data["language_model_settings"] == {"mention_phrases": "any", "argument_bonus": 0}
    assert data["n"] == 3


def test_cli_train_saves_the_settings_with_the_model(tmp_path, capsys):
    model = tmp_path / "model"
    assert main(["--quiet", "train", str(EXAMPLES), "--palette", "sokoban", "-o", str(model),
                 "--lm-setting", "mention_phrases=any"]) == 0
    assert Learner.load(model).lm.mention_phrases == "any"
    assert main(["--quiet", "train", str(EXAMPLES), "--palette", "sokoban", "-o", str(tmp_path / "bad"),
                 "--lm-setting", "mention_phrase=any"]) == 2
    err = capsys.readouterr().err
    assert "language model parse has no setting 'mention_phrase'" in err and not (tmp_path / "bad").exists()


def test_an_ablation_applies_each_setting_to_the_models_that_take_it():
    from groundlang.ablation import AblationResult, run_ablation
    from groundlang.corpus import read_corpus
    from groundlang.labels import read_labels

    corpus = read_corpus(EXAMPLES, "sokoban")
    labels = read_labels(EXAMPLES / "labels.csv")
    result = run_ablation(corpus, labels, language_models=("bow", "parse"), libraries=("authored",), limit=2,
                          language_model_settings={"mention_phrases": "any", "word_concentration": 1.1})
    assert [(r.language_model, r.n, r.error) for r in result.rows] == [("bow", 2, None), ("parse", 2, None)]
    assert result.language_model_settings == {"bow": {"word_concentration": 1.1},
                                              "parse": {"mention_phrases": "any", "word_concentration": 1.1}}
    assert AblationResult.from_json(result.to_json()).language_model_settings == result.language_model_settings
    with pytest.raises(ValueError, match=r"no language model of the grid \(bow, ibm2\) has the setting 'mention_phrases'"):
        run_ablation(corpus, labels, language_models=("bow", "ibm2"), language_model_settings={"mention_phrases": "any"})
    with pytest.raises(ValueError, match="language model parse, setting argument_bonus: expected a number"):
        run_ablation(corpus, labels, language_models=("parse",), language_model_settings={"argument_bonus": "x"})


@pytest.mark.parametrize("name", ["parse", "bow", "ibm2"])
def test_a_whole_number_for_a_real_setting_is_that_real(name):
    """``--lm-setting word_concentration=2`` reads as JSON's 2, an int: it made an integer tensor, which the
    Dirichlet refused in a traceback."""
    settings = language_model_settings(["word_concentration=2"])
    assert settings == {"word_concentration": 2} and type(settings["word_concentration"]) is int
    lm = get_language_model(name, **settings)
    assert lm.word_concentration == 2.0 and type(lm.word_concentration) is float
    if name == "parse":
        lm = get_language_model(name, mention_concentration=1, preposition_concentration=2, argument_bonus=3)
        assert type(lm.mention_concentration) is float and type(lm.preposition_concentration) is float


def test_a_whole_number_for_a_real_setting_trains(tmp_path):
    assert main(["--quiet", "train", str(EXAMPLES), "--palette", "sokoban", "-o", str(tmp_path / "m"),
                 "--lm-setting", "word_concentration=2", "--lm-setting", "mention_concentration=1"]) == 0


@pytest.mark.parametrize("text", ["word_concentration=1" + "0" * 400,
                                  'parser_weights={"nmods_coord": 1' + "0" * 400 + "}"])
def test_a_number_beyond_a_floats_range_is_one_line(text, capsys):
    assert main(["train", str(EXAMPLES), "--palette", "sokoban", "-o", "/tmp/never-written", "--lm-setting", text]) == 2
    err = capsys.readouterr().err
    assert "a number of 401 digits; no setting takes one beyond a float's range" in err and len(err.splitlines()) == 1
    with pytest.raises(ValueError, match="within a float's range, not one of 401 digits"):
        get_language_model("parse", argument_bonus=10**400)  # from Python, not JSON

