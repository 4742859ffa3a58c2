"""The held question, from the API and the CLI: words that most probably ask for what already holds are asked
about (yes: nothing to do; no: the rest of the reading), and words that say only what not to do ask what to do
(groundlang.held_question)."""

from __future__ import annotations

import io
import json
import re

import pytest

from groundlang.cli import main
from groundlang.corpus import example_corpus_path, read_state_file
from groundlang.learner import Learner
from groundlang.model.language_models import get_language_model

EXAMPLES = example_corpus_path()


def test_follow_says_when_the_words_ask_for_what_already_holds(tmp_path, capsys, monkeypatch):
    """"go to the red room" said in it: following sets the goal aside (it asks nothing), and without a word
    the interpretations would leave out the room named; follow says it is already true."""
    model = tmp_path / "m"
    assert main(["--quiet", "train", str(EXAMPLES), "--palette", "sokoban", "-o", str(model)]) == 0
    layout = (EXAMPLES / "novel_a.state").read_text().split(" agent,")[0]
    inside, outside = tmp_path / "inside.state", tmp_path / "outside.state"
    inside.write_text(layout + " agent,3,3\n")  # in the red room, room2
    outside.write_text(layout + " agent,3,8\n")  # in the blue room, room0
    capsys.readouterr()
    follow = ["--quiet", "follow", "go to the red room", "--model", str(model), "--palette", "sokoban", "--env"]
    assert main([*follow, str(inside), "--json"]) == 3
    answer = json.loads(capsys.readouterr().out)
    done = answer["already_true"]
    assert done["goal"] == "agentInRoom(agent0, room2)" and done["probability"] > 0.9
    # as sure as acting needs, it is asked, never taken: the reading of goals that hold is read from words
    # trained on none ("leave the red room" said in it reads as it too)
    assert answer["abstained"] and answer["question"].startswith("Do you mean the agent in the red room, as it is now?")
    assert [c["goal"] for c in answer["choices"]] == [done["goal"]] and "actions" not in answer
    assert answer["question_kind"] == "already true" and answer["unknown_words"] == []
    assert main([*follow, str(inside)]) == 3
    captured = capsys.readouterr()
    assert re.search(r"^already true here: the agent in the red room .*agentInRoom\(agent0, room2\); the words "
                     r"most probably ask for it \(0\.9\d of their reading .*\)\nDo you mean the agent in the red room, "
                     r"as it is now\? \(yes: nothing to do; no: the rest of the reading\)\n  1\) the agent in the red room",
                     captured.out, re.M)
    assert "interpretations:" not in captured.out and "(yes: nothing to do; no: the rest of their reading)" in captured.err
    # a yes: nothing to do; a no: the rest of the reading, here asked about in turn and answered
    monkeypatch.setattr("sys.stdin", io.StringIO("yes\n"))
    before = (model / "model.json").read_bytes()
    assert main([*follow, str(inside), "--ask", "--learn"]) == 0
    assert capsys.readouterr().out.endswith(f"nothing to do: plan (0 steps): (none)\nnothing learned: the model at "
                                            f"{model} is left as it was\n")
    assert (model / "model.json").read_bytes() == before
    monkeypatch.setattr("sys.stdin", io.StringIO("no\nthe blue one\n"))
    assert main([*follow, str(inside), "--ask"]) == 0
    assert "goal the agent in the blue room \u2014 agentInRoom(agent0, room0): reached" in capsys.readouterr().out
    # a no that names what is meant answers the rest's question too (it had been refused as naming nothing)
    monkeypatch.setattr("sys.stdin", io.StringIO("no, the blue one\n"))
    assert main([*follow, str(inside), "--ask"]) == 0
    assert "goal the agent in the blue room \u2014 agentInRoom(agent0, room0): reached" in capsys.readouterr().out
    # with --guess, or less sure than --min-confidence asks: said, and the rest of the reading is weighed
    for options in (["--guess"], ["--min-confidence", "0.9999"], ["--min-confidence", "0"]):  # 0 asks nothing
        main([*follow, str(inside), *options])
        assert re.search(r"\), but such a goal asks nothing: the interpretations below are the rest\ninterpretations:",
                         capsys.readouterr().out)
    # where it is not true yet, nothing is said
    assert main([*follow, str(outside), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["already_true"] is None
    # nor of a negated command, read without its negation (negation is no task): it asks for no such thing;
    # it asks what should be done instead ("do not go to the blue room" had walked into the blue room at 0.99)
    negated = ["--quiet", "follow", "do not go to the blue room", "--model", str(model), "--palette", "sokoban",
               "--env", str(inside)]
    assert main([*negated, "--json"]) == 3
    answer = json.loads(capsys.readouterr().out)
    assert answer["already_true"] is None and answer["abstained"] and answer["question_kind"] == "what to do"
    assert answer["choices"] == [] and "actions" not in answer
    assert main(negated) == 3
    out, err = capsys.readouterr()
    assert "The words say only what not to do" in out and "plan (" not in out and "read as what the negation" in out
    assert "not acting: the words say only what not to do" in err and "act on that reading with --guess" in err
    monkeypatch.setattr("sys.stdin", io.StringIO("the red one\n"))
    assert main([*negated, "--ask"]) == 3  # nothing to choose among: not asked on the terminal
    assert "answer> " not in capsys.readouterr().out
    assert main([*negated, "--guess"]) == 0  # acting however unsure: on what the words were read as
    assert "plan (" in capsys.readouterr().out


def test_learner_follow_asks_whether_what_already_holds_is_meant(learner, tmp_path):
    """The API asks as the CLI does: with ``min_confidence``, words that most probably ask for what already
    holds give a result asking whether it is meant; clarify takes a yes (nothing to do) or a no (the rest)."""
    from groundlang.clarify import AnswerError
    from groundlang.logic.atoms import Atom

    layout = (EXAMPLES / "novel_a.state").read_text().split(" agent,")[0]
    (tmp_path / "inside.state").write_text(layout + " agent,3,3\n")  # in the red room, room2
    inside = read_state_file(tmp_path / "inside.state", "sokoban")
    red = (Atom("agentInRoom", ("agent0", "room2")),)
    asked = learner.follow("go to the red room", inside, min_confidence=0.7)
    assert asked.already_true and asked.abstained and asked.actions == [] and asked.goal == red
    assert asked.question.startswith("Do you mean the agent in the red room, as it is now?")
    assert [c.goal for c in asked.choices] == [red] and asked.confidence > 0.9
    rest = learner.follow("go to the red room", inside)  # acting however unsure: the rest, as before
    assert not rest.already_true and rest.goal != red and rest.actions
    assert asked.otherwise.goal == rest.goal and not asked.otherwise.already_true
    yes = learner.clarify(asked, "yes")
    assert (yes.goal, yes.actions, yes.reached, yes.reason, yes.final_state) == (red, [], True, "goal", inside)
    assert learner.clarify(asked, "no") is asked.otherwise
    assert asked.otherwise.abstained  # "no, the blue room": the rest's question answered by the words after the no
    blue = learner.clarify(asked, "no, the blue room")
    assert blue.goal == (Atom("agentInRoom", ("agent0", "room0")),) and blue.reached
    assert learner.clarify(asked, 1).actions == []
    with pytest.raises(AnswerError):
        learner.clarify(asked, "the star")
    # not asked where the words do not ask for it as surely, nor where it does not hold
    unsure = learner.follow("go to the red room", inside, min_confidence=0.9999)
    assert not unsure.already_true and unsure.held_reading[0] == red  # said (follow's line), not asked
    assert asked.held_reading == (red, asked.choices[0].probability)
    (tmp_path / "outside.state").write_text(layout + " agent,3,8\n")
    outside = read_state_file(tmp_path / "outside.state", "sokoban")
    assert not learner.follow("go to the red room", outside, min_confidence=0.7).already_true


def test_a_no_that_names_what_is_meant_answers_a_held_question_whose_rest_acts(learner, tmp_path):
    """Two rooms, the agent in the blue one: "go to the blue room" asks whether it is meant, and the rest (the
    green room) is sure enough to act on. "no, the green room" had been refused as not naming the held choice,
    though a bare no acted on the green room."""
    from groundlang.clarify import AnswerError
    from groundlang.logic.atoms import Atom

    (tmp_path / "two.state").write_text("room,1,0,4,4,0 room,5,4,4,8,0 door,4,2,4,2 block,12,0,2,2 agent,1,1\n")
    state = read_state_file(tmp_path / "two.state", "sokoban")
    asked = learner.follow("go to the blue room", state, min_confidence=0.7)
    assert asked.already_true and not asked.otherwise.abstained
    green = (Atom("agentInRoom", ("agent0", "room1")),)
    assert asked.otherwise.goal == green
    named = learner.clarify(asked, "no, the green room")
    assert named.goal == green and named.reached and named.actions
    assert learner.clarify(asked, "no") is asked.otherwise
    # said of the question asked, not of a list never shown ("answer 1 or yes" would have taken the held choice)
    with pytest.raises(AnswerError, match=r"^'the red room' names nothing else the words could mean here \(the agent in "
                                          r"the green room\): answer no alone to act on the agent in the green room"):
        learner.clarify(asked, "no, the red room")
    for numbered in ("no, 2", "no, option two"):
        with pytest.raises(AnswerError, match="^after a no, say in words what is meant"):
            learner.clarify(asked, numbered)


def test_learner_follow_asks_what_to_do_where_the_words_say_only_what_not_to_do(learner, tmp_path):
    """Negation is no task: "do not go to the blue room" is read as the blue room. With min_confidence the
    learner asks for a command that says what to do (no choice to take), rather than act on it."""
    from groundlang.clarify import NOT_TO_DO_QUESTION, AnswerError, says_only_what_not_to_do
    from groundlang.grammar.parser import parse

    layout = (EXAMPLES / "novel_a.state").read_text().split(" agent,")[0]
    (tmp_path / "red.state").write_text(layout + " agent,3,3\n")
    state = read_state_file(tmp_path / "red.state", "sokoban")
    for said in ("do not go to the blue room", "never enter the blue room", "ok, don't go into the blue room"):
        asked = learner.follow(said, state, min_confidence=0.7)
        assert asked.abstained and asked.question == NOT_TO_DO_QUESTION and asked.choices == [] and not asked.actions
        with pytest.raises(AnswerError):
            learner.clarify(asked, "the green room")
        assert learner.follow(said, state).actions  # acting however unsure: on the reading, as before
    assert not says_only_what_not_to_do(parse("push the star without entering the blue room"))
    assert not says_only_what_not_to_do(parse("go to the green room, do not go to the blue room"))
    assert not says_only_what_not_to_do(parse("move to the pink room no matter the location"))  # a fallback's chunk


def test_the_words_reading_of_what_holds_conditions_on_nothing(learner, tmp_path):
    """``posterior(held=True)``: what the words say, goals that hold at the start offered; a room the agent
    cannot reach keeps its share (conditioning on what can be done would hand it to the room it is in)."""
    from groundlang.logic.atoms import Atom

    def read_state_text(line: str, palette: str):
        (tmp_path / "s.state").write_text(line + "\n")
        return read_state_file(tmp_path / "s.state", palette)

    layout = (EXAMPLES / "novel_a.state").read_text().split(" agent,")[0]
    inside = read_state_text(layout + " agent,3,3", "sokoban")  # in the red room
    held = learner.posterior("go to the red room", inside, held=True)
    assert held.best_goal == (Atom("agentInRoom", ("agent0", "room2")),) and held.confidence > 0.9
    assert learner.posterior("go to the red room", inside).best_goal != held.best_goal  # set aside when following
    walled = read_state_text(layout.replace("door,3,5,3,5 ", "").replace("door,9,5,9,5 ", "") + " agent,3,8",
                             "sokoban")  # in the blue room, no door to the red room: out of reach
    assert learner.posterior("go to the red room", walled).out_of_reach > 0.9
    said = learner.posterior("go to the red room", walled, held=True)
    assert said.best_goal == (Atom("agentInRoom", ("agent0", "room2")),) and said.out_of_reach == 0.0
    with pytest.raises(TypeError, match="held must be True or False, not str"):
        learner.posterior("go to the red room", inside, held="yes")


def test_the_words_share_on_what_already_holds_counts_against_following(learner, corpus, tmp_path):
    """``held_goals_confidence`` (off by default): "go to the red room" said in it is 0.98 the room the agent is
    in, a goal following sets aside; walking to another room is then not a confident reading of the words."""
    from groundlang.confidence import held_goals_success

    layout = (EXAMPLES / "novel_a.state").read_text().split(" agent,")[0]
    (tmp_path / "inside.state").write_text(layout + " agent,3,3\n")  # in the red room
    inside = read_state_file(tmp_path / "inside.state", "sokoban")
    counting = Learner(get_language_model("parse", held_goals_confidence=True)).fit(corpus.instances)
    result = counting.follow("go to the red room", inside, min_confidence=0.7)
    held = counting.posterior("go to the red room", inside, held=True)
    # asked whether the red room, as it is, is meant; the rest of the reading, walking elsewhere, is not sure
    assert held.confidence > 0.9 and result.already_true and result.abstained
    assert result.otherwise.abstained and result.otherwise.confidence < 0.1
    # the share on the held goal counts only where following leaves it: an end still in the red room keeps it
    assert held_goals_success(held, 0.5, inside, learner.library) == pytest.approx(
        (1 - held.confidence) * 0.5 + held.confidence, abs=1e-6)
    # off (the default), the confidence is where the end stands among the rest
    assert learner.follow("go to the red room", inside).confidence > 0.45
