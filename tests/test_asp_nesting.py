"""A term nested too deeply for clingo's C++ recursion is refused in one line, never a crash of the process.

clingo parses ``x(f(f(...)))`` 20,000 deep and ``x(1+1+...)`` 100,000 long, but printing the first and freeing
the second end the process (a segfault, no message): library files, palette files and a model's saved library
all went through that parse. The crashing cases run in a child process, so a regression fails the test."""

from __future__ import annotations

import subprocess
import sys

import pytest

from groundlang.corpus import example_corpus_path
from groundlang.logic.sources import MAX_TERM_DEPTH, AspSyntaxError, Source, parse_source

NOVEL_A = example_corpus_path() / "novel_a.state"


def _tasks_with(library, tmp_path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "groundlang", "tasks", str(NOVEL_A), "--palette", "sokoban",
                           "--library", str(library)], capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("text, said", [
    ("% a comment first\nx(" + "f(" * 20000 + "1" + ")" * 20000 + ").\n",
     f":2: a term nested too deeply (more than {MAX_TERM_DEPTH} levels of parentheses)"),
    ("x(" + "1+" * 100000 + "1).\n", ":1: a statement of more than 30000 operators: a term nested too deeply, "
                                      "or too long a statement to parse safely (split it)"),
    ("p(" + "..".join(["1"] * 100000) + ").\n", ":1: a statement of more than 30000 operators"),  # intervals
    ("x(" + "1+" * 5000 + "1).\n", f":1: a term nested too deeply (more than {MAX_TERM_DEPTH} levels"),
])
def test_a_library_too_deep_for_clingo_is_refused_in_one_line(text, said, tmp_path):
    library = tmp_path / "deep.lp"
    library.write_text(text, encoding="ascii")
    run = _tasks_with(library, tmp_path)
    assert run.returncode == 2, run.stderr[-500:]  # 139 had been a segfault
    assert run.stderr.startswith(f"groundlang tasks: error: {library}{said}")
    assert run.stderr.count("\n") == 1 and "Traceback" not in run.stderr


def test_nesting_within_the_limit_is_read_and_beyond_it_is_not():
    """The limit counts the parse's levels (a rule, its head, the atom, ...: a few more than the term's)."""
    within = "x(" + "f(" * (MAX_TERM_DEPTH - 10) + "1" + ")" * (MAX_TERM_DEPTH - 10) + ").\n"
    assert len(parse_source(Source("within.lp", within), allow_scripts=False)) == 2  # #program base and the fact
    beyond = "x(" + "f(" * MAX_TERM_DEPTH + "1" + ")" * MAX_TERM_DEPTH + ").\n"
    with pytest.raises(AspSyntaxError, match=r"^beyond.lp:1: a term nested too deeply"):
        parse_source(Source("beyond.lp", beyond), allow_scripts=False)


def test_long_flat_statements_are_not_taken_for_deep_ones():
    """Pools, intervals, disjunctions, long bodies and many facts are long but flat: each term nests a level or
    two (12,000 operators in one statement had been refused as nested too deeply)."""
    text = ("n(" + ";".join(str(-i) for i in range(20000)) + ").\n"  # 20,000 minus signs in one pool
            "m(1..100000).\n" + "".join(f"p({i}, {i}+1).\n" for i in range(20000))
            + "% " + "(" * 5000 + " in a comment\n" + 'q("' + "(" * 5000 + '").\n')
    statements = parse_source(Source("flat.lp", text), allow_scripts=False)
    assert len(statements) == 1 + 2 + 20000 + 2  # #program base, n, m, the p facts, the comment and q
    flat = ("p(" + ",".join(f"{i}*2" for i in range(12000)) + ").\n"
            + " | ".join(f"a({i})" for i in range(12000)) + ".\n"
            + ":- " + ", ".join(f"not -b({i})" for i in range(12000)) + ".\n")
    assert len(parse_source(Source("flat2.lp", flat), allow_scripts=False)) == 4


def test_a_script_body_is_not_read_as_asp_for_its_nesting():
    """A Python "%" had been blanked as an ASP comment, leaving each "(a % 2)" one parenthesis open."""
    body = "".join("def f(a):\n    return (a % 2)\n" for _ in range(1001))
    text = f"#script (python)\n{body}#end.\np(1).\n"
    statements = parse_source(Source("script.lp", text), allow_scripts=True)
    assert [s.ast_type.name for s in statements][-1] == "Rule" and len(statements) == 3
    unbalanced = "q(" * 3 + ".\n" + "r(" + "f(" * 999 + "1" + ")" * 1000 + ".\n"  # a broken statement's "("
    with pytest.raises(AspSyntaxError, match=r"^unbalanced.lp:1:"):  # a syntax error, not a nesting one
        parse_source(Source("unbalanced.lp", unbalanced), allow_scripts=False)
