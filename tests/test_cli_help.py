"""Every option of every command says what it does (issue 23: output a person can read)."""

from __future__ import annotations

import argparse

import pytest

from groundlang.cli import build_parser


def test_every_option_of_every_command_has_help():
    missing = []
    for action in build_parser()._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                missing += [f"{name} {' '.join(a.option_strings) or a.dest}" for a in sub._actions if a.help is None]
    assert missing == []


def test_the_log_level_is_groundlangs_own():
    """A run shows groundlang's information, not other libraries' (torch logs its FakeTensor cache
    statistics at INFO when the process exits)."""
    import subprocess
    import sys

    script = ("import logging; from groundlang.cli import main; main(['domain', '--palette', 'sokoban']); "
              "logging.getLogger('torch.other').info('LEAKED'); logging.getLogger('groundlang.x').info('OURS')")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "OURS" in done.stderr and "LEAKED" not in done.stderr


def test_json_output_is_strict_json_everywhere():
    """JSON has no NaN: a figure without a value is null in every command's JSON, printed or written."""
    import json
    import math
    from pathlib import Path

    from groundlang.commands import json_bytes, json_text

    data = {"auroc": math.nan, "rows": [1.5, -math.inf, {"x": (math.inf, 2)}], "name": "a"}
    strict = json.loads(json_text(data), parse_constant=lambda c: (_ for _ in ()).throw(ValueError(c)))
    assert strict == {"auroc": None, "rows": [1.5, None, {"x": [None, 2]}], "name": "a"}
    assert json.loads(json_bytes(data)) == strict and json_bytes(data).startswith(b"{\n")
    # no command writes JSON past json_text: a json.dumps there could write NaN again
    commands = Path(__file__).parent.parent / "groundlang" / "commands"
    assert [p.name for p in commands.glob("*.py") if p.name != "__init__.py" and "json.dumps" in p.read_text()] == []



@pytest.mark.parametrize("argv", [["evaluate", "--json", ""], ["ablate", "--json", " "], ["ablate", "--plot", ""],
                                  ["demo", "--out", ""], ["discover", "-o", ""], ["follow", "go", "--out", ""],
                                  ["show", "x.txt", "--out", ""], ["train", "-o", ""]])
def test_an_empty_output_path_is_refused_not_taken_for_no_output(argv, capsys):
    from groundlang.cli import main

    with pytest.raises(SystemExit) as stopped:
        main(argv)
    assert stopped.value.code == 2
    assert "an empty path; expected where to write" in capsys.readouterr().err


@pytest.mark.parametrize("argv", [["evaluate", "--json", "-"], ["ablate", "--json", "-"], ["train", "-o", "-"]])
def test_a_dash_is_not_taken_for_a_file_named_dash(argv, capsys):
    from groundlang.cli import main

    with pytest.raises(SystemExit) as stopped:
        main(argv)
    assert stopped.value.code == 2
    assert "'-' is no file here; name the file to write" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["check", "domain", "evaluate", "parse", "tasks", "train"])
def test_an_empty_library_path_is_refused_not_taken_for_the_current_folder(command, capsys):
    from groundlang.cli import main

    with pytest.raises(SystemExit) as stopped:
        main([command, "x", "--library", ""])
    assert stopped.value.code == 2
    err = capsys.readouterr().err
    assert "argument --library: an empty path; expected a .lp file or a library the package ships" in err
    assert "Is a directory" not in err and len(err.splitlines()) == 1


def test_python_dash_m_groundlang_is_the_command():
    """``python -m groundlang`` runs the command where the venv's scripts are not on the path: its exit code and
    its one-line error included."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "groundlang", "check", "tests/fixtures/williams2018/small.bdm"],
                          capture_output=True, text=True, cwd=str(__import__("pathlib").Path(__file__).parent.parent))
    assert done.returncode == 0 and "commands: 2 (2 distinct texts)" in done.stdout, done.stdout + done.stderr
    bad = subprocess.run([sys.executable, "-m", "groundlang", "check", "no/such/corpus"], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "no/such/corpus" in bad.stderr


def test_output_a_terminal_cannot_encode_is_escaped_not_an_error():
    # tasks writes conjunctions with "∧": under PYTHONIOENCODING=ascii the run had ended in an error line
    import os
    import subprocess
    import sys

    from groundlang.corpus import example_corpus_path

    env = {**os.environ, "PYTHONIOENCODING": "ascii"}
    done = subprocess.run([sys.executable, "-m", "groundlang.cli", "tasks", str(example_corpus_path() / "novel_a.state"),
                           "--palette", "sokoban"], capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    assert "agentInRoom(A, RA) \\u2227 toyInRoom(T, RT)" in done.stdout


def test_parse_names_an_unknown_grammar_rule_in_its_weights():
    from groundlang.grammar.parser import parse

    with pytest.raises(ValueError, match="unknown grammar rule\\(s\\) 'zzz'; the rules are"):
        parse("go to the red room", weights={"zzz": 1.0})  # it had been ignored


@pytest.mark.parametrize("argv, quiet, verbose", [
    (["--quiet", "domain"], True, False),
    (["domain", "--quiet"], True, False),
    (["domain", "--verbose"], False, True),
    (["domain"], False, False),
])
def test_quiet_and_verbose_may_come_before_or_after_the_command(argv, quiet, verbose):
    args = build_parser().parse_args(argv)
    assert (args.quiet, args.verbose) == (quiet, verbose)


def test_help_is_plain_text_not_docstring_markup():
    """A command's help is read in a terminal: no reST ``literals`` (parse's description is its docstring)."""
    marked = []
    parser = build_parser()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                if "``" in sub.format_help():
                    marked.append(name)
    assert "``" not in parser.format_help() and marked == []
