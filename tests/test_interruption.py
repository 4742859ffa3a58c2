"""Interrupted runs (Ctrl-C, SIGTERM) keep the last complete outputs, say what they kept, and resume.

groundlang.interrupt and the CLI's handling: in-process checks of the
signal helpers, then real ``groundlang train`` / ``groundlang evaluate``
processes stopped with SIGTERM or SIGINT while they work.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from groundlang.cli import main
from groundlang.corpus import example_corpus_path
from groundlang.interrupt import deferred_interrupts, terminate_as_interrupt, what_was_kept

EXAMPLES = example_corpus_path()


@pytest.fixture(autouse=True)
def _python_sigint_handler():
    """Runners that start tests in the background ignore SIGINT; these tests need Python's handler."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)  # so the child Python installs its own handler


def _signal_self(sig: int) -> None:
    os.kill(os.getpid(), sig)
    time.sleep(0.05)  # the handler runs at the next bytecode boundary


# ----------------------------------------------------------------- the helpers, in-process
def test_sigterm_raises_keyboard_interrupt_inside_and_not_after():
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(KeyboardInterrupt, match="SIGTERM"):
        with terminate_as_interrupt():
            _signal_self(signal.SIGTERM)
    assert signal.getsignal(signal.SIGTERM) == before


def test_deferred_interrupts_finish_the_block_then_interrupt():
    done = []
    with pytest.raises(KeyboardInterrupt, match="SIGINT"):
        with deferred_interrupts():
            _signal_self(signal.SIGINT)
            done.append("first")
            done.append("second")
    assert done == ["first", "second"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    with deferred_interrupts():  # nothing received: nothing raised
        done.append("third")
    assert done[-1] == "third"


@pytest.fixture(scope="module")
def learner():
    from groundlang.corpus import read_corpus
    from groundlang.learner import Learner

    return Learner(steps=20, cache_dir=False).fit(read_corpus(EXAMPLES, "sokoban").instances[:6])


def test_save_interrupted_between_its_two_files_still_writes_both(learner, tmp_path, monkeypatch):
    """Ctrl-C after the tensors are renamed: the JSON naming them is still written, then the interrupt."""
    from groundlang.logic import storage
    from groundlang.learner import Learner

    real = storage.write_atomically
    calls = []

    def write_then_interrupt(path, data, **options):
        real(path, data, **options)
        calls.append(Path(path).name)
        if len(calls) == 1:
            _signal_self(signal.SIGINT)

    monkeypatch.setattr(storage, "write_atomically", write_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        learner.save(tmp_path / "model")
    assert len(calls) == 2 and calls[0].startswith("globals-") and calls[1] == "model.json"
    monkeypatch.undo()
    loaded = Learner.load(tmp_path / "model")
    assert loaded.vocab.words == learner.vocab.words


def test_cli_reports_what_an_interrupted_train_kept(tmp_path, monkeypatch, capsys):
    """A SIGTERM in the middle of fitting: exit 130, one line saying nothing was written."""
    from groundlang.learner import Learner

    monkeypatch.setenv("GROUNDLANG_CACHE", str(tmp_path / "cache"))

    def fit(self, *args, **kwargs):
        _signal_self(signal.SIGTERM)
        raise AssertionError("SIGTERM did not interrupt")

    monkeypatch.setattr(Learner, "fit", fit)
    code = main(["--quiet", "train", str(EXAMPLES), "--palette", "sokoban", "-o", str(tmp_path / "model")])
    out, err = capsys.readouterr()
    assert code == 130
    assert err == f"groundlang train: interrupted; nothing written to {tmp_path / 'model'}\n"
    assert not (tmp_path / "model").exists()


def test_interrupting_again_while_the_interruption_is_reported_says_it_once(tmp_path, monkeypatch, capsys):
    """A second Ctrl-C while the report counted a large cache had printed two tracebacks."""
    from groundlang import cli
    from groundlang.learner import Learner

    monkeypatch.setenv("GROUNDLANG_CACHE", str(tmp_path / "cache"))

    def fit(self, *args, **kwargs):
        _signal_self(signal.SIGINT)
        raise AssertionError("SIGINT did not interrupt")

    reported = cli.what_was_kept

    def counted_while_interrupted(*args, **kwargs):
        _signal_self(signal.SIGINT)  # pressed again, twice
        _signal_self(signal.SIGINT)
        return reported(*args, **kwargs)

    monkeypatch.setattr(Learner, "fit", fit)
    monkeypatch.setattr(cli, "what_was_kept", counted_while_interrupted)
    before = (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM))
    code = main(["--quiet", "train", str(EXAMPLES), "--palette", "sokoban", "-o", str(tmp_path / "model")])
    assert code == 130
    assert capsys.readouterr().err == f"groundlang train: interrupted; nothing written to {tmp_path / 'model'}\n"
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before  # given back


def test_what_was_kept_describes_each_output(tmp_path):
    import groundlang.inference.likelihoods  # noqa: F401  entries are counted once the cache's module is loaded

    class Args:
        command = "train"
        output = str(tmp_path / "model")
        json = str(tmp_path / "result.json")
        cache_dir = str(tmp_path / "cache")

    start = time.time()
    assert what_was_kept(Args, start, uses_cache=False) == (
        f"nothing written to {tmp_path / 'model'}; nothing written to {tmp_path / 'result.json'}"
    )
    (tmp_path / "model").mkdir()
    assert what_was_kept(Args, start, uses_cache=False).startswith(f"{tmp_path / 'model'} holds no complete model")
    (tmp_path / "model" / "model.json").write_text("{}")
    os.utime(tmp_path / "model" / "model.json", (start - 100, start - 100))
    entry = tmp_path / "cache" / "behaviour" / "ab" / "abc.json"
    entry.parent.mkdir(parents=True)
    entry.write_text("{}")
    (entry.parent / ".tmp-x.json").write_text("{")  # a temporary file is not an entry
    assert what_was_kept(Args, start, uses_cache=True) == (
        f"{tmp_path / 'model'} left as it was (the previous complete model); "
        f"nothing written to {tmp_path / 'result.json'}; "
        f"1 new cache entry is kept in {tmp_path / 'cache'} (behaviour likelihoods, end-state evidence and readings; "
        "a rerun resumes from them)"
    )
    for kind in ("evidence", "parses"):  # a .bdm corpus's evidence and the readings of commands count too
        (tmp_path / "cache" / kind / "cd").mkdir(parents=True)
        (tmp_path / "cache" / kind / "cd" / "cdef.json").write_text("{}")
    assert what_was_kept(Args, start, uses_cache=True).endswith(
        f"3 new cache entries are kept in {tmp_path / 'cache'} (behaviour likelihoods, end-state evidence and "
        "readings; a rerun resumes from them)")
    # interrupted before the entries at the start were counted: none is claimed as new
    assert "cache" not in what_was_kept(Args, start, uses_cache=True, cache_entries_before=None)


def test_what_follow_learn_kept_names_its_model_and_no_negative_count(tmp_path):
    """follow --learn saves over --model: an interrupt had said "no output files were due" after the save.
    And a cache cleared during the run had been reported as "-45 new ... entries"."""
    import groundlang.inference.likelihoods  # noqa: F401

    class Args:
        command = "follow"
        learn = True
        model = str(tmp_path / "model")
        cache_dir = str(tmp_path / "cache")

    (tmp_path / "model").mkdir()
    (tmp_path / "model" / "model.json").write_text("{}")
    start = time.time()
    os.utime(tmp_path / "model" / "model.json", (start - 100, start - 100))
    assert what_was_kept(Args, start, uses_cache=True, cache_entries_before=45) == (
        f"{tmp_path / 'model'} left as it was (the previous complete model)")
    os.utime(tmp_path / "model" / "model.json", (start + 1, start + 1))
    assert what_was_kept(Args, start, uses_cache=False) == f"the model in {tmp_path / 'model'} was complete before the interruption"
    assert what_was_kept(Args, start, uses_cache=False, held=True) == (
        f"the model in {tmp_path / 'model'} is this run's, written whole (the interruption came while it was saved)")


def test_an_interruption_during_the_save_waits_for_it_and_says_so(tmp_path, monkeypatch, capsys):
    """Ctrl-C while the model's files are renamed into place: the save finishes (all or nothing), then the
    run stops with 130, and the line says the model there is this run's, not that it came before."""
    import signal

    from groundlang import model_io
    from groundlang.cli import main
    from groundlang.corpus import example_corpus_path

    real = model_io.storage.write_atomically

    def interrupted_write(path, data, **options):
        if Path(path).name == "model.json":
            os.kill(os.getpid(), signal.SIGINT)  # held by the save's deferred_interrupts
        return real(path, data, **options)

    monkeypatch.setattr(model_io.storage, "write_atomically", interrupted_write)
    model = tmp_path / "model"
    code = main(["--quiet", "train", str(example_corpus_path()), "--palette", "sokoban", "-o", str(model),
                 "--cache-dir", str(tmp_path / "cache")])
    err = capsys.readouterr().err
    assert code == 130 and err.startswith(f"groundlang train: interrupted; the model in {model} is this run's, "
                                          "written whole (the interruption came while it was saved)"), err
    monkeypatch.undo()
    from groundlang.learner import Learner

    assert Learner.load(model).vocab is not None


# ----------------------------------------------------------------- real processes
def _cache_entries(cache: Path, kinds: tuple[str, ...] = ("behaviour",)) -> list[Path]:
    """Whole entries only: temporary files (".tmp-...") are not entries yet."""
    return sorted(p for kind in kinds if (cache / kind).is_dir()
                  for p in (cache / kind).glob("*/*.json") if not p.name.startswith("."))


# Every kind of entry the interruption line counts: behaviour likelihoods, end-state evidence, readings.
from groundlang.inference.likelihoods import CACHE_FOLDERS as ALL_KINDS  # noqa: E402


def _assert_whole_entries(cache: Path) -> None:
    """Every cache entry is whole: it parses and records its own key.

    (A temporary ".tmp-" file may survive a signal that lands between its
    creation and the write's try block in inference/likelihoods.py; it is
    never read as an entry.)
    """
    files = _cache_entries(cache)
    assert files
    for path in files:
        data = json.loads(path.read_text())
        assert data["key"] == path.stem and isinstance(data["log_likelihood"], float)


def _start(argv: list[str], cache: Path) -> subprocess.Popen:
    env = dict(os.environ, GROUNDLANG_CACHE=str(cache), PYTHONUNBUFFERED="1")
    return subprocess.Popen([sys.executable, "-m", "groundlang.cli", *argv], env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, preexec_fn=_default_sigint)


def _interrupt_when(proc: subprocess.Popen, ready, sig: int, timeout: float = 60.0) -> tuple[int, str, str]:
    """Poll ``ready()`` every 5 ms; send ``sig`` when it turns true; return (code, stdout, stderr)."""
    deadline = time.monotonic() + timeout
    while proc.poll() is None and not ready():
        if time.monotonic() > deadline:
            proc.kill()
            pytest.fail("the run never reached the point to interrupt")
        time.sleep(0.005)
    assert proc.poll() is None, "the run finished before it could be interrupted"
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=timeout)
    return proc.returncode, out, err


