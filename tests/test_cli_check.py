"""The ``check`` and ``show`` commands, called through groundlang.cli.main."""

from __future__ import annotations

import pytest

from groundlang.cli import main
from groundlang.corpus import example_corpus_path


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return code, out, err


def test_check_fixture_corpus(capsys, fixtures):
    code, out, err = run(capsys, "check", str(fixtures / "sokoban"), "--palette", "sokoban",
                         "--labels", str(fixtures / "sokoban" / "labels.csv"))
    assert code == 0
    assert out.splitlines() == [
        f"corpus: {fixtures / 'sokoban'} (palette sokoban)",
        "instances: 4",
        "distinct commands: 4",
        "distinct layouts: 1",
        "distinct demonstrations: 2",
        "inconsistent demonstrations: 0",
        "labelled: 4/4 files (2 prefixes in labels.csv)",
        "goal holds in final state: 4/4",
    ]


def test_check_inconsistent_exit_codes(capsys, fixtures):
    code, out, err = run(capsys, "check", str(fixtures / "inconsistent"), "--palette", "sokoban")
    assert code == 1
    assert "inconsistent demonstrations: 1" in out
    assert "agent2red_1.txt, line 5: step 2 (east) from line 4" in out
    assert "use --skip-inconsistent" in err
    code, out, err = run(capsys, "check", str(fixtures / "inconsistent"), "--palette", "sokoban", "--skip-inconsistent")
    assert code == 0
    assert "instances: 1" in out
    assert "skipped: 1 inconsistent files" in out


def test_check_failing_goal_exits_1(capsys, fixtures):
    code, out, err = run(capsys, "check", str(fixtures / "sokoban"), "--palette", "sokoban",
                         "--labels", str(fixtures / "labels" / "wrong_goal.csv"))
    assert code == 1
    assert "goal holds in final state: 2/4" in out
    assert "agent2red_0.txt: goal agentInRoom(agent0, room0) does not hold in the final state" in out


def test_check_partial_labels(capsys, fixtures):
    code, out, _ = run(capsys, "check", str(fixtures / "sokoban2"), "--palette", "sokoban2",
                       "--labels", str(fixtures / "sokoban2" / "labels.csv"))
    assert code == 0
    assert "labelled: 1/2 files (1 prefixes in labels.csv)" in out


@pytest.mark.parametrize(
    "argv, pieces",
    [
        (["check", "{f}/no_corpus", "--palette", "sokoban"], ["no_corpus: no corpus files"]),
        (["check", "{f}/missing_folder", "--palette", "sokoban"], ["missing_folder: not a directory"]),
        # What is wrong with the folder comes before asking for a palette it would not need.
        (["check", "{f}/missing_folder"], ["missing_folder: No such file or directory"]),
        (["check", "{f}/no_corpus"], ["no_corpus: no corpus files", "or .bdm files"]),
        (["train", "{f}/no_corpus", "-o", "{f}/never_written"], ["no_corpus: no corpus files"]),
        (["evaluate", "--corpus", "{f}/missing_folder"], ["missing_folder: No such file or directory"]),
        (["check", "{f}/sokoban"], ["sokoban: --palette is required"]),
        (["check", "{f}/sokoban", "--palette", "sokoban2"], ["line 3", "colour index", "outside palette 'sokoban2'"]),
        (["check", "{f}/sokoban", "--palette", "sokoban", "--labels", "{f}/labels/unknown_prefix.csv"],
         ["prefixes star2blue_ name no files"]),
        (["check", "{f}/sokoban", "--palette", "sokoban", "--labels", "{f}/labels/unknown_object.csv"],
         ["names room7, which does not exist"]),
        (["check", "{f}/sokoban", "--palette", "sokoban", "--labels", "{f}/labels/bad_header.csv"],
         ["bad_header.csv, line 1"]),
        (["check", "{f}/sokoban", "--palette", "sokoban", "--labels", "{f}/labels/absent.csv"], ["absent.csv"]),
        (["show", "{f}/malformed/non_utf8.txt", "--palette", "sokoban"], ["non_utf8.txt, line 1", "not UTF-8"]),
        (["show", "{f}/malformed/truncated.txt", "--palette", "sokoban"], ["truncated.txt, line 5"]),
        (["show", "{f}/two_lines.state", "--palette", "sokoban"], ["two_lines.state, line 2"]),
        (["show", "{f}/inconsistent/agent2red_1.txt", "--palette", "sokoban"], ["line 5: step 2"]),
    ],
)
def test_bad_input_is_one_line_and_exit_2(capsys, fixtures, argv, pieces):
    code, out, err = run(capsys, *[a.format(f=fixtures) for a in argv])
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"groundlang {argv[0]}: error: ")
    for piece in pieces:
        assert piece in lines[0]


