"""Learning from one more example: Learner.update (groundlang.update, inference.incremental) and follow --learn."""

from __future__ import annotations

import io

import pytest
import torch

from groundlang.corpus import example_corpus_path, parse_state, read_corpus, read_state_file
from groundlang.examples.build import shortest_demonstration
from groundlang.inference.incremental import grow_words, word_totals
from groundlang.inference.joint import log_joint
from groundlang.learner import DEFAULT_MIN_CONFIDENCE, Learner
from groundlang.logic.atoms import parse_goal

EXAMPLES = example_corpus_path()
# novel_b with its blue room orange (colour 8): two room colours the example corpus never names.
ORANGE_LAYOUT = ("room,10,0,8,5,0 room,8,5,8,10,0 room,5,10,8,15,0 door,5,3,5,3 door,10,5,10,5 "
                 "block,12,0,5,3 agent,10,5")
BLUE_ROOM = parse_goal("agentInRoom(agent0, room1)")


@pytest.fixture(scope="module")
def corpus():
    return read_corpus(EXAMPLES, "sokoban").instances


@pytest.fixture(scope="module")
def trained(corpus):
    return Learner("parse", cache_dir=False).fit(corpus)


@pytest.fixture
def learner(trained, tmp_path):
    """A fresh copy of the trained model for each test (update changes it in place)."""
    return Learner.load(trained.save(tmp_path / "m"))


@pytest.fixture(scope="module")
def novel_b():
    return read_state_file(EXAMPLES / "novel_b.state", "sokoban")


def _follow(learner, command, state):
    return learner.follow(command, state, min_confidence=DEFAULT_MIN_CONFIDENCE)


def test_training_counts_are_read_back_from_the_unknown_word_column(trained, corpus):
    # The E step on the training data gives each token's expected word count; update reads the
    # same totals off the model alone.
    batch = trained.lm.encode(trained.observe(corpus), trained.vocab)
    phi = trained.globals["phi"].clone().requires_grad_(True)
    log_joint(batch, trained.lm, trained.vocab, {**trained.globals, "phi": phi}).backward()
    expected = (phi * phi.grad).sum(-1).detach().double()  # counts + W (alpha - 1) per token
    assert torch.allclose(word_totals(trained.globals["phi"], trained.lm.word_concentration), expected, rtol=1e-4)


def test_growing_the_vocabulary_keeps_the_old_counts():
    phi = torch.tensor([[0.05, 0.90, 0.05], [1 / 3, 1 / 3, 1 / 3]])  # Z = 1 and 0.15 for alpha 1.05
    totals = word_totals(phi, 1.05)
    assert totals.tolist() == pytest.approx([1.0, 0.15])
    grown, grown_totals = grow_words(phi, totals, 2, 1.05)
    assert grown.shape == (2, 5) and grown_totals.tolist() == pytest.approx([1.1, 0.25])
    assert grown.sum(-1).tolist() == pytest.approx([1.0, 1.0])
    assert torch.allclose(grown[:, :3] * grown_totals[:, None].float(), phi * totals[:, None].float())
    assert grown[0, 3:].tolist() == pytest.approx([0.05 / 1.1] * 2)
    assert word_totals(grown, 1.05).tolist() == pytest.approx(grown_totals.tolist())
    with pytest.raises(ValueError, match="word_concentration above 1"):
        word_totals(phi, 1.0)


def test_update_from_an_answer_learns_a_new_colour_word(learner, novel_b):
    asked = _follow(learner, "go to the purple room", novel_b)
    assert asked.abstained and asked.unknown_words == ("purple",)
    words, shape = len(learner.vocab.words), learner.globals["phi"].shape
    blue = next(c for c in asked.choices if c.goal == BLUE_ROOM)
    assert learner.update("go to the purple room", novel_b, goal=blue) is learner
    assert learner.vocab.words[-1] == "purple" and len(learner.vocab.words) == words + 1
    assert learner.globals["phi"].shape == (shape[0], shape[1] + 1)
    assert learner.lexicon()["purple"][0][0] == "roomIsBlue"
    again = _follow(learner, "go to the purple room", novel_b)
    assert not again.abstained and again.goal == BLUE_ROOM and again.reached
    assert again.confidence == pytest.approx(0.889, abs=0.01)
    star = _follow(learner, "take the star to the purple room", novel_b)
    assert star.goal == parse_goal("toyInRoom(block0, room1)") and star.reached
    # what it knew stays known
    assert _follow(learner, "go to the red room", novel_b).goal == parse_goal("agentInRoom(agent0, room0)")
    assert _follow(learner, "take the star to the green room", novel_b).confidence > 0.95


