"""A command given in several start states asks for what holds in none of them (groundlang.other_starts)."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from groundlang.corpus import example_corpus_path, read_state_file
from groundlang.learner import Learner
from groundlang.other_starts import given_other_starts, held_shares

EXAMPLES = example_corpus_path()
COMMAND = "go to the red room with the star"


@pytest.fixture(scope="module")
def novel_a():
    return read_state_file(EXAMPLES / "novel_a.state", "sokoban")


@pytest.fixture(scope="module")
def star_in_red(novel_a):
    """novel_a with the star two cells into the red room: there the star is in the red room already."""
    red = next(room for room in novel_a.layout.rooms if room.colour == "red")
    positions = novel_a.positions.copy()
    positions[1] = [red.left + 2, red.bottom + 2]
    state = novel_a.with_positions(positions)
    state.validate()
    return state


def _task_mass(post) -> Counter:
    mass: Counter = Counter()
    for interp, p in zip(post.interpretations, post.probabilities):
        mass[interp.lifted] += float(p)
    return mass


def test_the_words_say_which_task_already_holds_in_a_start(learner, novel_a, star_in_red):
    assert held_shares(learner, COMMAND, star_in_red)["toyToRoom"] > 0.95  # the star is in the red room there
    assert held_shares(learner, COMMAND, novel_a) == {}  # nothing the words ask holds at novel_a's start


def test_a_task_holding_in_another_start_is_not_what_the_command_asks(learner, novel_a, star_in_red):
    alone = _task_mass(learner.posterior(COMMAND, novel_a))
    assert alone["toyToRoom"] > 0.9
    given = _task_mass(learner.posterior(COMMAND, novel_a, other_starts=[star_in_red]))
    # The star was in the red room in a state the command was also given in: it asks for more than that.
    assert given["toyToRoom"] < 0.2 and given["toyToRoomAgentToRoom"] > 0.6
    assert sum(given.values()) == pytest.approx(1.0)
    # A start where nothing it asks holds changes nothing.
    assert _task_mass(learner.posterior(COMMAND, novel_a, other_starts=[novel_a])) == pytest.approx(alone)


def test_following_acts_on_what_no_start_shows_held(learner, novel_a, star_in_red):
    result = learner.follow(COMMAND, novel_a, other_starts=[star_in_red])
    assert {atom.predicate for atom in result.goal} >= {"agentInRoom"}
    assert result.goal != learner.follow(COMMAND, novel_a).goal


def test_the_setting_off_reads_the_command_in_its_own_start_alone(learner, novel_a, star_in_red):
    alone = _task_mass(learner.posterior(COMMAND, novel_a))
    learner.lm.other_starts = False
    try:
        assert _task_mass(learner.posterior(COMMAND, novel_a, other_starts=[star_in_red])) == pytest.approx(alone)
    finally:
        learner.lm.other_starts = True


def test_nothing_is_ruled_out_where_every_reading_would_be(learner, novel_a):
    post = learner.posterior(COMMAND, novel_a)
    probabilities = np.asarray(post.probabilities, dtype=float)
    everything = {interp.lifted: 1.0 for interp in post.interpretations}
    assert given_other_starts(probabilities, post.interpretations, [everything]) is probabilities
    assert given_other_starts(probabilities, post.interpretations, [{}, {}]) is probabilities
    half = given_other_starts(probabilities, post.interpretations, [{"toyToRoom": 0.5}])
    toy = np.array([interp.lifted == "toyToRoom" for interp in post.interpretations])
    assert half[toy].sum() / half[~toy].sum() == pytest.approx(0.5 * probabilities[toy].sum() / probabilities[~toy].sum())


@pytest.mark.parametrize("other, message", [
    ("state", "other_starts must be a sequence of States"),
    ("text", "other_starts must be a sequence of States"),
    ("list of text", r"other_starts\[0\] is a str, expected a State"),
])
def test_other_starts_of_the_wrong_type_are_refused_in_one_line(learner, novel_a, other, message):
    given = {"state": novel_a, "text": "novel_a.state", "list of text": ["novel_a.state"]}[other]
    with pytest.raises(TypeError, match=message):
        learner.follow(COMMAND, novel_a, other_starts=given)
    with pytest.raises(TypeError, match=message):
        learner.posterior(COMMAND, novel_a, other_starts=given)


def test_a_model_saved_before_other_starts_follows_as_it_did(learner):
    state = learner.state_dict()
    assert Learner.from_state_dict(state).lm.other_starts is True
    del state["language_model_settings"]["other_starts"]
    assert Learner.from_state_dict(state).lm.other_starts is False


def test_pair_evaluation_gives_each_execution_the_commands_other_starts(williams_commands, williams_library,
                                                                        monkeypatch):
    from groundlang.pair_evaluation import evaluate_pairs

    seen = []
    follow = Learner.follow

    def spy(self, command, state, *args, **kwargs):
        seen.append((command, state, tuple(kwargs.get("other_starts", ()))))
        return follow(self, command, state, *args, **kwargs)

    monkeypatch.setattr(Learner, "follow", spy)
    evaluate_pairs(williams_commands, williams_commands, williams_library)
    expected = [(c.text, p.start, tuple(q.start for q in c.pairs if q is not p)) for c in williams_commands
                for p in c.pairs]
    assert seen == expected


def test_follow_reads_other_starts_from_files_and_names_a_bad_one(learner, star_in_red, tmp_path, capsys):
    import json

    from groundlang.cli import main
    from groundlang.state_line import format_state

    model = learner.save(tmp_path / "model")
    other = tmp_path / "star_in_red.state"
    other.write_text(format_state(star_in_red) + "\n", encoding="utf-8")
    base = ["--quiet", "follow", COMMAND, "--model", str(model), "--env", str(EXAMPLES / "novel_a.state"), "--guess",
            "--json"]
    main(base)
    alone = json.loads(capsys.readouterr().out)
    main(base + ["--other-start", str(other)])
    given = json.loads(capsys.readouterr().out)
    assert alone["goal"] == "toyInRoom(block0, room2)"
    assert given["goal"] != alone["goal"] and "agentInRoom(agent0, room2)" in given["goal"]
    broken = tmp_path / "broken.state"
    broken.write_text("room,1,0,10,6,5 agent,3\n", encoding="utf-8")
    assert main(base + ["--other-start", str(broken)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"groundlang follow: error: {broken}") and err.count("\n") == 1


def test_the_start_itself_given_as_another_changes_nothing(learner, novel_a, star_in_red):
    """Per lifted task, its readings holding in the start had counted against all of its readings."""
    alone = _task_mass(learner.posterior(COMMAND, star_in_red))
    assert _task_mass(learner.posterior(COMMAND, star_in_red, other_starts=[star_in_red])) == pytest.approx(alone)


def test_another_start_of_another_palette_is_named_by_its_place(learner, novel_a):
    from groundlang.corpus import parse_state

    other = parse_state("room,1,0,4,4,0 block,1,0,2,2 agent,1,1", "sokoban2")
    with pytest.raises(ValueError, match=r"^posterior: other_starts\[1\]: the state is of palette 'sokoban2'"):
        learner.posterior(COMMAND, novel_a, other_starts=[novel_a, other])


def test_follow_names_an_other_start_file_it_cannot_read_for_the_model(learner, tmp_path, capsys):
    from groundlang.cli import main

    model = learner.save(tmp_path / "model")
    other = tmp_path / "huge.state"
    other.write_text("room,1,0,70,70,0 agent,1,1\n", encoding="utf-8")  # 4,761 walkable cells: no PF table
    assert main(["--quiet", "follow", COMMAND, "--model", str(model), "--env", str(EXAMPLES / "novel_a.state"),
                 "--other-start", str(other)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"groundlang follow: error: {other}: this layout has 4,761 walkable cells")
    assert err.count("\n") == 1


def test_a_commands_other_starts_are_read_once_while_the_model_is_unchanged(learner, novel_a, star_in_red,
                                                                            monkeypatch):
    """Followed from each of its starts, the others given, a command read each start twice; a changed model
    (refitted, updated: new parts) or another command reads them again."""
    import groundlang.other_starts as other_starts

    command = "bring the star to the red room"  # read with other starts by no other test of the module

    read = []
    real = other_starts.held_shares
    monkeypatch.setattr(other_starts, "held_shares", lambda l, c, s, where: read.append((c, s)) or real(l, c, s, where))
    first = learner.posterior(command, novel_a, other_starts=[star_in_red])
    again = learner.posterior(command, novel_a, other_starts=[star_in_red])
    assert read == [(command, star_in_red)] and np.array_equal(first.probabilities, again.probabilities)
    learner.posterior("go to the red room", novel_a, other_starts=[star_in_red])
    assert len(read) == 2
    learner.posterior(command, novel_a, other_starts=[star_in_red])
    assert len(read) == 3  # another command came between
    saved = learner.globals
    learner.globals = dict(saved)  # what update() does: new parts
    try:
        learner.posterior(command, novel_a, other_starts=[star_in_red])
        assert len(read) == 4
    finally:
        learner.globals = saved
    learner.lm.argument_bonus += 1.0  # a setting changed in place
    try:
        learner.posterior(command, novel_a, other_starts=[star_in_red])
        assert len(read) == 5
    finally:
        learner.lm.argument_bonus -= 1.0
