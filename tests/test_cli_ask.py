"""``groundlang follow`` asking on the terminal: exit code 3 with the question, --guess, and --ask reading answers
from stdin (declining, end of input, bytes that are not UTF-8, overlong answers)."""

from __future__ import annotations

import pytest

from groundlang.corpus import example_corpus_path
from groundlang.learner import DEFAULT_MIN_CONFIDENCE

EXAMPLES = example_corpus_path()


@pytest.fixture(scope="module")
def model_dir(learner, tmp_path_factory):
    return learner.save(tmp_path_factory.mktemp("model") / "m")


def _follow(model_dir, command, *extra):
    from groundlang.cli import main

    return main(["--quiet", "follow", command, "--env", str(EXAMPLES / "novel_b.state"), "--palette", "sokoban",
                 "--model", str(model_dir), *extra])


def test_cli_asks_with_exit_code_3_and_guess_acts(model_dir, capsys, tmp_path):
    from groundlang.commands.follow import ASKED, DEFAULT_MIN_CONFIDENCE as CLI_DEFAULT

    assert CLI_DEFAULT == DEFAULT_MIN_CONFIDENCE and ASKED == 3
    assert _follow(model_dir, "go to the purple room", "--out", str(tmp_path / "asked.png")) == 3
    assert not (tmp_path / "asked.png").exists()  # nothing done, nothing drawn
    out, err = capsys.readouterr()
    assert ("I don't know the word 'purple'. Which room do you mean: the red room, the blue room or the green room?"
            in out)
    assert "  2) the blue room  (0.33; agentInRoom(agent0, room1))" in out and "plan" not in out
    assert err.strip() == ("groundlang follow: not acting: confidence 0.33 is below --min-confidence 0.7; "
                           "answer with --ask, or act anyway with --guess")
    # with --json nothing is asked on the terminal: the message says where the question is
    assert _follow(model_dir, "go to the purple room", "--ask", "--json") == 3
    out, err = capsys.readouterr()
    assert '"question": "I don' in out and err.strip().endswith(
        "the question and its choices are in the JSON (--ask asks only without --json), or act anyway with --guess")
    assert _follow(model_dir, "go to the purple room", "--guess") == 0
    # three rooms equally probable: each is as likely to be right, so it ends in the nearest (expected_success);
    # the nearest states tie (the agent stands in the door between the blue and the green room), which is
    # taken is decided by the last bits of the posterior, and the goal said is the room it ends in
    out = capsys.readouterr().out
    assert ("plan (1 step): west" in out and "goal the agent in the blue room \u2014 agentInRoom(agent0, room1): "
            "reached (goal)" in out) or ("plan (1 step): east" in out and "goal the agent in the green room "
                                         "\u2014 agentInRoom(agent0, room2): reached (goal)" in out), out
    assert _follow(model_dir, "take the star to the red room") == 0
    out = capsys.readouterr().out
    assert "0.9851  the yellow star in the red room \u2014 toyInRoom(block0, room0)" in out


def test_cli_ask_reads_the_answer_from_stdin(model_dir, capsys, monkeypatch):
    import io

    monkeypatch.setattr("sys.stdin", io.StringIO("the orange one\nthe blue one\n"))
    assert _follow(model_dir, "go to the purple room", "--ask") == 0
    out = capsys.readouterr().out
    assert "names none of the choices" in out  # the first answer, asked again
    assert "acting on the answer (from the words alone: the most probable goal 0.33, margin 0.00 over the next " \
           "goal that differs)\nplan (1 step): west" in out
    assert "goal the agent in the blue room \u2014 agentInRoom(agent0, room1): reached (goal)" in out
    # a piped answer is shown as read, an escape sequence escaped (it had cleared the terminal)
    monkeypatch.setattr("sys.stdin", io.StringIO("\x1b[2Jthe blue one\n"))
    assert _follow(model_dir, "go to the purple room", "--ask") in (0, 3)
    out = capsys.readouterr().out
    assert "\x1b" not in out and "'\\x1b[2Jthe blue one'" in out
    monkeypatch.setattr("sys.stdin", io.StringIO(""))  # end of input: nothing done
    assert _follow(model_dir, "go to the purple room", "--ask") == 3
    assert capsys.readouterr().err.strip() == "groundlang follow: no answer named a choice; nothing done"


