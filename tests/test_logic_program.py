"""Loading, checking and grounding ASP programs: errors name file and line, scripts need opt-in."""

from __future__ import annotations

import time

import pytest

from groundlang.logic.program import (
    AspError,
    AspGroundingError,
    AspScriptRefused,
    AspSyntaxError,
    AspTimeout,
    Program,
    Source,
    file_source,
    package_source,
)


def shown(program: Program, facts: str = "") -> set[str]:
    (model,) = program.solve(facts, models=1)
    return {str(s) for s in model}


def test_package_sources_load_with_a_header_comment():
    for name in ("domain.lp", "pfs.lp", "tasks.lp", "groundings.lp"):
        src = package_source(name)
        assert src.name == f"groundlang.logic/{name}"
        assert src.text.lstrip().startswith("%"), name


def test_a_program_grounds_with_facts():
    program = Program((Source("double.lp", "d(Y) :- n(X), Y = 2*X."),))
    assert shown(program, "n(1). n(3).") == {"n(1)", "n(3)", "d(2)", "d(6)"}


def test_solve_enumerates_every_answer_set():
    program = Program((Source("choice.lp", "1 { p(1..3) } 1."),))
    models = program.solve(models=0)
    assert sorted(str(m[0]) for m in models) == ["p(1)", "p(2)", "p(3)"]


def test_syntax_error_names_file_and_line(tmp_path):
    path = tmp_path / "broken.lp"
    path.write_text("a(1).\n% fine\nb(X) :- c(X) d.\n")
    with pytest.raises(AspSyntaxError) as err:
        Program((file_source(path),))
    assert f"{path}:3:" in str(err.value)
    assert "syntax error" in str(err.value) and "error: syntax" not in str(err.value)  # the CLI says "error:" once
    assert isinstance(err.value, ValueError)


def test_syntax_error_in_text_names_the_source_name():
    with pytest.raises(AspSyntaxError, match=r"^mine\.lp:2:"):
        Program((Source("mine.lp", "a.\nb :- .. .\n"),))


def test_unsafe_variable_names_file_line_and_variable():
    program = Program((Source("unsafe.lp", "a(1).\nb(X) :- c(Y).\n"),))
    with pytest.raises(AspGroundingError) as err:
        program.control()
    message = str(err.value)
    assert "unsafe.lp:2:" in message
    assert "unsafe variables" in message
    assert "'X' is unsafe" in message
    assert "\n" not in message


def test_script_is_refused_without_opt_in():
    text = 'a.\n#script (python)\nimport os\nos.system("touch /tmp/groundlang-pwned")\n#end.\n'
    with pytest.raises(AspScriptRefused, match=r"^evil\.lp:2: #script blocks are refused") as refused:
        Program((Source("evil.lp", text),))
    assert "--allow-scripts of tasks and domain" in str(refused.value)  # the option a shell user has


def test_script_passes_the_check_with_opt_in():
    text = '#script (python)\nimport clingo\ndef seven():\n    return clingo.Number(7)\n#end.\nv(@seven()).\n'
    program = Program((Source("ok.lp", text),), allow_scripts=True)
    assert "v(7)" in shown(program)  # the clingo module's Python scripting is off until enabled


def test_an_allowed_script_runs_from_the_command_line_too(tmp_path, capsys):
    """`domain --allow-scripts` said "python support not available" for every script: it could never work."""
    from groundlang.cli import main

    library = tmp_path / "scripted.lp"
    library.write_text('#script (python)\nimport clingo\ndef seven():\n    return clingo.Number(7)\n#end.\n'
                       'pf(size, toyIsSeven, (toy,)).\nholds(toyIsSeven, (T,)) :- toy(T), @seven() = 7.\n')
    assert main(["--quiet", "domain", "--library", "tasks", "--library", str(library)]) == 2
    assert "#script blocks are refused" in capsys.readouterr().err
    assert main(["--quiet", "domain", "--library", "tasks", "--library", str(library), "--allow-scripts"]) == 0
    assert "toyIsSeven" in capsys.readouterr().out


def test_script_word_in_a_comment_or_string_is_fine():
    program = Program((Source("c.lp", '% a #script or #include here is only a comment\nname("#include").\n'),))
    assert shown(program) == {'name("#include")'}


@pytest.mark.parametrize("statement", ["#minimize { 1 : a }.", "#maximize { 1 : a }.", ":~ a. [1@1]"])
def test_an_optimisation_statement_is_refused_naming_its_line(statement):
    """Every answer set of a program is read (a library's groundings, a PF's table); optimisation would keep the
    best alone, and groundings would go missing with no word said."""
    from groundlang.logic.sources import AspSyntaxError

    with pytest.raises(AspSyntaxError, match=r"^opt\.lp:3: an optimisation statement \(#minimize, #maximize or a "
                                             r"weak constraint :~\) is not allowed"):
        Program((Source("opt.lp", f"a.\n{{b}}.\n{statement}\n"),))