def test_update_from_a_demonstration(learner, novel_b):
    actions = shortest_demonstration(novel_b, BLUE_ROOM)
    learner.update("go to the purple room", novel_b, demonstration=[a.word for a in actions])
    result = _follow(learner, "take the star to the purple room", novel_b)
    assert result.goal == parse_goal("toyInRoom(block0, room1)") and result.confidence > 0.85


def test_update_works_for_ibm_model_2_too(corpus, novel_b):
    learner = Learner("ibm2", cache_dir=False).fit(corpus)
    assert _follow(learner, "take the star to the purple room", novel_b).abstained
    learner.update("go to the purple room", novel_b, goal="agentInRoom(agent0, room1)")
    result = _follow(learner, "take the star to the purple room", novel_b)
    assert result.goal == parse_goal("toyInRoom(block0, room1)") and result.confidence == pytest.approx(0.898, abs=0.01)


def test_the_papers_scenario_a_model_without_green_learns_it_from_one_demonstration(corpus):
    """Model 1's first scenario (MacGlashan et al. 2012): every word known but "green"; one command
    with its demonstration teaches it, and new commands then use it."""
    learner = Learner("parse", cache_dir=False).fit([i for i in corpus if "green" not in i.command])
    assert "green" not in learner.vocab.words
    layout = parse_state(ORANGE_LAYOUT, "sokoban")
    before = _follow(learner, "take the star to the green room", layout)
    # green and orange rooms are both rooms no word was learned for: a coin flip, so it asks
    assert before.abstained and before.confidence == pytest.approx(0.475, abs=0.01) and {c.goal for c in before.choices} >= {
        parse_goal("toyInRoom(block0, room1)"), parse_goal("toyInRoom(block0, room2)")}
    shown = next(i for i in corpus if i.command == "go to the green room")
    learner.update(shown.command, shown.initial_state, demonstration=shown.actions)
    assert learner.lexicon()["green"][0][0] == "roomIsGreen"
    after = _follow(learner, "take the star to the green room", layout)
    assert not after.abstained and after.goal == parse_goal("toyInRoom(block0, room2)") and after.reached
    assert after.confidence == pytest.approx(0.891, abs=0.01)
    assert _follow(learner, "go into the green room", layout).goal == parse_goal("agentInRoom(agent0, room2)")
    assert _follow(learner, "take the star to the red room", layout).goal == parse_goal("toyInRoom(block0, room0)")


def test_bad_updates_are_refused_and_leave_the_model_as_it_was(learner, novel_b):
    words, phi = list(learner.vocab.words), learner.globals["phi"].clone()
    with pytest.raises(ValueError, match="give a demonstration or the goal"):
        learner.update("go to the purple room", novel_b)
    with pytest.raises(ValueError, match="no task of the library has goal agentInRoom\\(agent0, room7\\)"):
        learner.update("go to the purple room", novel_b, goal="agentInRoom(agent0, room7)")
    with pytest.raises(ValueError, match="unknown action 'up'"):
        learner.update("go to the purple room", novel_b, demonstration=["north", "up"])
    with pytest.raises(ValueError, match="no actions"):
        learner.update("go to the purple room", novel_b, demonstration=[])
    with pytest.raises(TypeError, match="goal must be"):
        learner.update("go to the purple room", novel_b, goal=3)
    # a demonstration and a goal it never reaches (it had been folded in as if it did: "mauve" learned as red)
    with pytest.raises(ValueError, match=r"the demonstration ends where goal agentInRoom\(agent0, room0\) does not hold"):
        learner.update("go to the mauve room", novel_b, demonstration=["east"], goal="agentInRoom(agent0, room0)")
    other = parse_state(ORANGE_LAYOUT.replace("room,10,", "room,1,").replace("room,8,", "room,2,")
                        .replace("room,5,", "room,3,").replace("block,12,", "block,4,"), "sokoban2")
    with pytest.raises(ValueError, match="palette"):
        learner.update("go to the purple room", other, goal="agentInRoom(agent0, room1)")
    assert learner.vocab.words == words and torch.equal(learner.globals["phi"], phi)