def test_cli_ask_stops_at_an_answer_that_declines_and_acts_on_a_yes(model_dir, capsys, monkeypatch):
    """A "no" had been answered with the question again, until the tries ran out: it declines, nothing done."""
    import io

    monkeypatch.setattr("sys.stdin", io.StringIO("none of them\nthe blue one\n"))
    assert _follow(model_dir, "go to the purple room", "--ask") == 3
    captured = capsys.readouterr()
    assert "'none of them' declines every choice: nothing is done" in captured.out
    assert captured.out.count("answer>") == 1 and "plan" not in captured.out  # not asked again
    assert captured.err.strip() == "groundlang follow: the answer declined what was offered; nothing done"
    # a question of one choice, taken by a yes
    monkeypatch.setattr("sys.stdin", io.StringIO("yes please\n"))
    assert _follow(model_dir, "go to the red room", "--ask", "--min-confidence", "1") == 0
    out = capsys.readouterr().out
    assert "Do you mean the agent in the red room?" in out
    assert "goal the agent in the red room \u2014 agentInRoom(agent0, room0): reached (goal)" in out


def test_cli_ask_with_stdin_closed_is_end_of_input(model_dir, capsys, monkeypatch):
    monkeypatch.setattr("sys.stdin", None)  # what Python makes of `<&-`: had failed with an AttributeError
    assert _follow(model_dir, "go to the purple room", "--ask") == 3
    assert capsys.readouterr().err.strip() == "groundlang follow: no answer named a choice; nothing done"


def test_cli_ask_gives_up_on_an_input_with_no_line_end(model_dir, capsys, monkeypatch):
    import io

    class Endless(io.TextIOBase):  # /dev/zero: a line that never ends had been read forever
        def readline(self, size=-1):
            return "\0" * (size if size > 0 else 1 << 16)

    monkeypatch.setattr("sys.stdin", Endless())
    monkeypatch.setattr("groundlang.commands.asking.MAX_DROPPED_CHARS", 1 << 20)
    assert _follow(model_dir, "go to the purple room", "--ask") == 3
    captured = capsys.readouterr()
    assert "no line end within 1,048,576 characters: no answer" in captured.out
    assert captured.err.strip() == "groundlang follow: no answer named a choice; nothing done"


def test_cli_ask_says_an_answer_is_not_utf8_and_reads_the_next(model_dir, capsys, monkeypatch):
    import io

    # strict decoding, as stdin has under a UTF-8 locale other than C.UTF-8: the run had ended blaming the command
    stdin = io.TextIOWrapper(io.BytesIO(b"gr\xfcn\n2\n"), encoding="utf-8", errors="strict")
    monkeypatch.setattr("sys.stdin", stdin)
    assert _follow(model_dir, "go to the purple room", "--ask") == 0
    out = capsys.readouterr().out
    assert "the answer is not UTF-8 text (byte 0xfc at character 3)" in out and "command" not in out.split("answer>")[1]
    assert "goal the agent in the blue room \u2014 agentInRoom(agent0, room1): reached (goal)" in out


def test_cli_ask_refuses_an_overlong_answer_without_reading_it_whole(model_dir, capsys, monkeypatch):
    import io

    from groundlang.commands.asking import MAX_ANSWER_CHARS

    monkeypatch.setattr("sys.stdin", io.StringIO("x" * (50 * MAX_ANSWER_CHARS) + "\nthe blue one\n"))
    assert _follow(model_dir, "go to the purple room", "--ask") == 0
    out = capsys.readouterr().out
    assert f"an answer is at most {MAX_ANSWER_CHARS} characters" in out
    assert "x" * (MAX_ANSWER_CHARS + 1) not in out  # not echoed whole
    assert "goal the agent in the blue room \u2014 agentInRoom(agent0, room1): reached (goal)" in out


def test_cli_guess_takes_no_threshold(model_dir, capsys):
    """--guess acts however unsure: a --min-confidence beside it had been dropped without a word."""
    assert _follow(model_dir, "go to the purple room", "--guess", "--min-confidence", "0.9") == 2
    assert capsys.readouterr().err.strip() == ("groundlang follow: error: --guess acts however unsure, so "
                                               "--min-confidence 0.9 would do nothing: give one or the other")
    assert _follow(model_dir, "go to the purple room", "--guess") == 0