def _last_line(err: str) -> str:
    # tqdm redraws with carriage returns; the report is the last thing on stderr
    return re.split(r"[\r\n]", err.strip())[-1]


@pytest.mark.slow
def test_train_interrupted_keeps_nothing_then_resumes_and_protects_the_previous_model(tmp_path):
    cache, model = tmp_path / "cache", tmp_path / "model"
    argv = ["train", str(EXAMPLES), "--palette", "sokoban", "-o", str(model)]

    # 1. SIGTERM as soon as the first behaviour likelihood is cached.
    code, out, err = _interrupt_when(_start(argv, cache), lambda: bool(_cache_entries(cache)), signal.SIGTERM)
    assert code == 130, err
    assert "Traceback" not in err
    kept = len(_cache_entries(cache))
    assert _last_line(err).startswith(f"groundlang train: interrupted; nothing written to {model}; "
                                      f"{len(_cache_entries(cache, ALL_KINDS))} new cache ")
    assert _last_line(err).endswith(f"kept in {cache} (behaviour likelihoods, end-state evidence and readings; a rerun "
                                    "resumes from them)")
    assert not model.exists()
    _assert_whole_entries(cache)

    # 2. The rerun starts from the kept entries and finishes.
    done = subprocess.run([sys.executable, "-m", "groundlang.cli", *argv], capture_output=True, text=True,
                          env=dict(os.environ, GROUNDLANG_CACHE=str(cache)), timeout=120)
    assert done.returncode == 0, done.stderr
    hits = int(re.search(r"behaviour likelihoods: (\d+) cached", done.stderr).group(1))
    assert hits >= kept > 0
    assert f"model written to {model}" in done.stdout
    before = {p.name: p.read_bytes() for p in model.iterdir()}

    # 3. Ctrl-C while training over that model (another seed): the previous model stays, whole.
    proc = _start([*argv, "--seed", "1"], cache)
    seen = []

    def fitting() -> bool:
        line = proc.stderr.readline()
        seen.append(line)
        return "behaviour likelihoods:" in line

    code, out, err = _interrupt_when(proc, fitting, signal.SIGINT)
    assert code == 130, "".join(seen) + err
    assert "Traceback" not in err
    assert _last_line(err) == f"groundlang train: interrupted; {model} left as it was (the previous complete model)"
    assert {p.name: p.read_bytes() for p in model.iterdir()} == before
    from groundlang.learner import Learner

    assert Learner.load(model).lexicon()