def test_an_updated_model_saves_and_loads(learner, novel_b, tmp_path):
    learner.update("go to the purple room", novel_b, goal="agentInRoom(agent0, room1)")
    loaded = Learner.load(learner.save(tmp_path / "updated"))
    assert loaded.vocab.words == learner.vocab.words
    assert _follow(loaded, "go to the purple room", novel_b).goal == BLUE_ROOM
    # a second update reads the counts of the first back from the saved model
    loaded.update("go to the purple room", novel_b, goal="agentInRoom(agent0, room1)")
    assert _follow(loaded, "go to the purple room", novel_b).confidence > 0.93


def _cli(model_dir, command, *extra):
    from groundlang.cli import main

    return main(["--quiet", "follow", command, "--env", str(EXAMPLES / "novel_b.state"), "--palette", "sokoban",
                 "--model", str(model_dir), *extra])


def test_cli_learns_from_the_answer_and_then_acts_without_asking(trained, tmp_path, capsys, monkeypatch):
    model_dir = trained.save(tmp_path / "model")
    monkeypatch.setattr("sys.stdin", io.StringIO("the blue one\n"))
    assert _cli(model_dir, "go to the purple room", "--ask", "--learn") == 0
    out = capsys.readouterr().out
    assert (f"learned that 'go to the purple room' means the agent in the blue room (new words: 'purple'); "
            f"model saved to {model_dir}") in out
    assert sorted(p.name for p in model_dir.iterdir() if not p.name.startswith("globals-")) == ["model.json"]
    monkeypatch.setattr("sys.stdin", io.StringIO(""))  # nothing to answer with: it must not ask
    assert _cli(model_dir, "go to the purple room") == 0
    out = capsys.readouterr().out
    assert "goal the agent in the blue room \u2014 agentInRoom(agent0, room1): reached (goal)" in out
    assert _cli(model_dir, "take the star to the purple room") == 0
    assert "toyInRoom(block0, room1): reached (goal)" in capsys.readouterr().out


def test_cli_learn_needs_ask_and_leaves_the_model_alone_without_an_answer(trained, tmp_path, capsys, monkeypatch):
    model_dir = trained.save(tmp_path / "model")
    saved = (model_dir / "model.json").read_bytes()
    assert _cli(model_dir, "go to the purple room", "--learn") == 2
    assert capsys.readouterr().err.strip() == ("groundlang follow: error: --learn learns from the answer to a "
                                               "question: use it with --ask")
    monkeypatch.setattr("sys.stdin", io.StringIO(""))
    assert _cli(model_dir, "go to the purple room", "--ask", "--learn") == 3
    # a confident command is acted on, with nothing to learn
    assert _cli(model_dir, "go to the red room", "--ask", "--learn") == 0
    assert "learned" not in capsys.readouterr().out
    assert (model_dir / "model.json").read_bytes() == saved


def test_cli_learn_refuses_a_model_folder_it_cannot_save_to_before_asking(trained, tmp_path, capsys, monkeypatch):
    # the answer is learned and saved after the question: a folder that cannot take the model (a read-only
    # mount; root ignores permission bits, so the probe is made to fail) is refused before the question
    from groundlang.logic import storage

    model_dir = trained.save(tmp_path / "model")

    def read_only(folder, name, what):
        raise ValueError(f"{what}: cannot create a file in {folder} (Read-only file system)")

    monkeypatch.setattr(storage, "check_writable", read_only)
    monkeypatch.setattr("sys.stdin", io.StringIO("the blue one\n"))
    assert _cli(model_dir, "go to the purple room", "--ask", "--learn") == 2
    out, err = capsys.readouterr()
    assert "Which room" not in out and err.strip() == (f"groundlang follow: error: --model {model_dir}: cannot create "
                                                       f"a file in {model_dir} (Read-only file system)")
    assert _cli(model_dir, "go to the red room", "--ask") == 0  # without --learn nothing is saved: no probe
