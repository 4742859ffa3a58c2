"""Held-out likelihood of a corpus, and of a switch on and off (``groundlang ablate --held-out-likelihood``)."""

from __future__ import annotations

import json
import math

import pytest
import torch

from groundlang.cli import main
from groundlang.corpus import example_corpus_path, read_corpus
from groundlang.held_out import compare_switches, held_out_likelihood, switch_settings
from groundlang.learner import Learner

EXAMPLES = example_corpus_path()


@pytest.fixture(scope="module")
def examples():
    return read_corpus(EXAMPLES, "sokoban").instances


@pytest.mark.slow
def test_a_fold_is_scored_by_a_model_that_never_saw_it(examples):
    """Fold k holds instances n with n mod folds == k; the model of fold k is trained on the others."""
    result = held_out_likelihood(examples, folds=3)
    joint = words = 0.0
    for k in range(3):
        learner = Learner("parse").fit([x for n, x in enumerate(examples) if n % 3 != k])
        batch = learner.lm.encode(learner.observe([x for n, x in enumerate(examples) if n % 3 == k]), learner.vocab)
        with torch.no_grad():
            said = learner.lm.log_likelihood(learner.globals, batch)
        joint += float(torch.logsumexp(batch.log_prior + batch.behaviour + said, -1).sum())
        words += float(torch.logsumexp(batch.log_prior + said, -1).sum())
    assert (result.folds, result.n) == (3, 24)
    assert result.joint == pytest.approx(joint, abs=1e-3) and result.words == pytest.approx(words, abs=1e-3)
    # a demonstration's likelihood is at most 1: words and demonstrations together are less likely
    assert math.isfinite(result.joint) and result.joint < result.words < 0


@pytest.mark.slow
def test_a_switch_is_compared_with_the_defaults(examples):
    (row,) = compare_switches(examples, ["object_key"], folds=3)
    assert (row.setting, row.default, row.value) == ("object_key", True, False)
    assert row.on.joint == pytest.approx(held_out_likelihood(examples, folds=3).joint)
    assert row.off.joint == pytest.approx(held_out_likelihood(examples, settings={"object_key": False}, folds=3).joint)
    assert row.off.words != pytest.approx(row.on.words)  # the keys of "take the star to ..." changed
    assert row.favours == ("tie" if row.off.demonstrations == row.on.demonstrations else
                           "other" if row.off.demonstrations > row.on.demonstrations else "default")
    assert row.on.demonstrations == pytest.approx(row.on.joint - row.on.words)


@pytest.mark.parametrize("switch, message", [
    ("start_rol", "--switch 'start_rol': language model parse has no setting 'start_rol'"),
    ("argument_bonus", "--switch 'argument_bonus': argument_bonus is not true or false (default 3.0)"),
    ("start_role=3", "language model parse, setting start_role: expected true or false, not 3"),
    ("word_concentration=" + "[" * 3000, "--switch word_concentration=[[[[[[[[[[[[[[[[[[[[...: nested too deeply"),
])
def test_a_wrong_switch_is_refused(switch, message):
    with pytest.raises(ValueError) as caught:
        switch_settings("parse", switch)
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_a_value_switch_and_the_base_settings():
    assert switch_settings("parse", "mention_phrases=any") == ("mention_phrases", "referring", "any")
    assert switch_settings("parse", "start_role", {"start_role": False}) == ("start_role", False, True)