@pytest.mark.parametrize("name", ["empty.txt", "wrong_fields.txt", "not_a_number.txt", "unknown_kind.txt",
                                  "colour_outside_palette.txt", "unknown_action.txt", "object_in_wall.txt"])
def test_show_malformed_files(capsys, fixtures, name):
    code, out, err = run(capsys, "show", str(fixtures / "malformed" / name), "--palette", "sokoban")
    assert code == 2
    assert name in err and len(err.strip().splitlines()) == 1
    assert out == ""


def test_show_corpus_file_with_picture(capsys, fixtures, tmp_path):
    png = tmp_path / "star.png"
    code, out, err = run(capsys, "show", str(fixtures / "sokoban" / "star2green_0.txt"), "--palette", "sokoban",
                         "--out", str(png))
    assert code == 0
    lines = out.splitlines()
    assert lines[0] == "command: push the star into the green room"
    assert lines[1] == "steps: 2 (west,west)"
    assert lines[2] == "initial state:"
    assert lines[3:8] == ["#########", "#ggg#rrr#", "#ggg+SAr#", "#ggg#rrr#", "#########"]
    assert "final state:" in lines
    assert "#ggSArrr#" in lines
    assert lines[-1] == f"wrote {png}"
    assert png.read_bytes().startswith(b"\x89PNG")


def test_show_state_file(capsys, fixtures, tmp_path):
    code, out, _ = run(capsys, "show", str(fixtures / "two_toys.state"), "--palette", "sokoban2",
                       "--out", str(tmp_path / "s.png"))
    assert code == 0
    assert "#bbb+CAy#" in out.splitlines()
    assert (tmp_path / "s.png").stat().st_size > 1000


def test_show_a_one_line_bdm_state_file_without_a_palette(capsys, fixtures, tmp_path):
    """A BURLAP state line (Williams et al.) is shown as a .state file is, with its own palette by default."""
    line = (fixtures / "williams2018" / "small.bdm").read_text(encoding="utf-8").splitlines()[1]
    (tmp_path / "one.bdm").write_text(line + "\n", encoding="utf-8")
    code, out, err = run(capsys, "show", str(tmp_path / "one.bdm"), "--out", str(tmp_path / "one.png"))
    assert code == 0 and err == ""
    assert out.splitlines()[0] == f"state: {tmp_path / 'one.bdm'}" and "A" in out
    assert (tmp_path / "one.png").read_bytes().startswith(b"\x89PNG")


@pytest.mark.parametrize("command", ["show", "tasks"])
@pytest.mark.parametrize("name, piece", [
    ("small.bdm", "line 1 is not a state line; {command} reads a one-line .bdm or .state file"),
    ("absent.bdm", "absent.bdm: No such file or directory"),
])
def test_show_and_tasks_say_what_a_bdm_file_they_cannot_read_is(capsys, fixtures, name, piece, command):
    code, out, err = run(capsys, command, str(fixtures / "williams2018" / name))
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and piece.format(command=command) in err


def test_check_example_corpus(capsys):
    folder = example_corpus_path()
    code, out, _ = run(capsys, "check", str(folder), "--palette", "sokoban", "--labels", str(folder / "labels.csv"))
    assert code == 0
    assert "instances: 24" in out
    assert "distinct demonstrations: 6" in out
    assert "labelled: 24/24 files" in out
    assert "goal holds in final state: 24/24" in out


@pytest.mark.parametrize("folder, commands", [("allTurkTrain", 237), ("allTurkTrainLimitedCommand", 227)])
def test_check_shared_corpus(capsys, shared_corpus, folder, commands):
    code, out, err = run(capsys, "check", str(shared_corpus / folder), "--palette", "sokoban",
                         "--labels", str(shared_corpus / "labels.csv"))
    assert code == 0
    assert out.splitlines()[1:] == [
        "instances: 240",
        f"distinct commands: {commands}",
        "distinct layouts: 1",
        "distinct demonstrations: 6",
        "inconsistent demonstrations: 0",
        "labelled: 240/240 files (6 prefixes in labels.csv)",
        "goal holds in final state: 240/240",
    ]