@pytest.mark.slow
def test_evaluate_interrupted_writes_no_result_and_keeps_cache(tmp_path):
    cache, result = tmp_path / "cache", tmp_path / "result.json"
    argv = ["evaluate", "--corpus", str(EXAMPLES), "--palette", "sokoban", "--labels", str(EXAMPLES / "labels.csv"),
            "--protocol", "loo", "--limit", "2", "--json", str(result)]
    code, out, err = _interrupt_when(_start(argv, cache), lambda: bool(_cache_entries(cache)), signal.SIGTERM)
    assert code == 130, err
    assert "Traceback" not in err
    kept = len(_cache_entries(cache, ALL_KINDS))
    entries = "entry is" if kept == 1 else "entries are"
    assert _last_line(err) == (
        f"groundlang evaluate: interrupted; nothing written to {result}; "
        f"{kept} new cache {entries} kept in {cache} (behaviour likelihoods, end-state evidence and readings; a rerun "
        "resumes from them)"
    )
    assert not result.exists()
    assert [p for p in tmp_path.iterdir() if p.name.startswith(".")] == []
    _assert_whole_entries(cache)


def test_nested_deferral_waits_for_the_outermost_block(tmp_path):
    """An inner deferral inside an outer one (save's, around its two files) must not raise at its own end."""
    from groundlang.logic.storage import write_atomically

    with pytest.raises(KeyboardInterrupt):
        with deferred_interrupts():
            write_atomically(tmp_path / "a", b"1")
            _signal_self(signal.SIGINT)
            with deferred_interrupts():
                write_atomically(tmp_path / "b", b"2")
            (tmp_path / "c").write_bytes(b"3")  # the inner deferral passed the signal on, not raising
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a", "b", "c"]