def test_cli_prints_and_writes_the_table(tmp_path, capsys):
    out = tmp_path / "h.json"
    assert main(["--quiet", "ablate", "--held-out-likelihood", "--corpus", str(EXAMPLES), "--palette", "sokoban",
                 "--folds", "3", "--switch", "start_role", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "3-fold held-out log-likelihood (nats), 24 instances, language model parse" in printed
    data = json.loads(out.read_text())
    (row,) = data["rows"]
    assert (data["folds"], row["setting"], row["default"], row["value"]) == (3, "start_role", True, False)
    assert f"{row['default_joint']:.1f}" in printed and f"{row['value_joint']:.1f}" in printed
    assert f"{row['default_demonstrations']:.1f}" in printed and f"{row['value_demonstrations']:.1f}" in printed
    assert printed.splitlines()[-2].endswith(row["favours"])


@pytest.mark.parametrize("extra, message", [
    (["--switch", "start_role", "--labels", "x.csv"], "--held-out-likelihood uses no --labels (they are the grid's)"),
    # read by the grid only: they had been ignored without a word (--libraries discovered showed the authored's)
    (["--switch", "start_role", "--libraries", "discovered", "--workers", "2", "--ray", "local"],
     "--held-out-likelihood uses no --libraries, --workers, --ray (they are the grid's)"),
    ([], "--held-out-likelihood: name at least one --switch"),
    (["--switch", "start_role", "--language-models", "bow,parse"], "name one language model, not bow,parse"),
])
def test_cli_refuses_what_the_held_out_likelihood_does_not_take(extra, message, capsys):
    assert main(["ablate", "--held-out-likelihood", "--corpus", str(EXAMPLES), "--palette", "sokoban", *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]


def test_cli_grid_still_needs_labels_and_takes_no_switch(capsys):
    assert main(["ablate", "--corpus", str(EXAMPLES), "--palette", "sokoban"]) == 2
    assert "--labels is required" in capsys.readouterr().err
    assert main(["ablate", "--corpus", str(EXAMPLES), "--palette", "sokoban", "--labels",
                 str(EXAMPLES / "labels.csv"), "--switch", "start_role"]) == 2
    assert "--switch needs --held-out-likelihood" in capsys.readouterr().err
    assert main(["ablate", "--corpus", str(EXAMPLES), "--palette", "sokoban", "--labels",
                 str(EXAMPLES / "labels.csv"), "--folds", "3"]) == 2
    assert "--folds is --held-out-likelihood's" in capsys.readouterr().err


def test_a_switch_to_its_default_is_refused_and_a_repeated_one_compared_once(capsys):
    """--switch object_key=true compared the default with itself ("favours default"); a switch named twice
    printed its row twice."""
    from groundlang.cli import main
    from groundlang.held_out import switch_settings

    with pytest.raises(ValueError, match=r"--switch 'object_key=true': True is object_key's default here"):
        switch_settings("parse", "object_key=true")
    assert switch_settings("parse", "object_key") == ("object_key", True, False)
    E = str(example_corpus_path())
    assert main(["ablate", "--held-out-likelihood", "--corpus", E, "--palette", "sokoban", "--switch", "object_key",
                 "--switch", "object_key", "--folds", "2"]) == 0
    assert sum(line.startswith("object_key ") for line in capsys.readouterr().out.splitlines()) == 1


def test_a_setting_that_acts_only_when_following_is_refused_and_trains_as_the_default(examples):
    """Such a switch had been trained twice and reported as a tie ("no effect on held-out data")."""
    from groundlang.model.language_model_base import FOLLOWING_SETTINGS
    from groundlang.model.language_models import get_language_model

    defaults = get_language_model("parse").settings()
    other = {name: not value if isinstance(value, bool) else {"step_cost": 0.5, "habit_prior": "overall"}[name]
             for name, value in defaults.items() if name in FOLLOWING_SETTINGS}
    assert all(other[name] != defaults[name] for name in FOLLOWING_SETTINGS)  # each compared with another value
    for name in FOLLOWING_SETTINGS:
        with pytest.raises(ValueError, match=rf"^--switch '{name}[^']*': {name} acts only when following"):
            switch_settings("parse", f"{name}=" + json.dumps(other[name]))
    # the list is right: a model trained with each of them changed has the default's parameters
    default = Learner("parse", steps=5).fit(examples[::3]).globals
    for name in FOLLOWING_SETTINGS:
        changed = get_language_model("parse", **{name: other[name]})
        trained = Learner(changed, steps=5).fit(examples[::3]).globals
        assert set(trained) == set(default) and all(torch.equal(trained[k], default[k]) for k in default), name
