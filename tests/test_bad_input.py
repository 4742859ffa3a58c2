"""The bad-input table (issue 9), every row through the CLI (``groundlang.cli.main``).

An error row must give exactly one line on stderr, ``groundlang CMD: error:
...``, naming the input and the problem; exit code 2 (1 for "goal not
reached"); no traceback; and no output file, not even a half-written one.
Rows marked "works" are messy input that must NOT fail: they give an
interpretation and a plan. Also here: the loader is fuzzed (hypothesis) and
the package sources are checked for ways to run code from data (pickle,
``torch.load`` without ``weights_only``, ``np.load`` with pickles allowed).
"""

from __future__ import annotations

import ast
import hashlib
import io
import json
import math
import shutil
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from groundlang.cli import main
from groundlang.corpus import example_corpus_path, read_corpus
from groundlang.learner import Learner
from groundlang.model_io import FORMAT_VERSION, ModelFormatError, signed
from test_corpus import MALFORMED  # the corpus-file rows and their messages, shared with test_corpus

TESTS = Path(__file__).parent
FIXTURES = TESTS / "fixtures"
BAD = FIXTURES / "bad_input"
REPO = TESTS.parent
EXAMPLES = example_corpus_path()
NOVEL = EXAMPLES / "novel_a.state"  # three rooms (green room0, red room1, blue room2), one star
# A 1x1 PNG: "a file swapped for another kind".
PNG = bytes.fromhex(
    "89504e470d0a1a0a0000000d49484452000000010000000108060000001f15c4890000000d4944415478da63f8cf"
    "c0f01f0005000201a1e7b1d40000000049454e44ae426082"
)


@pytest.fixture(scope="session")
def trained_model(tmp_path_factory) -> Path:
    """A model trained once per session on the example corpus (24 instances, about 3 s)."""
    root = tmp_path_factory.mktemp("trained")
    learner = Learner(cache_dir=root / "cache").fit(read_corpus(EXAMPLES, "sokoban").instances)
    return learner.save(root / "model")


# ----------------------------------------------------------------- model directories made bad
def _edit_meta(d: Path, change: Callable[[dict], None]) -> None:
    """Rewrite model.json with ``change`` applied to its contents."""
    meta = json.loads((d / "model.json").read_text())
    change(meta)
    (d / "model.json").write_text(json.dumps(signed(meta)))


def _tensors(d: Path) -> Path:
    """The model's tensor file, globals-<hash>.npz, as its model.json names it."""
    return d / json.loads((d / "model.json").read_text())["globals_file"]


def _rehash(d: Path) -> None:
    """Record the current tensor file's hash in model.json: a hostile file, not an accident."""
    _edit_meta(d, lambda meta: meta.update(globals_sha256=hashlib.sha256(_tensors(d).read_bytes()).hexdigest()))


def _npz(d: Path, **arrays) -> None:
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    _tensors(d).write_bytes(buffer.getvalue())
    _rehash(d)