def test_an_interrupt_while_starting_is_one_line(monkeypatch, capsys):
    """Ctrl-C while the subcommands were imported (seconds on a busy machine) printed a traceback."""
    import groundlang.cli

    def build_parser():
        raise KeyboardInterrupt

    monkeypatch.setattr(groundlang.cli, "build_parser", build_parser)
    try:
        code = main(["train"])
    except KeyboardInterrupt:
        pytest.fail("the interrupt escaped main: Python printed its traceback")
    assert code == 130
    assert capsys.readouterr().err == "groundlang: interrupted while starting; nothing was written\n"


def test_sigterm_is_an_interrupt_while_the_cache_is_first_read(tmp_path, monkeypatch, capsys):
    """Counting the cache imports torch (seconds); a SIGTERM then killed the run without a word (exit 143)."""
    import groundlang.cli

    handlers = []
    monkeypatch.setattr(groundlang.cli, "cache_entry_count",
                        lambda args: handlers.append(signal.getsignal(signal.SIGTERM)) or 0)
    monkeypatch.setattr(groundlang.cli.importlib.import_module("groundlang.commands.train"), "run",
                        lambda args: 0)
    main(["--quiet", "train", str(EXAMPLES), "--palette", "sokoban", "-o", str(tmp_path / "model")])
    assert handlers and callable(handlers[0]) and handlers[0] is not signal.SIG_DFL