def test_check_reads_a_library_given_without_labels(capsys, tmp_path):
    # the library is part of what is checked: a script in it is refused whether or not --labels uses it
    bad = tmp_path / "bad.lp"
    bad.write_text("#script (python)\nimport os\n#end.\n")
    code, out, err = run(capsys, "check", str(example_corpus_path()), "--palette", "sokoban", "--library", str(bad))
    assert code == 2 and f"{bad}:1: #script blocks are refused" in err and out == ""


def test_check_refuses_labels_for_a_bdm_corpus_in_one_line(capsys):
    """A .bdm pair's end state is its label: --labels, even a file that does not exist, is said to be wrong,
    not ignored."""
    code = main(["check", "tests/fixtures/williams2018/small.bdm", "--labels", "no-such-labels.csv"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "--labels no-such-labels.csv" in err and ".bdm corpus" in err and "\n" not in err


@pytest.mark.parametrize("argv", [
    ["check", "{examples}", "--palette", "sokoban", "--library", "{lp}"],
    ["parse", "go to the red room", "--library", "{lp}"],
    ["discover", "{examples}", "--palette", "sokoban", "-o", "{tmp}/found.lp", "--pfs", "{lp}"],
])
def test_a_grounding_that_times_out_names_the_time_limit_the_command_takes(capsys, tmp_path, argv):
    """The message had said "--time-limit or time_limit=" where check, parse and discover took no --time-limit;
    they take it now, and the CLI names it beside the message."""
    forever = tmp_path / "forever.lp"
    forever.write_text("n(0). n(X+1) :- n(X).\n")
    args = [a.format(examples=example_corpus_path(), lp=forever, tmp=tmp_path) for a in argv]
    code, _, err = run(capsys, *args, "--time-limit", "0.5")
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert err.strip().endswith("did not finish within 0.5 s; the program grounds too many atoms: infinitely many (a "
                                "rule without a bound), or a large layout's many (raise the time limit if it is just "
                                "large); --time-limit SECONDS sets it")


def test_a_command_without_a_time_limit_is_not_told_to_raise_one(capsys, monkeypatch):
    from groundlang.commands import irl
    from groundlang.logic.program import AspTimeout

    def too_large(*_):
        raise AspTimeout("grounding the layout did not finish within 10 s (raise the time limit if it is just large)")

    monkeypatch.setattr(irl, "fit_file", too_large)
    code, _, err = run(capsys, "irl", str(example_corpus_path() / "agent2red_0.txt"), "--palette", "sokoban")
    assert code == 2 and "did not finish within 10 s" in err and "--time-limit" not in err


def test_time_limit_acts_on_a_bdm_check_and_is_refused_where_it_would_not(capsys, tmp_path):
    code, _, err = run(capsys, "check", "tests/fixtures/williams2018/small.bdm", "--time-limit", "0.001")
    assert code == 2 and "did not finish within 0.001 s" in err
    code, _, err = run(capsys, "discover", str(example_corpus_path()), "--palette", "sokoban", "-o",
                       str(tmp_path / "found.lp"), "--time-limit", "1")
    assert code == 2 and "--time-limit: discover grounds a --pfs file of yours under it" in err


def test_check_reads_the_labels_before_the_corpus(capsys):
    """A missing labels file had been said after half the corpus's report was printed."""
    from groundlang.corpus import example_corpus_path

    assert main(["check", str(example_corpus_path()), "--palette", "sokoban", "--labels", "no-such-labels.csv"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.strip() == "groundlang check: error: no-such-labels.csv: No such file or directory"


def test_an_environment_that_is_a_device_is_refused_naming_what_may_be_given():
    """follow --env takes a state file too; a device was refused as "expected a corpus file"."""
    from groundlang.corpus import read_initial_state

    with pytest.raises(ValueError, match=r"^/dev/zero: a device, not a regular file; expected a state file "
                                         r"\(\.state, a one-line \.bdm\) or a corpus file$"):
        read_initial_state("/dev/zero", "sokoban")


def test_a_json_result_on_standard_output_is_the_json_alone(tmp_path):
    """--json /dev/stdout had printed the report first, so a reader could not parse what came through."""
    import json
    import subprocess
    import sys

    E = str(example_corpus_path())
    done = subprocess.run([sys.executable, "-m", "groundlang.cli", "evaluate", "--corpus", E, "--palette", "sokoban",
                           "--labels", f"{E}/labels.csv", "--limit", "1", "--json", "/dev/stdout"],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["n"] == 1  # the whole of stdout is the JSON
    assert "result written to /dev/stdout" in done.stderr  # the report went beside it
