"""``groundlang parse``: a command's readings on the command line, and a file's or corpus's commands with a summary."""

from __future__ import annotations

import json

from groundlang.cli import main


def test_cli_parse_text_and_json(capsys, tmp_path):
    assert main(["parse", "Push the star into the green room"]) == 0
    out = capsys.readouterr().out
    assert "0.650  push(star1, room1), P1(room1, green)" in out
    assert main(["parse", "--json", "go to green"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record == {"command": "go to green", "words": ["go", "to", "green"], "readings": [
        {"logical_form": "go(green1), P1(green1, green)", "probability": 1.0, "fallback": False}]}
    # a multiword entry of a word file is read as one word: parse says so (the logical form shows no preposition)
    assert main(["parse", "stand to the left of the red chair"]) == 0
    assert capsys.readouterr().out.splitlines()[1] == "  read as: stand to_the_left_of the red chair"
    # and where a word file's synonym was read as its word, or nothing was read otherwise than typed
    words = tmp_path / "syn.words"
    words.write_text("SYNONYM: toward=into\n")
    assert main(["parse", "--lexicon", str(words), "go toward the red room"]) == 0
    assert capsys.readouterr().out.splitlines()[1] == "  read as: go into the red room"
    assert main(["parse", "go to the red room ."]) == 0
    assert "read as" not in capsys.readouterr().out


def test_cli_parse_escapes_a_commands_control_characters(tmp_path, capsys):
    """An escape sequence had been printed raw (and cleared the terminal); follow shows it escaped, and so does parse."""
    assert main(["parse", "go to the \x1b[2Jred room"]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and out.splitlines()[0] == "'go to the \\x1b[2Jred room'"
    path = tmp_path / "commands.txt"
    path.write_text("go to the \x1b[2Jred room\ngo to the red room\n", encoding="utf-8")
    assert main(["parse", "--file", str(path)]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "'go to the \\x1b[2Jred room'" in out.splitlines()
    assert "go to the red room" in out.splitlines()  # printable text is shown as typed


def test_cli_parse_file_summary_and_errors(tmp_path, capsys):
    path = tmp_path / "commands.txt"
    path.write_text("go to green\n\nthe into green star room of blue the the\n", encoding="utf-8")
    assert main(["parse", "--file", str(path)]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == "2 commands: 1 full parse, 1 fallback only"
    assert main(["parse", "   "]) == 2
    assert "empty" in capsys.readouterr().err
    assert main(["parse"]) == 2
    capsys.readouterr()
    # a file of commands is UTF-8 like every other file read (a byte-order mark dropped), not guessed at
    path.write_bytes(b"\xef\xbb\xbfgo to green\ngo to the r\xe9d room\n")
    assert main(["parse", "--file", str(path)]) == 2
    assert capsys.readouterr().err.strip() == (f"groundlang parse: error: {path}, line 2: byte 0xe9 at offset 26 is "
                                               "not UTF-8; expected a UTF-8 text file")
    path.write_bytes(b"\xef\xbb\xbfgo to green\n")
    assert main(["parse", "--json", "--file", str(path)]) == 0
    assert json.loads(capsys.readouterr().out)["command"] == "go to green"


def test_cli_parse_corpus_folder(tmp_path, capsys):
    for i, text in enumerate(["push star into orange room", "walk to beige room"]):
        (tmp_path / f"x{i}.txt").write_text(f"{text}\nnorth\nagent,1,1\nagent,1,2\n", encoding="utf-8")
    assert main(["parse", "--json", "--file", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    assert [json.loads(line)["command"] for line in captured.out.splitlines()] == [
        "push star into orange room", "walk to beige room"]
    assert captured.err.strip().endswith("2 commands: 2 full parse, 0 fallback only")


def test_cli_parse_file_reads_the_commands_of_a_bdm_file_or_one_corpus_file(tmp_path, capsys):
    """A .bdm file's state lines, "true" and "---" had been parsed as commands (20 "commands" of a file of two),
    and so had a corpus file's actions and states."""
    from pathlib import Path

    from groundlang.corpus import example_corpus_path

    fixture = Path(__file__).parent / "fixtures" / "williams2018" / "small.bdm"
    assert main(["parse", "--file", str(fixture)]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[-1] == "2 commands: 2 full parse, 0 fallback only" and "true()" not in out
    assert main(["parse", "--json", "--file", str(fixture.parent)]) == 0  # a folder of .bdm files too
    texts = [json.loads(line)["command"] for line in capsys.readouterr().out.splitlines()]
    assert texts == [line.strip() for i, line in enumerate(fixture.read_text().splitlines())
                     if i == 0 or (line.strip() and not fixture.read_text().splitlines()[i - 1].strip())]
    # the states are not read: a .bdm file parses whatever palette its states are in, as --palette only adds words
    assert main(["parse", "--palette", "sokoban", "--file", str(fixture)]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == "2 commands: 2 full parse, 0 fallback only"
    broken = tmp_path / "broken.bdm"
    broken.write_text("true\n{agent0 (agent): [x: {1} y: {1} ] , }\n", encoding="utf-8")
    assert main(["parse", "--file", str(broken)]) == 2
    assert f"{broken}, line 1: a block starts with the word true; expected the command first" in capsys.readouterr().err
    corpus_file = example_corpus_path() / "agent2red_0.txt"
    assert main(["parse", "--file", str(corpus_file)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == corpus_file.read_text().splitlines()[0] and out[-1] == "1 command: 1 full parse, 0 fallback only"