def test_an_interrupt_during_the_cache_modules_import_does_not_import_it_again(tmp_path, monkeypatch):
    """A Ctrl-C while inference.likelihoods imported torch: what_was_kept imported it again, over a
    half-initialised torch, and the process died (SystemError, SIGSEGV or abort) instead of saying what it
    kept. A failed import leaves no module in sys.modules; None there makes importing it an error."""
    monkeypatch.setitem(sys.modules, "groundlang.inference.likelihoods", None)

    class Args:
        command = "train"
        output = str(tmp_path / "model")
        cache_dir = str(tmp_path / "cache")

    assert what_was_kept(Args(), time.time(), uses_cache=True) == f"nothing written to {tmp_path / 'model'}"


def test_a_fold_worker_dies_with_its_parent(tmp_path):
    """evaluate --workers killed with -9: its workers had gone on with their folds and printed BrokenPipe
    tracebacks after the command had ended; the kernel now stops them when the parent dies (Linux)."""
    script = tmp_path / "parent.py"
    script.write_text(
        "import os, signal, sys, time\n"
        "from groundlang.folds import _die_with_parent\n"
        "parent = os.getpid()\n"
        "if os.fork() == 0:\n"
        "    _die_with_parent(signal.SIGTERM, parent)\n"
        "    print(os.getpid(), flush=True)\n"
        "    time.sleep(60)\n"
        "    os._exit(0)\n"
        "time.sleep(60)\n")
    parent = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    worker = int(parent.stdout.readline())
    parent.kill()
    parent.wait()
    deadline = time.time() + 10
    while time.time() < deadline:
        state = Path(f"/proc/{worker}/status")
        if not state.exists() or "\nState:\tZ" in state.read_text():
            break
        time.sleep(0.05)
    else:
        os.kill(worker, signal.SIGKILL)
        pytest.fail("the worker outlived its parent")


def test_an_interruption_held_over_a_block_that_failed_is_still_an_interruption():
    """A save refused (a ValueError) while a Ctrl-C waited: the run stops as interrupted (130), not as
    an error (2) that drops the user's Ctrl-C."""
    import signal

    import pytest

    from groundlang.interrupt import HeldInterrupt, deferred_interrupts

    with pytest.raises(HeldInterrupt) as stopped:
        with deferred_interrupts():
            os.kill(os.getpid(), signal.SIGINT)
            raise ValueError("not written")
    assert isinstance(stopped.value.__context__, ValueError)


def test_folds_run_in_this_process_keep_its_signal_handlers(monkeypatch):
    """With one worker (the default) the folds ran after a worker's set-up in the CLI's own process: Ctrl-C was
    ignored for the rest of `ablate` and leave-one-out `evaluate`, and SIGTERM killed them without a word."""
    import groundlang.folds as folds

    seen = []
    monkeypatch.setattr(folds, "_fold", lambda i: seen.append(
        (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM))) or {"index": i})
    before = (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM))
    assert folds.run_folds({}, [0, 1], workers=1, ray_address=None, progress=False) == [{"index": 0}, {"index": 1}]
    assert seen == [before, before]
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before