def _truncate(d: Path) -> None:
    data = _tensors(d).read_bytes()
    _tensors(d).write_bytes(data[: len(data) // 2])


def _set_version(d: Path) -> None:
    _edit_meta(d, lambda meta: meta.update(version=99))


def _drop_vocabulary_tasks(d: Path) -> None:
    _edit_meta(d, lambda meta: (meta["vocabulary"].pop("tasks"), meta["vocabulary"].pop("task_roles")))


def _globals(d: Path) -> dict:
    with np.load(_tensors(d), allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _with(d: Path, drop: str | None = None, **replace) -> None:
    """Rewrite globals.npz from the model's own tensors, replacing or dropping some."""
    arrays = {k: v for k, v in _globals(d).items() if k != drop}
    arrays.update(replace)
    _npz(d, **arrays)


def _phi_shape(d: Path) -> tuple[int, int]:
    with np.load(_tensors(d), allow_pickle=False) as z:
        return z["phi"].shape


MODEL_DIRS: dict[str, tuple[Callable[[Path], None], list[str]]] = {
    "model.json missing": (lambda d: (d / "model.json").unlink(),
                           ["no model.json; this is not a groundlang model directory"]),
    "globals.npz missing": (lambda d: _tensors(d).unlink(), [".npz: the model's tensor file is missing (model.json names it)"]),
    "truncated tensors": (_truncate, [".npz: contents do not match the hash recorded in model.json",
                                      "truncated or swapped?"]),
    "truncated tensors, hash rewritten": (lambda d: (_truncate(d), _rehash(d)),
                                          ["model files are incomplete or corrupt", "BadZipFile"]),
    "JSON from format version 99": (_set_version, ["model.json: model format version 99",
                                                   f"this groundlang reads version {FORMAT_VERSION}", "train the model again"]),
    # the version as text reads as a contradiction unless its type is said; none at all is said so
    "JSON with the version as text": (lambda d: _edit_meta(d, lambda meta: meta.update(version=str(FORMAT_VERSION))),
                                      [f"model format version '{FORMAT_VERSION}' (a str, not a number), this groundlang "
                                       f"reads version {FORMAT_VERSION}"]),
    "JSON with no version": (lambda d: _edit_meta(d, lambda meta: meta.pop("version")),
                             [f"model.json: no model format version, this groundlang reads version {FORMAT_VERSION}"]),
    "globals.npz swapped for a PNG": (lambda d: _tensors(d).write_bytes(PNG),
                                      [".npz: contents do not match the hash"]),
    "globals.npz swapped for a PNG, hash rewritten": (
        lambda d: (_tensors(d).write_bytes(PNG), _rehash(d)),
        [".npz: not an .npz archive (it starts with b'\\x89PNG", "expected the tensors groundlang saved"]),
    "model.json swapped for a PNG": (lambda d: (d / "model.json").write_bytes(PNG),
                                     ["model.json: not valid JSON", "can't decode byte 0x89"]),
    "model.json of another program": (lambda d: (d / "model.json").write_text('{"format": "keras"}'),
                                      ["model.json: not a groundlang model (format field is not 'groundlang-model')"]),
    # edited on purpose and re-signed: each index still names each entry once
    "vocabulary with a word twice": (lambda d: _edit_meta(d, lambda m: m["vocabulary"]["words"].__setitem__(
        2, m["vocabulary"]["words"][1])), ["model files are incomplete or corrupt", "words name each entry once"]),
    "vocabulary with a number for a token": (lambda d: _edit_meta(d, lambda m: m["vocabulary"]["tokens"].append(7)),
                                             ["model files are incomplete or corrupt", "tokens are text; found 7"]),
    "vocabulary with null for a word": (lambda d: _edit_meta(d, lambda m: m["vocabulary"]["words"].__setitem__(2, None)),
                                        ["model files are incomplete or corrupt", "words are text; found None"]),
    "vocabulary without prepositions": (lambda d: _edit_meta(d, lambda m: m["vocabulary"].__setitem__("preps", [])),
                                        ["model files are incomplete or corrupt", "a vocabulary starts with none among "
                                         "roles and <other>, <dobj> among prepositions"]),
    "vocabulary whose task roles name another task": (
        lambda d: _edit_meta(d, lambda m: m["vocabulary"]["task_roles"].__setitem__("flyToMoon", ["none"])),
        ["model files are incomplete or corrupt", "task_roles name 'flyToMoon', which is not one of its tasks"]),
    "vocabulary whose task roles name another role": (
        lambda d: _edit_meta(d, lambda m: next(iter(m["vocabulary"]["task_roles"].values())).append("other:moon")),
        ["model files are incomplete or corrupt", "the role 'other:moon', which is not one of its roles"]),
    "vocabulary aliasing a word to a number": (
        lambda d: _edit_meta(d, lambda m: m["vocabulary"]["aliases"].__setitem__("red", 5)),
        ["model files are incomplete or corrupt", "a vocabulary's aliases map text to text"]),
    "vocabulary naming a token by a list": (
        lambda d: _edit_meta(d, lambda m: m["vocabulary"]["names"].__setitem__("CLASS:door", [1])),
        ["model files are incomplete or corrupt", "a vocabulary's names map text to text"]),
    "vocabulary without its lifted tasks": (_drop_vocabulary_tasks,
                                            ["model files are incomplete or corrupt",
                                             "the vocabulary lacks the lifted tasks ['agentToRoom'"]),
    "tensor of the wrong shape": (lambda d: _with(d, phi=np.ones((3, 4), np.float32)),
                                  [".npz: phi is float32 (3, 4); expected finite floats of shape"]),
    "tensor with NaN": (lambda d: _with(d, phi=np.full(_phi_shape(d), np.nan, np.float32)),
                        [".npz: phi is float32", "expected finite floats"]),
    "tensor missing": (lambda d: _with(d, drop="align"),
                       [".npz: holds [", "language model parse needs [", "'align'"]),
    "pickled object array": (lambda d: _with(d, phi=np.array([{"x": 1}], dtype=object)),
                             [".npz: phi is object (1,); expected finite floats"]),  # refused from its header
    "directory does not exist": (lambda d: shutil.rmtree(d), ["not a model directory (it does not exist"]),
    "a file, not a directory": (lambda d: (shutil.rmtree(d), d.write_text("model")),
                                ["not a model directory (it does not exist or is not a folder)"]),
}


# ----------------------------------------------------------------- the table
@dataclass(frozen=True)
class Row:
    """One bad input: CLI arguments ({model}, {tmp} filled in) and the outcome they must give.

    ``broken`` makes {model} a damaged copy of the session's trained model.
    """

    id: str
    argv: tuple[str, ...]
    code: int = 2
    pieces: tuple[str, ...] = ()  # all in the one stderr line
    absent: tuple[str, ...] = ()  # outputs that must not exist afterwards
    check: Callable[[str], None] | None = None  # for rows that must work: checks stdout
    broken: Callable[[Path], None] | None = None  # turns a copy of the trained model into {broken}
    env: dict = field(default_factory=dict)


def _has(out: str, piece: str) -> None:
    assert piece in out, out


def _follow(command: str, env: Path | str = NOVEL, *extra: str) -> tuple[str, ...]:
    return ("follow", command, "--env", str(env), "--palette", "sokoban", "--model", "{model}", *extra)


def _works(expect_goal_words: tuple[str, ...] = ()) -> Callable[[str], None]:
    """A ``follow --json`` answer with interpretations that sum to at most 1 and a plan that reached its goal."""

    def check(out: str) -> None:
        answer = json.loads(out)
        probs = [i["probability"] for i in answer["interpretations"]]
        assert probs and all(0.0 <= p <= 1.0 for p in probs) and sum(probs) <= 1.0 + 1e-6
        assert probs == sorted(probs, reverse=True)
        assert answer["reached"] is True and answer["reason"] == "goal"
        assert all(a in ("north", "south", "east", "west") for a in answer["actions"])
        for word in expect_goal_words:  # every reading with any weight says it (the tail is noise)
            assert all(word in i["goal"] for i in answer["interpretations"] if i["probability"] > 0.01), \
                answer["interpretations"]

    return check


def _parsed(out: str) -> None:
    answer = json.loads(out)
    assert answer["readings"] and abs(sum(r["probability"] for r in answer["readings"]) - 1.0) < 1e-6
    assert all(r["logical_form"] for r in answer["readings"])


TEN_THOUSAND = " ".join(["take the star to the red room"] * 1428 + ["go", "now"])  # 10,000 words
CONTROL = "go\x00 to the\x07 red\x1b[31m room\r\x7f"
UNICODE = "bring the ☆ to the rouge räum 🚀 ﬁnally, 紅い部屋へ"
UNSEEN = "blorf the zzyzx into quux"


def _asks(unknown: tuple[str, ...]) -> Callable[[str], None]:
    """A ``follow --json`` answer that did not act: it asks, naming the unknown words."""

    def check(out: str) -> None:
        answer = json.loads(out)
        assert answer["abstained"] is True and "actions" not in answer
        assert answer["confidence"] < 0.7 and len(answer["choices"]) >= 2
        assert answer["unknown_words"] == list(unknown)
        assert answer["question"].startswith("I don't know the word")

    return check


ROWS: list[Row] = []

# Corpus files: the messages of tests/test_corpus.py, now seen by a CLI user (show draws the file).
for _name, (_line, _pieces) in sorted(MALFORMED.items()):
    _path = FIXTURES / "malformed" / _name
    ROWS.append(Row(f"corpus/{_name}", ("show", str(_path), "--palette", "sokoban", "--out", "{tmp}/picture.png"),
                    pieces=(f"groundlang show: error: {_path}", *_pieces), absent=("{tmp}/picture.png",)))
ROWS += [
    Row("corpus/no corpus files", ("check", str(FIXTURES / "no_corpus"), "--palette", "sokoban"),
        pieces=(f"{FIXTURES / 'no_corpus'}: no corpus files; expected files like agent2red_0.txt",)),
    Row("corpus/folder does not exist", ("check", str(FIXTURES / "absent"), "--palette", "sokoban"),
        pieces=(f"{FIXTURES / 'absent'}: not a directory",)),
    Row("corpus/train on a folder with no corpus files",
        ("train", str(FIXTURES / "no_corpus"), "--palette", "sokoban", "-o", "{tmp}/model"),
        pieces=("no_corpus: no corpus files",), absent=("{tmp}/model",)),
    Row("corpus/train on a malformed file",
        ("train", str(FIXTURES / "malformed"), "--palette", "sokoban", "-o", "{tmp}/model"),
        pieces=("malformed/", ".txt"), absent=("{tmp}/model",)),
    Row("labels/prefix names no files",
        ("check", str(FIXTURES / "sokoban"), "--palette", "sokoban", "--labels", str(FIXTURES / "labels/unknown_prefix.csv")),
        pieces=("unknown_prefix.csv: prefixes star2blue_ name no files in", "expected every labelled prefix to have corpus files")),
    Row("labels/goal over an object that does not exist",
        ("check", str(FIXTURES / "sokoban"), "--palette", "sokoban", "--labels", str(FIXTURES / "labels/unknown_object.csv")),
        pieces=("unknown_object.csv: goal of 'agent2red_' for", "agentInRoom(agent0, room7) names room7, which does not exist",
                "objects: agent0, room0, room1, door0")),
    Row("labels/evaluate with a goal over a missing object writes no result",
        ("evaluate", "--corpus", str(FIXTURES / "sokoban"), "--palette", "sokoban",
         "--labels", str(FIXTURES / "labels/unknown_object.csv"), "--json", "{tmp}/result.json"),
        pieces=("names room7, which does not exist",), absent=("{tmp}/result.json",)),
]

# Commands.
# follow --guess acts however unsure, as follow did before it could ask (the asking is tested below).
for _via, _argv in (("parse", lambda c: ("parse", c, "--json")),
                    ("follow", lambda c: _follow(c, NOVEL, "--json", "--guess"))):
    ROWS += [
        Row(f"command/{_via}/empty", _argv(""),
            pieces=("cannot parse the command: it is empty or only whitespace",)),
        Row(f"command/{_via}/whitespace only", _argv(" \t\n  "),
            pieces=("cannot parse the command: it is empty or only whitespace",)),
        Row(f"command/{_via}/10,000 words (works)", _argv(TEN_THOUSAND), code=0,
            check=_parsed if _via == "parse" else _works()),
        Row(f"command/{_via}/control characters (works)", _argv(CONTROL), code=0,
            check=_parsed if _via == "parse" else _works(("agentInRoom",))),
        Row(f"command/{_via}/unicode (works)", _argv(UNICODE), code=0,
            check=_parsed if _via == "parse" else _works()),
        Row(f"command/{_via}/words never seen in training (works)", _argv(UNSEEN), code=0,
            check=_parsed if _via == "parse" else _works()),
    ]
ROWS.append(Row("command/follow/words never seen in training, without --guess: asks (exit 3)",
                _follow(UNSEEN, NOVEL, "--json"), code=3, check=_asks(("zzyzx", "quux")),
                pieces=("groundlang follow: not acting: confidence 0.", "below --min-confidence 0.7")))


def _no_toy_tasks(out: str) -> None:
    answer = json.loads(out)
    assert answer["interpretations"], answer
    assert all("toyInRoom" not in i["goal"] and "block" not in i["goal"] for i in answer["interpretations"])
    assert answer["reached"] is True


# Environments.
ROWS += [
    Row("environment/agent walled in: goal not reached",
        _follow("go to the red room", BAD / "walled_in.state", "--out", "{tmp}/picture.png"), code=1,
        pieces=("groundlang follow: goal agentInRoom(agent0, room1) not reached: no state reachable from the start "
                "satisfies it, so no plan can carry it out",)),
    Row("environment/no toy for a toy task: only possible tasks (works)",
        _follow("push the star into the red room", BAD / "no_toy.state", "--json"), code=0, check=_no_toy_tasks),
    Row("environment/state space too large: refused up front",
        _follow("push the star into the red room", BAD / "huge_grid.state", "--out", "{tmp}/picture.png"),
        pieces=(f"{BAD / 'huge_grid.state'}: this layout has 162,793 walkable cells; PFs are tabulated for at most "
                "4,096",),  # by its cells, before its states are counted or it is grounded
        absent=("{tmp}/picture.png",)),
    Row("environment/more blocks than the mention model sums over: refused before it doubles per block",
        _follow("push the star into the red room", BAD / "many_blocks.state", "--out", "{tmp}/picture.png"),
        pieces=("20 objects a command could name in one layout", "reads at most 16"),
        absent=("{tmp}/picture.png",)),
    Row("environment/limit lowered with GROUNDLANG_MAX_STATES: the relevance abstraction plans (works)",
        _follow("go to the red room", NOVEL), env={"GROUNDLANG_MAX_STATES": "1000"}, code=0,
        check=lambda out: _has(out, "reached (goal)")),
    Row("environment/limit lowered below the agent's cells",
        _follow("go to the red room", NOVEL), env={"GROUNDLANG_MAX_STATES": "50"},
        pieces=("even the agent alone could reach 86 cells here, more than max_states=50",
                "set GROUNDLANG_MAX_STATES=86")),
    Row("environment/GROUNDLANG_MAX_STATES not a number",
        _follow("go to the red room", NOVEL), env={"GROUNDLANG_MAX_STATES": "lots"},
        pieces=("GROUNDLANG_MAX_STATES='lots': expected a positive integer",)),
    Row("environment/GROUNDLANG_MAX_STATES not a number, said before a corpus is read (demo had checked one first)",
        ("check", str(NOVEL.parent), "--palette", "sokoban"), env={"GROUNDLANG_MAX_STATES": "lots"},
        pieces=("groundlang check: error: GROUNDLANG_MAX_STATES='lots': expected a positive integer",)),
]

# ASP task libraries (user files are solved in a child process, killed at the limit).
_TASKS = ("tasks", str(FIXTURES / "small.state"), "--palette", "sokoban", "--library")
ROWS += [
    Row("asp/syntax error", (*_TASKS, str(BAD / "syntax_error.lp")),
        pieces=(f"{BAD / 'syntax_error.lp'}:3:", "syntax error, unexpected <VARIABLE>")),
    Row("asp/unsafe variable", (*_TASKS, str(BAD / "unsafe.lp")),
        pieces=(f"{BAD / 'unsafe.lp'}:3:", "unsafe variables in: bad(X)", "'X' is unsafe")),
    Row("asp/non-ASCII name (clingo would abort)", (*_TASKS, str(BAD / "non_ascii.lp")),
        pieces=(f"{BAD / 'non_ascii.lp'}:3:58: unexpected character 'é'", "names and operators are ASCII")),
    Row("asp/a NUL byte (clingo would read no further, and silently)", (*_TASKS, str(BAD / "nul_byte.lp")),
        pieces=(f"{BAD / 'nul_byte.lp'}:2: a NUL byte; ASP text has none",)),
    Row("asp/a term nested deeper than a Python walk goes (1+1+...+1)", (*_TASKS, str(BAD / "nested_too_deeply.lp")),
        pieces=(f"{BAD / 'nested_too_deeply.lp'}:2: a term nested too deeply",)),
    Row("asp/#script refused without opt-in", (*_TASKS, str(BAD / "script.lp")),
        pieces=(f"{BAD / 'script.lp'}:2: #script blocks are refused",)),
    Row("asp/goal PF nobody declared", (*_TASKS, str(BAD / "unknown_goal_pf.lp")),
        pieces=(f"{BAD / 'unknown_goal_pf.lp'}: task t: goal agentFliesTo is not a declared PF of a goal class (position)",
                "no plan can make it true", "agentInRoom")),
    Row("asp/goal over a variable of another class", (*_TASKS, str(BAD / "goal_wrong_class.lp")),
        pieces=("task t: goal agentInRoom(A, R) needs arguments of classes ('agent', 'room')",
                "the task's var/3 give (A: toy, R: room)")),
    Row("asp/PF over a class no object has", (*_TASKS, str(BAD / "pf_of_no_class.lp")),
        pieces=(f"{BAD / 'pf_of_no_class.lp'} (palette sokoban): PF toyHue(", "is declared over class lamp, "
                "which no object has")),
    Row("asp/holds/2 rule with another arity than the PF's declaration", (*_TASKS, str(BAD / "holds_other_arity.lp")),
        pieces=(f"{BAD / 'holds_other_arity.lp'}: holds(agentNear, ...) has 2 arguments where pf/3 declares "
                "agentNear with 1",)),
    Row("asp/a PF declared with two arities (a library redeclaring one of pfs.lp)",
        (*_TASKS, str(BAD / "pf_two_arities.lp")),
        pieces=("PF agentInRoom is declared as pf(position, agentInRoom, (agent, room)) in groundlang.logic/pfs.lp and "
                f"as pf(position, agentInRoom, (agent,)) in {BAD / 'pf_two_arities.lp'}",)),
    Row("asp/colour PF of two arguments, through discover --pfs",
        ("discover", str(FIXTURES / "sokoban"), "--palette", "sokoban", "--restrict",
         "--pfs", str(BAD / "colour_pf_binary.lp"), "-o", "{tmp}/x.lp"),
        pieces=("colour PF sameColour takes more than one argument",), absent=("{tmp}/x.lp",)),
    Row("asp/goal on a colour PF (never changes)", (*_TASKS, str(BAD / "colour_goal.lp")),
        pieces=(f"{BAD / 'colour_goal.lp'}: task t: goal roomIsRed is not a declared PF of a goal class (position)",)),
    Row("asp/train with a library of no task",
        ("train", str(FIXTURES / "sokoban"), "--palette", "sokoban", "--library", str(BAD / "no_tasks.lp"),
         "-o", "{tmp}/model"),
        pieces=(f"{BAD / 'no_tasks.lp'}: the task library declares no task/1",), absent=("{tmp}/model",)),
    Row("asp/never finishes grounding", (*_TASKS, str(BAD / "never_grounds.lp"), "--time-limit", "1"),
        pieces=("never_grounds.lp", "did not finish within 1 s", "grounds too many atoms: infinitely many")),
]

# Output paths: refused before the work, naming the option (before, a folder given to --json lost a whole
# evaluation at the end, naming a temporary file; demo trained and planned before refusing a .txt picture).
_SMALL = FIXTURES / "small.state"  # a file, so nothing can be written below it
ROWS += [
    Row("output/evaluate --json a folder",
        ("evaluate", "--corpus", str(FIXTURES / "sokoban"), "--palette", "sokoban",
         "--labels", str(FIXTURES / "sokoban" / "labels.csv"), "--json", "{tmp}"),
        pieces=("--json {tmp}: is a folder; expected the path of a file to write",)),
    Row("output/evaluate --json below a file",
        ("evaluate", "--corpus", str(FIXTURES / "sokoban"), "--palette", "sokoban",
         "--labels", str(FIXTURES / "sokoban" / "labels.csv"), "--json", f"{_SMALL}/r.json"),
        pieces=(f"--json {_SMALL}/r.json: {_SMALL} is a file, not a folder",)),
    Row("output/demo picture format", ("demo", "--out", "{tmp}/demo.txt"),
        pieces=("{tmp}/demo.txt: picture format 'txt' is not supported; expected .png, .svg or .pdf",),
        absent=("{tmp}/demo.txt",)),
    Row("output/show picture in a folder", ("show", str(_SMALL), "--palette", "sokoban", "--out", "{tmp}"),
        pieces=("--out {tmp}: is a folder",)),
    Row("output/ablate plot in a format no picture has",
        ("ablate", "--corpus", str(FIXTURES / "sokoban"), "--palette", "sokoban",
         "--labels", str(FIXTURES / "sokoban" / "labels.csv"), "--plot", "{tmp}/p.txt"),
        pieces=("{tmp}/p.txt: picture format 'txt' is not supported; expected .png, .svg or .pdf",),
        absent=("{tmp}/p.txt",)),
    Row("output/discover library below a file",
        ("discover", str(FIXTURES / "sokoban"), "--palette", "sokoban", "-o", f"{_SMALL}/x.lp"),
        pieces=(f"-o {_SMALL}/x.lp: {_SMALL} is a file, not a folder",)),
    Row("output/train model below a file",
        ("train", str(FIXTURES / "sokoban"), "--palette", "sokoban", "-o", f"{_SMALL}/m"),
        pieces=(f"-o {_SMALL}/m: {_SMALL} is a file, not a folder; a model is written to a folder",)),
]

ROWS.append(Row("input/discover --cache-dir a file",
                ("discover", str(FIXTURES / "sokoban"), "--palette", "sokoban", "-o", "{tmp}/x.lp",
                 "--cache-dir", str(_SMALL)),
                pieces=(f"the cache folder {_SMALL}: it is a file, not a folder",), absent=("{tmp}/x.lp",)))
ROWS.append(Row("input/GROUNDLANG_CACHE a file",
                ("train", str(FIXTURES / "sokoban"), "--palette", "sokoban", "-o", "{tmp}/model"),
                env={"GROUNDLANG_CACHE": str(_SMALL)},
                pieces=(f"GROUNDLANG_CACHE {_SMALL}: it is a file, not a folder",), absent=("{tmp}/model",)))
_WILLIAMS_SMALL = FIXTURES / "williams2018" / "small.bdm"
ROWS += [
    Row("input/train .bdm with a setting the model lacks refused before the evidence",
        ("train", str(_WILLIAMS_SMALL), "-o", "{tmp}/model", "--cache-dir", "{tmp}/cache", "--lm-setting",
         "held_parts=maybe"),
        pieces=("held_parts",), absent=("{tmp}/model", "{tmp}/cache")),
    Row("input/train with a setting nested 3000 deep (the JSON decoder recursed out)",
        ("train", str(_WILLIAMS_SMALL), "-o", "{tmp}/model", "--lm-setting", "x=" + "[" * 3000),
        pieces=("--lm-setting x=[[[[[[[[[[[[[[[[[[[[...: nested too deeply to be a setting",),
        absent=("{tmp}/model",)),
    Row("input/train --no-cache with --cache-dir",
        ("train", str(_WILLIAMS_SMALL), "-o", "{tmp}/model", "--no-cache", "--cache-dir", "{tmp}/cache"),
        pieces=("--no-cache and --cache-dir {tmp}/cache: choose one",), absent=("{tmp}/model", "{tmp}/cache")),
    Row("input/train an empty --cache-dir",
        ("train", str(_WILLIAMS_SMALL), "-o", "{tmp}/model", "--cache-dir", ""),
        pieces=("--cache-dir: empty; name a folder",), absent=("{tmp}/model",)),
    # the run had trained to the end, then been refused its save: the folder held the cache too
    Row("input/train a --cache-dir inside the model folder",
        ("train", str(_WILLIAMS_SMALL), "-o", "{tmp}/model", "--cache-dir", "{tmp}/model/cache"),
        pieces=("--cache-dir {tmp}/model/cache: inside the model folder -o {tmp}/model",), absent=("{tmp}/model",)),
    Row("input/train GROUNDLANG_CACHE inside the model folder",
        ("train", str(_WILLIAMS_SMALL), "-o", "{tmp}/model"), env={"GROUNDLANG_CACHE": "{tmp}/model"},
        pieces=("GROUNDLANG_CACHE {tmp}/model: inside the model folder -o {tmp}/model",), absent=("{tmp}/model",)),
    # discover had written its cache into the working folder, and taken both options silently
    Row("input/discover an empty --cache-dir",
        ("discover", str(FIXTURES / "sokoban"), "--palette", "sokoban", "-o", "{tmp}/x.lp", "--cache-dir", ""),
        pieces=("--cache-dir: empty; name a folder",), absent=("{tmp}/x.lp",)),
    Row("input/discover --no-cache with --cache-dir",
        ("discover", str(FIXTURES / "sokoban"), "--palette", "sokoban", "-o", "{tmp}/x.lp", "--no-cache",
         "--cache-dir", "{tmp}/c"),
        pieces=("--no-cache and --cache-dir {tmp}/c: choose one",), absent=("{tmp}/x.lp", "{tmp}/c")),
]
ROWS.append(Row("input/train on a .bdm whose only layout is too large to tabulate: every pair skipped, counted",
                ("train", str(BAD / "too_large_to_tabulate.bdm"), "-o", "{tmp}/m"),
                pieces=("too_large_to_tabulate.bdm: no usable training pair (every pair was skipped: 3 too large to "
                        "tabulate)",), absent=("{tmp}/m",)))
ROWS.append(Row("input/evaluate trained on a .bdm whose only layout is too large to tabulate",
                ("evaluate", "--corpus", str(BAD / "too_large_to_tabulate.bdm"), "--test",
                 str(FIXTURES / "williams2018" / "small.bdm")),
                pieces=("no usable training pair (every pair was skipped: 3 too large to tabulate)",)))
ROWS.append(Row("input/a task library that does not exist", (*_TASKS, "{tmp}/nope.lp"),
                pieces=("groundlang tasks: error: {tmp}/nope.lp: No such file or directory",)))
ROWS.append(Row("input/a folder where a state file is expected", ("tasks", str(FIXTURES), "--palette", "sokoban"),
                pieces=(f"groundlang tasks: error: {FIXTURES}: a folder, not a regular file; expected a state file",)))
ROWS.append(Row("input/irl given a .bdm file of pairs", ("irl", str(FIXTURES / "williams2018" / "small.bdm"), "--palette",
                                                        "williams2018"),
                pieces=("small.bdm: a .bdm file holds (start, end) pairs, no moves; expected a commands-to-tasks file",)))
ROWS.append(Row("input/a folder where follow's --env state is expected",
                ("follow", "--model", "{model}", "go to the red room", "--env", str(FIXTURES)),
                pieces=(f"groundlang follow: error: {FIXTURES}: a folder, not a regular file; expected a state file",)))
# Without --palette too: what is wrong with the path comes before asking for a palette it would not need.
ROWS.append(Row("input/a folder named like a state file, no palette", ("show", "{tmp}"),
                pieces=("groundlang show: error: {tmp}: a folder, not a regular file",)))

ROWS.append(Row("input/evaluate --novel-envs folder missing",
                ("evaluate", "--corpus", str(FIXTURES / "sokoban"), "--palette", "sokoban",
                 "--labels", str(FIXTURES / "sokoban" / "labels.csv"), "--novel-envs", "{tmp}/absent"),
                pieces=("--novel-envs {tmp}/absent: not a folder (it does not exist or is a file)",)))

ROWS.append(Row("input/a bare --library name the package does not ship", (*_TASKS, "taskz"),
                pieces=("groundlang tasks: error: taskz: no such file, nor a library the package ships (tasks, "
                        "williams2018)",)))

ROWS.append(Row("model/every table zeros (finite, but no distribution): refused at load, never acts",
                _follow("go to the red room", NOVEL, "--out", "{tmp}/picture.png"),
                pieces=("groundlang follow: error: {model}/globals-", ": row 0 sums to 0; each row must be a distribution"),
                broken=lambda d: _with(d, **{k: np.zeros_like(v) for k, v in _globals(d).items()}),
                absent=("{tmp}/picture.png",)))

# Model directories, through follow and lexicon.
for _case, (_make, _pieces) in MODEL_DIRS.items():
    ROWS += [
        Row(f"model/{_case}/follow", _follow("go to the red room", NOVEL, "--out", "{tmp}/picture.png"),
            pieces=("groundlang follow: error: {model}", *_pieces), broken=_make, absent=("{tmp}/picture.png",)),
        Row(f"model/{_case}/lexicon", ("lexicon", "{model}"),
            pieces=("groundlang lexicon: error: {model}", *_pieces), broken=_make),
    ]


def _fill(text: str, values: dict) -> str:
    for key, value in values.items():
        text = text.replace("{" + key + "}", str(value))
    return text


@pytest.mark.parametrize("row", ROWS, ids=[r.id for r in ROWS])
def test_bad_input(row: Row, capsys, tmp_path, trained_model, monkeypatch):
    monkeypatch.setenv("GROUNDLANG_CACHE", str(tmp_path / "cache"))
    for key, value in row.env.items():
        monkeypatch.setenv(key, value.replace("{tmp}", str(tmp_path)))
    values = {"model": trained_model, "tmp": tmp_path}
    if row.broken is not None:
        values["model"] = tmp_path / "broken-model"
        shutil.copytree(trained_model, values["model"])
        row.broken(values["model"])
    argv = [_fill(a, values) for a in row.argv]
    code = main(["--quiet", *argv])
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    assert code == row.code, (out, err)
    if row.code != 0:
        lines = err.splitlines()
        assert len(lines) == 1, err
        assert lines[0].startswith(f"groundlang {argv[0]}: ")
        for piece in row.pieces:
            assert _fill(piece, values) in lines[0]
        if row.check is not None:  # a refusal that still answers on stdout (follow asking, exit 3)
            row.check(out)
    else:
        assert err == ""
        row.check(out)
    for path in row.absent:
        assert not Path(_fill(path, values)).exists()
    # no temporary files left behind by atomic writes
    assert [p for p in tmp_path.rglob(".*") if p.is_file()] == []


def test_every_bad_input_fixture_is_used():
    used = " ".join(" ".join(r.argv) for r in ROWS)
    assert sorted(p.name for p in BAD.iterdir() if p.name not in used) == []


@pytest.mark.parametrize("argv, option, read", [
    (("evaluate", "--corpus", "{tmp}/small.bdm", "--holdout", "0.5", "--json", "{tmp}/small.bdm"),
     "--json {tmp}/small.bdm", "--corpus {tmp}/small.bdm"),
    (("evaluate", "--corpus", "{tmp}/small.bdm", "--test", "{tmp}/test.bdm", "--json", "{tmp}/test.bdm"),
     "--json {tmp}/test.bdm", "--test {tmp}/test.bdm"),
    (("evaluate", "--corpus", "{tmp}/ex", "--palette", "sokoban", "--labels", "{tmp}/ex/labels.csv", "--json",
      "{tmp}/ex/labels.csv"), "--json {tmp}/ex/labels.csv", "--corpus {tmp}/ex"),
    (("discover", "{tmp}/ex", "--palette", "sokoban", "-o", "{tmp}/ex/agent2blue_0.txt"),
     "-o {tmp}/ex/agent2blue_0.txt", "directory {tmp}/ex"),
    (("evaluate", "--corpus", "{tmp}/small.bdm", "--holdout", "0.5", "--json", "{tmp}/link.json"),
     "--json {tmp}/link.json", "--corpus {tmp}/small.bdm"),  # a link to the corpus is the corpus
])
def test_an_output_that_is_one_of_the_inputs_is_refused_before_any_work(tmp_path, capsys, argv, option, read):
    """``evaluate --corpus c.bdm --json c.bdm`` replaced the corpus with its own result, and ``discover ex -o
    ex/agent2blue_0.txt`` a corpus file with a library."""
    shutil.copy(FIXTURES / "williams2018" / "small.bdm", tmp_path / "small.bdm")
    shutil.copy(FIXTURES / "williams2018" / "small.bdm", tmp_path / "test.bdm")
    shutil.copytree(EXAMPLES, tmp_path / "ex")
    (tmp_path / "link.json").symlink_to(tmp_path / "small.bdm")
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    assert main([a.format(tmp=tmp_path) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert f"{option.format(tmp=tmp_path)}: the command reads it ({read.format(tmp=tmp_path)})" in err, err
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before


def test_script_did_not_run(tmp_path):
    """The refused #script block would have created this file."""
    assert not Path("/tmp/groundlang-pwned").exists()


@pytest.mark.slow
def test_errors_through_the_real_executable(tmp_path, trained_model):
    """Two rows in a fresh interpreter: what a user at a shell sees (exit code, one line, no traceback)."""
    import subprocess

    cases = [
        (["show", str(FIXTURES / "malformed/non_utf8.txt"), "--palette", "sokoban"], 2,
         "non_utf8.txt, line 1: byte 0xe9 at offset 11 is not UTF-8"),
        (["lexicon", str(tmp_path / "absent")], 2, "not a model directory"),
    ]
    for argv, code, piece in cases:
        done = subprocess.run([sys.executable, "-m", "groundlang.cli", *argv], capture_output=True, text=True,
                              env={"PATH": "/usr/bin:/bin", "GROUNDLANG_CACHE": str(tmp_path / "cache")}, timeout=60)
        assert done.returncode == code
        assert "Traceback" not in done.stderr
        assert len(done.stderr.splitlines()) == 1 and piece in done.stderr


# ----------------------------------------------------------------- no code execution from data
PACKAGE_DIRS = ["groundlang", "logic", "model", "inference", "grammar"]
UNSAFE_MODULES = {"pickle", "cPickle", "dill", "cloudpickle", "shelve", "marshal", "joblib"}


def _calls(tree: ast.AST):
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            yield node


def _dotted(node: ast.AST) -> str:
    if isinstance(node, ast.Attribute):
        return f"{_dotted(node.value)}.{node.attr}"
    return node.id if isinstance(node, ast.Name) else ""


def _keyword(call: ast.Call, name: str):
    for kw in call.keywords:
        if kw.arg == name and isinstance(kw.value, ast.Constant):
            return kw.value.value
    return None


def test_no_code_execution_from_data():
    problems = []
    files = [p for d in PACKAGE_DIRS for p in (REPO / d).rglob("*.py")]
    assert len(files) > 30
    for path in files:
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        where = path.relative_to(REPO)
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names = [a.name.split(".")[0] for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [(node.module or "").split(".")[0]]
            else:
                continue
            for name in set(names) & UNSAFE_MODULES:
                problems.append(f"{where}:{node.lineno}: imports {name}")
        for call in _calls(tree):
            name = _dotted(call.func)
            if name in ("np.load", "numpy.load") and _keyword(call, "allow_pickle") is not False:
                problems.append(f"{where}:{call.lineno}: {name} without allow_pickle=False")
            if name == "torch.load" and _keyword(call, "weights_only") is not True:
                problems.append(f"{where}:{call.lineno}: torch.load without weights_only=True")
            if name in ("eval", "exec"):
                problems.append(f"{where}:{call.lineno}: {name}()")
    assert problems == []


def test_the_source_check_catches_offenders(tmp_path):
    """The checker above is not vacuous: it flags each pattern it is meant to flag."""
    source = "import pickle\nimport numpy as np, torch\nnp.load(f)\nnp.load(f, allow_pickle=True)\ntorch.load(f)\n"
    tree = ast.parse(source)
    flagged = [_dotted(c.func) for c in _calls(tree)
               if (_dotted(c.func) == "np.load" and _keyword(c, "allow_pickle") is not False)
               or (_dotted(c.func) == "torch.load" and _keyword(c, "weights_only") is not True)]
    assert flagged == ["np.load", "np.load", "torch.load"]


# ----------------------------------------------------------------- fuzzing the model loader
FUZZ = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def _fresh_copy(trained_model: Path, tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("fuzz") / "model"
    shutil.copytree(trained_model, d)
    return d


def _loads_or_refuses(d: Path) -> None:
    try:
        learner = Learner.load(d)
    except ModelFormatError as exc:
        assert "\n" not in str(exc)
        assert str(exc).startswith(str(d))
    else:  # whatever loads must be usable
        assert learner.lexicon(top=1)


@FUZZ
@given(data=st.binary(max_size=400))
def test_fuzz_model_json_bytes(trained_model, tmp_path_factory, data):
    d = _fresh_copy(trained_model, tmp_path_factory)
    (d / "model.json").write_bytes(data)
    _loads_or_refuses(d)


@pytest.mark.slow
@FUZZ
@given(data=st.one_of(
    st.binary(max_size=400),
    st.binary(max_size=400).map(lambda b: b"PK\x03\x04" + b),
    st.tuples(st.integers(0, 4000), st.integers(0, 4000), st.binary(max_size=8)),
))
def test_fuzz_globals_npz_bytes(trained_model, tmp_path_factory, data):
    """Random bytes and damaged copies of the real archive, with the hash rewritten to match (hostile)."""
    d = _fresh_copy(trained_model, tmp_path_factory)
    if isinstance(data, tuple):
        good = _tensors(d).read_bytes()
        start, stop, insert = data
        start, stop = sorted((start % (len(good) + 1), stop % (len(good) + 1)))
        data = good[:start] + insert + good[stop:]
    _tensors(d).write_bytes(data)
    _rehash(d)
    _loads_or_refuses(d)


_JSON = st.recursive(
    st.none() | st.booleans() | st.integers(-3, 10**6) | st.floats(allow_nan=True) | st.text(max_size=12),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=8), children, max_size=4),
    max_leaves=12,
)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(key=st.sampled_from(["format", "version", "language_model", "language_model_settings", "vocabulary",
                            "task_library", "planning", "training", "globals_sha256", "lexicon",
                            "end_habits"]),
       value=_JSON, drop=st.booleans())
def test_fuzz_model_json_fields(trained_model, tmp_path_factory, key, value, drop):
    """One field of a real model.json replaced by arbitrary JSON, or removed."""
    d = _fresh_copy(trained_model, tmp_path_factory)
    meta = json.loads((d / "model.json").read_text())
    if drop:
        meta.pop(key)
    else:
        meta[key] = value
    (d / "model.json").write_text(json.dumps(signed(meta)))
    _loads_or_refuses(d)


@pytest.mark.parametrize("key, value, expected", [
    ("language_model_settings", [1, 2], "list, expected names with values"),
    ("training", [1, 2], "list, expected names with values"),
    ("planning", [1, 2], "list, expected names with values"),
    ("vocabulary", "words", "str, expected names with values"),
    ("language_model", ["parse"], "list, expected a name"),
    ("task_library", 3, "int, expected the text of an ASP program"),
])
def test_a_model_json_section_of_the_wrong_kind_is_named(trained_model, tmp_path_factory, key, value, expected):
    d = _fresh_copy(trained_model, tmp_path_factory)
    meta = json.loads((d / "model.json").read_text())
    meta[key] = value
    (d / "model.json").write_text(json.dumps(signed(meta)))
    with pytest.raises(ModelFormatError, match=f"{key} is {expected}"):
        Learner.load(d)


@pytest.mark.parametrize("argv, message", [
    (("tasks", str(NOVEL), "--palette", "sokoban", "--time-limit", "inf"),
     "argument --time-limit: expected seconds above 0 and at most 1000000, not 'inf'"),
    (("tasks", str(NOVEL), "--palette", "sokoban", "--time-limit", "0"),
     "argument --time-limit: expected seconds above 0 and at most 1000000, not '0'"),
    (("evaluate", "--corpus", str(FIXTURES / "sokoban"), "--palette", "sokoban", "--labels", "x.csv", "--workers", "0"),
     "argument --workers: expected a whole number of 1 or more, not '0'"),
    (("evaluate", "--corpus", str(FIXTURES / "sokoban"), "--palette", "sokoban", "--labels", "x.csv", "--limit", "-1"),
     "argument --limit: expected a whole number of 1 or more, not '-1'"),
    (("train", str(FIXTURES / "sokoban"), "--palette", "sokoban", "-o", "m", "--seed", "-1"),
     "argument --seed: expected a seed from 0 to 4294967295, not '-1'"),
    (("train", str(FIXTURES / "sokoban"), "--palette", "sokoban", "-o", "m", "--seed", "99999999999999999999"),
     "argument --seed: expected a seed from 0 to 4294967295, not '99999999999999999999'"),
    (("follow", "go", "--env", str(NOVEL), "--palette", "sokoban", "--model", "m", "--top", "0"),
     "argument --top: expected a whole number of 1 or more, not '0'"),
    (("follow", "go", "--env", str(NOVEL), "--palette", "sokoban", "--model", "m", "--max-steps", "-1"),
     "argument --max-steps: expected a whole number of 1 or more, not '-1'"),
    (("discover", str(FIXTURES / "sokoban"), "--palette", "sokoban", "-o", "x.lp", "--weight-margin", "2"),
     "argument --weight-margin: expected a number from 0 to 1, not '2'"),
    # each list option's message gives an example of its own, and --folds the least it takes
    (("ablate", "--corpus", "x", "--palette", "sokoban", "--sizes", ","),
     "argument --sizes: expected a comma-separated list, e.g. 24,60,120,240"),
    (("ablate", "--corpus", "x", "--palette", "sokoban", "--libraries", ","),
     "argument --libraries: expected a comma-separated list, e.g. authored,discovered"),
    (("ablate", "--corpus", "x", "--palette", "sokoban", "--folds", "0"),
     "argument --folds: expected a whole number of 2 or more, not '0'"),
])
def test_numeric_options_out_of_range_are_refused_by_name(argv, message, capsys):
    """Before, --time-limit inf crashed clingo (exit 134), --limit -1 scored all but one instance and --top 0
    printed every word as unknown."""
    with pytest.raises(SystemExit) as exit_info:
        main(["--quiet", *argv])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    # one line, as every bad input is: argparse's usage block is for --help
    assert err == f"groundlang {argv[0]}: error: {message} (see groundlang {argv[0]} --help)\n"


@pytest.mark.parametrize("limit", [math.inf, math.nan, 0, -1.0, 1e12, True, "5"])
def test_a_time_limit_that_is_no_number_of_seconds_is_refused(limit):
    from groundlang.logic.program import Program, Source

    program = Program((Source("t.lp", "a."),))
    for run in (program.solve, program.control):
        with pytest.raises(ValueError, match="time_limit must be seconds above 0 and at most 1000000"):
            run(time_limit=limit)


def test_an_unwritable_result_path_is_refused_before_the_evaluation_runs(tmp_path, capsys, monkeypatch):
    import groundlang.evaluation

    monkeypatch.setattr(groundlang.evaluation, "evaluate", lambda *a, **k: pytest.fail("evaluated first"))
    code = main(["--quiet", "evaluate", "--corpus", str(FIXTURES / "sokoban"), "--palette", "sokoban",
                 "--labels", str(FIXTURES / "sokoban" / "labels.csv"), "--json", str(tmp_path)])
    assert code == 2
    assert f"--json {tmp_path}: is a folder" in capsys.readouterr().err


_WILLIAMS_CORPUS = ("--corpus", str(_WILLIAMS_SMALL), "--test", str(_WILLIAMS_SMALL))


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs /proc, where no file can be created")
@pytest.mark.parametrize("argv, work, said", [
    (("evaluate", *_WILLIAMS_CORPUS, "--json", "/proc/x.json"), "groundlang.pair_evaluation.evaluate_pairs",
     "--json /proc/x.json: cannot create a file in /proc"),
    (("evaluate", "--corpus", str(FIXTURES / "sokoban"), "--palette", "sokoban", "--labels",
      str(FIXTURES / "sokoban" / "labels.csv"), "--json", "/proc/new/x.json"), "groundlang.evaluation.evaluate",
     "--json /proc/new/x.json: cannot create a file in /proc"),
    (("train", str(_WILLIAMS_SMALL), "--no-cache", "-o", "/proc/m"), "groundlang.learner.Learner.fit",
     "-o /proc/m: cannot create a file in /proc"),
    (("discover", str(FIXTURES / "sokoban"), "--palette", "sokoban", "-o", "/proc/x.lp"),
     "groundlang.inference.discovery.discover_tasks", "-o /proc/x.lp: cannot create a file in /proc"),
    (("show", str(_SMALL), "--palette", "sokoban", "--out", "/proc/x.png"), "groundlang.render.save_picture",
     "--out /proc/x.png: cannot create a file in /proc"),
])
def test_an_output_no_file_can_be_created_in_is_refused_before_the_work(argv, work, said, capsys, monkeypatch):
    """Before, /proc/x.json passed the check: the whole evaluation (or training) ran, then the write failed,
    and show named its temporary file (/proc/.x.png.7a3e....tmp)."""
    monkeypatch.setattr(work, lambda *a, **k: pytest.fail(f"{work} ran before the output was checked"))
    code = main(["--quiet", *argv])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.startswith(f"groundlang {argv[0]}: error: {said} (") and len(err.splitlines()) == 1, err
    assert ".tmp" not in err


@pytest.mark.parametrize("argv, said", [
    (("demo", "--language-model", "xyz"), "argument --language-model: invalid choice: 'xyz' (choose from 'bow', "
                                          "'ibm2', 'parse')"),
    (("demo", "--command", ""), "--command: the command is empty or only whitespace; expected the command's words"),
    (("demo", "--command", "?!"), "--command: the command has no word, only punctuation ('?!')"),
])
def test_demo_refuses_a_bad_command_or_language_model_before_the_work(argv, said, capsys, monkeypatch, tmp_path):
    """Both had been refused only after the corpus check and the training."""
    for work in ("groundlang.corpus.read_corpus", "groundlang.learner.Learner.fit"):
        monkeypatch.setattr(work, lambda *a, work=work, **k: pytest.fail(f"{work} ran before the options were checked"))
    try:
        code = main(["--quiet", *argv, "--out", str(tmp_path / "demo.png")])
    except SystemExit as stopped:  # how argparse refuses an option's value
        code = stopped.code
    err = capsys.readouterr().err
    assert code == 2 and len(err.splitlines()) == 1 and said in err, err


@pytest.mark.parametrize("isolated", [False, True])
def test_numpy_and_fraction_time_limits_are_seconds_too(isolated):
    from fractions import Fraction

    from groundlang.logic.program import Program, Source

    program = Program((Source("t.lp", "a."),), isolated=isolated)
    for limit in (np.int64(5), np.float32(5), Fraction(5)):
        assert [[str(a) for a in m] for m in program.solve(time_limit=limit)] == [["a"]]


def test_operating_system_errors_read_path_and_reason():
    import errno

    from groundlang.cli import _said

    assert _said(FileNotFoundError(errno.ENOENT, "No such file or directory", "x.lp")) == (
        "x.lp: No such file or directory")
    # a failed rename of a temporary file names the target the user asked for
    assert _said(IsADirectoryError(errno.EISDIR, "Is a directory", "out/.r.json.1a2b.tmp", None, "out/r.json")) == (
        "out/r.json: Is a directory")
    assert _said(FileExistsError("out: no free temporary name for r.json in 100 tries")) == (
        "out: no free temporary name for r.json in 100 tries")  # our own message, kept


@pytest.mark.parametrize("command", ["show", "tasks"])
def test_a_state_file_that_is_a_symbolic_link_loop_is_said_to_loop(command, tmp_path, capsys):
    loop = tmp_path / "loop.bdm"
    loop.symlink_to(loop)
    assert main(["--quiet", command, str(loop)]) == 2
    assert capsys.readouterr().err == f"groundlang {command}: error: {loop}: Too many levels of symbolic links\n"


@pytest.mark.parametrize("command", [["domain"], ["tasks", str(example_corpus_path() / "novel_a.state"),
                                                   "--palette", "sokoban"]])
def test_a_library_that_is_a_symbolic_link_loop_is_said_to_loop(command, tmp_path, capsys):
    """Path.resolve raises RuntimeError for a loop (Python 3.11), which the library reader took for a bug."""
    first, second = tmp_path / "a.lp", tmp_path / "b.lp"
    first.symlink_to(second)
    second.symlink_to(first)
    assert main(["--quiet", *command, "--library", str(first)]) == 2
    assert capsys.readouterr().err == f"groundlang {command[0]}: error: {first}: Too many levels of symbolic links\n"


def test_check_sets_aside_a_layout_too_large_to_tabulate_before_enumerating_it(tmp_path):
    """A 1000x1000 room with 700 blocks: its abstraction had been enumerated (2.9 GB) before being refused;
    check now sets its pairs aside, by file and line, as training skips them."""
    import subprocess
    import sys

    blocks = " , ".join(f"block{i} (block): [x: {{{2 + i}}} y: {{5}} shape: {{chair}} colour: {{red}} ]" for i in range(700))
    line = ("{agent0 (agent): [x: {1} y: {1} ] , " + blocks
            + " , room0 (room): [top: {1000} left: {0} bottom: {0} right: {1000} colour: {red} ] , }")
    corpus = tmp_path / "many.bdm"
    corpus.write_text(f"go to the red room\n{line}\n{line.replace('x: {1} y: {1}', 'x: {2} y: {1}')}\ntrue\n")
    # through a process of its own, whose only child is the check: its peak memory is the check's
    measure = ("import resource, subprocess, sys; run = subprocess.run(sys.argv[1:], capture_output=True, text=True); "
               "sys.stderr.write(run.stderr + run.stdout); print(run.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")
    run = subprocess.run([sys.executable, "-c", measure, sys.executable, "-m", "groundlang.cli", "check", str(corpus)],
                         capture_output=True, text=True, timeout=300)
    code, peak_kb = map(int, run.stdout.split())
    assert code == 0 and "Traceback" not in run.stderr, run.stderr
    # said of the pair, which training would skip (check's stdout, passed on through stderr here)
    assert f"pairs in a layout too large to tabulate (training skips them): 1\n  {corpus}, line 2: this layout has 998,001 walkable cells" in run.stderr
    assert peak_kb < 800 * 1024  # no abstraction was built (2.9 GB before)


def test_an_abstraction_of_many_objects_is_refused_before_its_positions_are_stored():
    from groundlang.bdm import parse_bdm_state
    from groundlang.model.relevance import abstract_space_uncached
    from groundlang.model.statespace import StateSpaceError

    blocks = " , ".join(f"block{i} (block): [x: {{{2 + i}}} y: {{5}} shape: {{chair}} colour: {{red}} ]" for i in range(700))
    state, _ = parse_bdm_state("{agent0 (agent): [x: {1} y: {1} ] , " + blocks
                               + " , room0 (room): [top: {1000} left: {0} bottom: {0} right: {1000} colour: {red} ] , }")
    with pytest.raises(StateSpaceError, match=r"997,301 states of 701 objects each: their positions would take 2\.6 GiB"):
        abstract_space_uncached(state, (), 5_000_000)


def test_outputs_that_would_replace_or_join_what_a_command_reads_are_refused(trained_model, tmp_path, capsys):
    """A picture through a symlink onto its own input had replaced the corpus file; a new .txt in the corpus
    folder had joined the corpus (the next run failed on it); a file in a model folder had made the model
    folder one that `train -o` refuses; --plot onto --json had replaced the rows. Each is one line, nothing written."""
    import shutil

    corpus = tmp_path / "ex"
    shutil.copytree(EXAMPLES, corpus)
    victim = tmp_path / "victim.txt"
    victim.write_bytes((corpus / "agent2blue_0.txt").read_bytes())
    (tmp_path / "link.png").symlink_to(victim)
    before = victim.read_bytes()
    model = trained_model
    cases = [
        (["show", str(victim), "--palette", "sokoban", "--out", str(tmp_path / "link.png")],
         f"--out {tmp_path / 'link.png'}: the command reads it (FILE {victim})"),
        (["discover", str(corpus), "--palette", "sokoban", "-o", str(corpus / "new.txt")],
         f"-o {corpus / 'new.txt'}: inside directory {corpus}, which the command reads: a .txt file there would be "
         "read as part of it next time"),
        (["discover", str(corpus), "--palette", "sokoban", "-o", str(model / "tasks.lp")],
         f"-o {model / 'tasks.lp'}: inside a model folder"),
        (["ablate", "--corpus", str(corpus), "--palette", "sokoban", "--labels", str(corpus / "labels.csv"), "--json",
          str(tmp_path / "same.png"), "--plot", str(tmp_path / "same.png")],
         f"--plot {tmp_path / 'same.png'}: the same file as --json"),
    ]
    for argv, piece in cases:
        assert main(["--quiet", *argv]) == 2, argv
        err = capsys.readouterr().err
        assert piece in err and len(err.strip().splitlines()) == 1, err
    assert victim.read_bytes() == before and not (corpus / "new.txt").exists()
    assert not (model / "tasks.lp").exists() and not (tmp_path / "same.png").exists()


def test_ablate_refuses_labels_that_miss_a_prefix_before_any_cell(tmp_path, capsys):
    """A labels file of its header alone had run every cell of the grid (task discovery too), each failing, a row
    each, exit 1."""
    header = (EXAMPLES / "labels.csv").read_text().splitlines()[0]
    (tmp_path / "labels.csv").write_text(header + "\n")
    assert main(["ablate", "--corpus", str(EXAMPLES), "--palette", "sokoban", "--labels", str(tmp_path / "labels.csv"),
                 "--sizes", "12"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == (
        f"groundlang ablate: error: {tmp_path / 'labels.csv'}: no gold label for the prefixes 'agent2blue_', "
        f"'agent2green_', 'agent2red_', 'star2blue_', 'star2green_' ... of {EXAMPLES}\n")


@pytest.mark.parametrize("argv", [("discover", "", "--palette", "sokoban", "-o", "x.lp"), ("lexicon", ""),
                                  ("parse", "--file", ""), ("train", "", "-o", "m"), ("check", ""),
                                  ("show", "", "--palette", "sokoban"), ("evaluate", "--corpus", "")])
def test_an_empty_input_path_is_refused_by_its_argument(argv, capsys):
    """It had been read as the current folder: discover "" read whatever lay there as a corpus, parse --file ""
    every *.txt below it."""
    with pytest.raises(SystemExit) as stopped:
        main(["--quiet", *argv])
    assert stopped.value.code == 2
    assert "an empty path; expected a file or folder to read" in capsys.readouterr().err


def test_ablate_lists_name_each_cell_once():
    """--language-models bow,bow had made the same cells twice, row for row."""
    from groundlang.commands.ablate import _list_of, _sizes

    assert _list_of("bow,ibm2,parse")("bow, bow,parse,bow") == ["bow", "parse"]
    assert _sizes("12,12,24") == [12, 24]


def test_discover_refuses_a_weight_margin_of_zero_by_its_option(capsys):
    """It had said "weight_margin must be in (0, 1], got 0.0", the Python parameter's name, after the corpus was read."""
    assert main(["discover", str(EXAMPLES), "--palette", "sokoban", "-o", "x.lp", "--weight-margin", "0"]) == 2
    assert capsys.readouterr().err == ("groundlang discover: error: --weight-margin 0: expected a fraction above 0, "
                                       "up to 1 (of the largest MLIRL weight)\n")