def test_include_is_refused(tmp_path):
    with pytest.raises(AspScriptRefused, match=r"^inc\.lp:2: #include is not allowed"):
        Program((Source("inc.lp", 'a.\n#include "other.lp".\n'),))


def test_non_utf8_file_names_file_and_line(tmp_path):
    path = tmp_path / "latin1.lp"
    path.write_bytes(b"a.\nroom(\xe9).\n")
    with pytest.raises(AspSyntaxError, match=r"latin1\.lp:2: not UTF-8"):
        file_source(path)


def test_missing_file_is_an_os_error(tmp_path):
    with pytest.raises(OSError):
        file_source(tmp_path / "absent.lp")


def test_grounding_time_limit_gives_a_clear_error():
    # About 2.7e7 body instances: seconds of grounding, little memory; stopped waiting after 0.1 s.
    program = Program((Source("slow.lp", "d(1..300). q :- d(X), d(Y), d(Z), X+Y+Z < 0."),))
    start = time.perf_counter()
    with pytest.raises(AspTimeout, match=r"grounding slow\.lp did not finish within 0\.1 s"):
        program.control(time_limit=0.1)
    assert time.perf_counter() - start < 1.0


def test_bad_environment_facts_are_reported():
    program = Program((Source("p.lp", "a."),))
    with pytest.raises(AspError, match="facts"):
        program.control("room(.")


def test_isolated_program_gives_the_same_answer_sets():
    source = Source("choice.lp", "1 { p(1..3) } 1. q(\"a b\", (x,)).")
    inside = Program((source,)).solve(models=0)
    child = Program((source,), isolated=True).solve(models=0)
    assert sorted(map(str, map(sorted, inside))) == sorted(map(str, map(sorted, child)))
    assert len(child) == 3


def test_isolated_errors_keep_their_class_and_location():
    program = Program((Source("unsafe.lp", "a(1).\nb(X) :- c(Y).\n"),), isolated=True)
    with pytest.raises(AspGroundingError, match=r"unsafe\.lp:2:.*'X' is unsafe"):
        program.solve()


def test_isolated_infinite_grounding_is_stopped():
    program = Program((Source("forever.lp", "n(1). n(X+1) :- n(X)."),), isolated=True)
    start = time.perf_counter()
    with pytest.raises(AspTimeout, match=r"forever\.lp did not finish within 0\.5 s"):
        program.solve(time_limit=0.5)
    assert time.perf_counter() - start < 5.0


def test_an_isolated_answer_of_too_many_atoms_is_refused_before_the_parent_reads_it():
    """"task(t(1..3000000))." took 2 GB and a minute in the parent, reading the child's reply, past the limit."""
    from groundlang.logic.child_process import MAX_REPLY_ATOMS

    program = Program((Source("many.lp", f"task(t(1..{MAX_REPLY_ATOMS + 1})).\n"),), isolated=True)
    with pytest.raises(AspGroundingError, match=rf"many\.lp: the program shows 1 answer set of {MAX_REPLY_ATOMS + 1:,} "
                                                rf"atoms in all, more than {MAX_REPLY_ATOMS:,} distinct; "
                                                rf"at most {MAX_REPLY_ATOMS:,} distinct"):
        program.solve(models=1)
    assert len(Program((Source("some.lp", f"a(1..{MAX_REPLY_ATOMS})."),), isolated=True).solve(models=1)[0]) \
        == MAX_REPLY_ATOMS
    # in a layout (its facts given): the layout is said to be what is large, not the library's rules
    pairs = Program((Source("pairs.lp", "near(A, B) :- room(A), room(B).\n"),), isolated=True)
    with pytest.raises(AspGroundingError, match=r"pairs\.lp: grounded in this layout it shows 1 answer set of "
                                                r"250,500 atoms in all, more than 200,000 distinct;.*a layout of many rooms"):
        pairs.solve("room(1..500).", models=0)


def test_answer_sets_that_repeat_their_atoms_are_sent_each_atom_once():
    """256 answer sets of a thousand atoms each, the same thousand: 257,000 shown, which a cap on every atom sent
    refused, as it refused a layout's groundings (each answer set repeats the layout's descriptions)."""
    source = Source("repeats.lp", "q(1..1000). { p(1..8) }.\n")
    child = Program((source,), isolated=True).solve(models=0)
    assert len(child) == 256 and sum(map(len, child)) > 200_000
    assert sorted(map(sorted, child)) == sorted(map(sorted, Program((source,)).solve(models=0)))
