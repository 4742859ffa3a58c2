"""Evaluation protocols: intervals, goal translation, leave-one-out, novel layouts, the CLI."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from groundlang.cli import main
from groundlang.corpus import example_corpus_path, read_corpus, read_state_file
from groundlang.evaluation import NovelEnvironmentError, describe_goal, evaluate, translate_goal, wilson_interval
from groundlang.labels import read_labels
from groundlang.published import REFERENCES
from groundlang.logic.atoms import parse_goal
from groundlang.model.world import Agent

EXAMPLES = example_corpus_path()
NOVEL = EXAMPLES.parent.parent / "tests" / "fixtures" / "novel_envs"


def test_wilson_interval_matches_reference_values():
    low, high = wilson_interval(211, 240)
    assert low == pytest.approx(0.8318, abs=1e-4) and high == pytest.approx(0.9145, abs=1e-4)
    assert wilson_interval(0, 0) == (0.0, 1.0)
    assert wilson_interval(10, 10)[1] == 1.0


def test_arguments_of_another_type_are_named(corpus):
    """Each had failed deep inside: AttributeError ('list' object has no attribute 'instances', 'NoneType'
    object has no attribute 'get') or "cannot unpack non-iterable State object"."""
    labels = read_labels(EXAMPLES / "labels.csv")
    state = read_state_file(EXAMPLES / "novel_a.state", "sokoban")
    for call, message in (
            (lambda: evaluate(corpus.instances, labels), r"^evaluate: corpus must be a Corpus \(read_corpus\), got list$"),
            (lambda: evaluate(corpus, None), r"^evaluate: labels must map file prefixes to goals \(read_labels\), got NoneType$"),
            (lambda: evaluate(corpus, labels, novel_states=[state]),
             r"^evaluate: novel_states must be \(name, State\) pairs, .* got an item that is a State$"),
            (lambda: evaluate(corpus, labels, novel_states=state), r"^evaluate: novel_states must be .* got State$")):
        with pytest.raises(TypeError, match=message):
            call()


def test_goal_is_carried_over_by_colour(corpus):
    source = corpus.instances[0].initial_state
    target = read_state_file(EXAMPLES / "novel_a.state", "sokoban")
    red_source = next(f"room{i}" for i, r in enumerate(source.layout.rooms) if r.colour == "red")
    red_target = next(f"room{i}" for i, r in enumerate(target.layout.rooms) if r.colour == "red")
    goal = parse_goal(f"toyInRoom(block0, {red_source})")
    assert translate_goal(goal, source, target) == parse_goal(f"toyInRoom(block0, {red_target})")
    assert describe_goal(goal, source) == "toyInRoom(star, red)"


def test_ambiguous_or_already_true_novel_layouts_are_refused(corpus):
    source = corpus.instances[0].initial_state
    target = read_state_file(EXAMPLES / "novel_a.state", "sokoban")
    twin = replace(target.layout, rooms=tuple(replace(r, colour="red") for r in target.layout.rooms))
    with pytest.raises(NovelEnvironmentError, match="3 counterparts"):
        translate_goal(parse_goal("agentInRoom(agent0, room1)"), source, replace(target, layout=twin))
    inside = next(r for r in target.layout.rooms if r.colour == "green")
    started = replace(target, agent=Agent(inside.left + 1, inside.bottom + 1))
    green = next(f"room{i}" for i, r in enumerate(source.layout.rooms) if r.colour == "green")
    with pytest.raises(NovelEnvironmentError, match="already holds at the start"):
        translate_goal(parse_goal(f"agentInRoom(agent0, {green})"), source, started)


@pytest.mark.slow
def test_leave_one_out_on_the_example_corpus(corpus):
    labels = read_labels(EXAMPLES / "labels.csv")
    novel = [(p.name, read_state_file(p, "sokoban")) for p in sorted(NOVEL.glob("*.state"))]
    result = evaluate(corpus, labels, protocol="loo", novel_states=novel)
    assert result.n == 24 and not result.failed_folds
    # Measured: 24/24 held out, 72/72 in the three novel layouts.
    assert result.correct == 24
    assert result.novel_n == 72 and result.novel_correct == 72
    assert sum(row["n"] for row in result.per_task.values()) == 24
    assert sum(sum(row.values()) for row in result.confusion.values()) == 24


def test_cold_folds_fit_every_fold_from_scratch(corpus):
    result = evaluate(corpus, read_labels(EXAMPLES / "labels.csv"), protocol="loo", warm_start=False, limit=6)
    assert result.n == 6 and result.correct == 6 and not result.failed_folds  # measured: 24/24 on all folds


def test_train_protocol_on_the_example_corpus_is_perfect(corpus):
    result = evaluate(corpus, read_labels(EXAMPLES / "labels.csv"), protocol="train")
    assert result.correct == 24


def test_cli_evaluate_writes_the_documented_json(tmp_path, capsys):
    out = tmp_path / "r.json"
    code = main(["--quiet", "evaluate", "--corpus", str(EXAMPLES), "--palette", "sokoban",
                 "--labels", str(EXAMPLES / "labels.csv"), "--protocol", "train", "--novel-envs", str(NOVEL),
                 "--workers", "2", "--json", str(out)])
    assert code == 0
    data = json.loads(out.read_text())
    assert {"accuracy", "n", "correct", "ci_low", "ci_high", "seconds", "per_task",
            "novel_accuracy", "novel_n", "skipped"} <= set(data)
    assert data["n"] == 24 and data["novel_n"] == 72
    assert "accuracy 100.00%" in capsys.readouterr().out


def test_a_novel_layout_a_label_cannot_be_carried_to_is_named_by_its_path(tmp_path, capsys):
    """The error had named the layout's file name alone (and the instance's), not where either is."""
    layouts = tmp_path / "layouts"
    layouts.mkdir()
    (layouts / "grey.state").write_text("room,0,0,10,6,5 room,0,6,10,12,5 room,0,0,5,12,0 door,6,8,6,8 door,3,5,3,5 "
                                        "door,9,5,9,5 block,12,0,6,8 agent,9,5\n", encoding="utf-8")
    assert main(["--quiet", "evaluate", "--corpus", str(EXAMPLES), "--palette", "sokoban",
                 "--labels", str(EXAMPLES / "labels.csv"), "--novel-envs", str(layouts)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"groundlang evaluate: error: {layouts / 'grey.state'} (the label of 'agent2blue_', "
                          f"{EXAMPLES / 'agent2blue_0.txt'}): the goal's room2 (room blue) has 0 counterparts")


@pytest.mark.slow
@pytest.mark.parametrize(
    "folder, measured, measured_novel",
    [("allTurkTrainLimitedCommand", 230, 663), ("allTurkTrain", 228, 652)],
)
def test_leave_one_out_beats_the_published_ibm_model_2(shared_corpus, folder, measured, measured_novel):
    corpus = read_corpus(shared_corpus / folder, "sokoban")
    novel = [(p.name, read_state_file(p, "sokoban")) for p in sorted(NOVEL.glob("*.state"))]
    result = evaluate(corpus, read_labels(shared_corpus / "labels.csv"), protocol="loo", workers=2,
                      novel_states=novel)
    assert result.n == 240 and not result.failed_folds and result.novel_n == 720
    published = {ref.setting: dict(ref.published)["IBM Model 2"] for ref in REFERENCES[folder]}
    assert result.accuracy > published["loo"]
    # The published novel-environment row is the original commands'; the simplified ones must beat it too.
    novel_ibm2 = dict(REFERENCES["allTurkTrain"][1].published)["IBM Model 2"]  # 73.33%, the best published
    assert REFERENCES["allTurkTrain"][1].setting == "novel environments"
    assert result.novel_accuracy > novel_ibm2
    # Measured with this code; a few folds' EM stops may differ (3 novel executions per command).
    assert result.correct >= measured - 3
    assert result.novel_correct >= measured_novel - 9


def test_cli_evaluate_trains_and_scores_with_the_users_library(tmp_path, capsys, fixtures):
    """--library on a *.txt corpus is the learner's library, and labels may name its PFs (it was ignored:
    the package's tasks were learned and a label of the user's PF refused as unknown)."""
    from importlib.resources import files

    csv = tmp_path / "labels.csv"
    csv.write_text('prefix,goal\nagent2red_,"agentInRoom(agent0, room1)"\n'
                   'star2green_,"agentNextToToy(agent0, block0)"\n', encoding="utf-8")
    out = tmp_path / "r.json"
    code = main(["--quiet", "evaluate", "--corpus", str(fixtures / "sokoban"), "--palette", "sokoban",
                 "--labels", str(csv), "--protocol", "train", "--json", str(out),
                 "--library", str(files("groundlang.logic") / "tasks.lp"), "--library", str(EXAMPLES / "next_to.lp")])
    assert code == 0, capsys.readouterr().err
    data = json.loads(out.read_text())
    assert data["n"] == data["correct"] == 4 and set(data["per_task"]) == {"agentInRoom(agent, red)", "agentNextToToy(agent, star)"}


def test_a_novel_layout_where_a_labels_goal_already_holds_leaves_those_executions_unscored(corpus):
    """The agent starts in the green room of ``in_green.state``: the four agent-to-green commands have
    nothing to ask there and are counted apart; every other command is scored in it."""
    labels = read_labels(EXAMPLES / "labels.csv")
    where = Path(__file__).parent / "fixtures" / "novel_goal_holds" / "in_green.state"
    result = evaluate(corpus, labels, protocol="train", novel_states=[(where.name, read_state_file(where, "sokoban"))])
    unscored = [x for r in result.records for x in r["novel"] if "not_scored" in x]
    assert len(unscored) == result.novel_not_scored == 4
    assert all("agentInRoom(agent0, room1) already holds at the start" in x["not_scored"] for x in unscored)
    assert result.novel_n == 20 and "novel executions not scored (the label's goal already holds at the start): 4" \
        in result.summary()


def test_evaluate_checks_its_limit_threshold_and_protocol_options(capsys):
    """evaluate(limit=-1) had scored all but the last instance, limit=0 all of them, min_confidence=5 was
    reported as a threshold; --cold-folds was taken silently by the train protocol, which has no folds."""
    from groundlang.cli import main
    from groundlang.corpus import example_corpus_path, read_corpus
    from groundlang.evaluation import evaluate
    from groundlang.labels import read_labels

    E = example_corpus_path()
    corpus, labels = read_corpus(E, "sokoban"), read_labels(E / "labels.csv")
    for options, said in (({"limit": 0}, "limit must be a positive integer, got 0"),
                          ({"limit": -1}, "limit must be a positive integer, got -1"),
                          ({"min_confidence": 5}, "min_confidence must be a number from 0 to 1"),
                          ({"min_confidence": float("nan")}, "min_confidence must be a number from 0 to 1")):
        with pytest.raises(ValueError, match=said):
            evaluate(corpus, labels, **options)
    assert main(["evaluate", "--corpus", str(E), "--palette", "sokoban", "--labels", str(E / "labels.csv"),
                 "--protocol", "train", "--cold-folds"]) == 2
    assert "--cold-folds: the train protocol trains one model, with no folds" in capsys.readouterr().err


def test_a_novel_layout_the_model_cannot_read_is_counted_wrong_and_named(corpus, tmp_path):
    """Seventeen more blocks: more objects than the mention model reads. Every fold had failed (accuracy 0/0), the
    layout never named; its executions are now wrong, named, and the other layout is scored."""
    labels = read_labels(EXAMPLES / "labels.csv")
    base = (EXAMPLES / "novel_a.state").read_text().strip()
    crowded = tmp_path / "crowded.state"
    cells = [(x, y) for y in (1, 2, 3) for x in (1, 2, 3, 6, 7, 8)][:17]  # in the red room, clear of its doors
    crowded.write_text(base + "".join(f" block,1,1,{x},{y}" for x, y in cells) + "\n")
    novel = [("novel_a.state", read_state_file(EXAMPLES / "novel_a.state", "sokoban")),
             (str(crowded), read_state_file(crowded, "sokoban"))]
    result = evaluate(corpus, labels, protocol="train", novel_states=novel)
    assert not result.failed_folds and result.n == 24
    assert len(result.novel_unfollowed) == 24 and result.novel_n == 48
    assert all(u.startswith(f"{crowded}: ") and "objects a command could name" in u for u in result.novel_unfollowed)
    assert result.novel_correct == sum(x["correct"] for r in result.records for x in r["novel"]
                                       if x["environment"] == "novel_a.state") >= 20
    assert f"novel executions that could not be followed (counted wrong): 24; first: {crowded}: " in result.summary()
    assert result.novel_calibration["n"] == 24  # what was followed: the others had no confidence to calibrate
