"""groundlang.distributed: folds and ablation cells on a local Ray instance give the process pool's results."""

from __future__ import annotations

import os
import sys

import pytest

from groundlang.corpus import example_corpus_path, read_corpus
from groundlang.labels import read_labels

# ------------------------------------------------------------------ without Ray


def test_missing_ray_is_a_clear_value_error(monkeypatch):
    from groundlang.distributed import RayUnavailableError, run_on_ray

    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` now raises ImportError
    with pytest.raises(ValueError, match=r"install the ray extra: pip install 'groundlang\[ray\]'") as info:
        run_on_ray(_init, _square, {}, [0, 1], "local")
    assert isinstance(info.value, RayUnavailableError)


# ------------------------------------------------------------------ with Ray

_STATE = {"inits": 0, "context": None}


def _init(context) -> None:
    _STATE["inits"] += 1
    _STATE["context"] = context


def _square(index: int) -> dict:
    if index in _STATE["context"]["fail"]:
        raise KeyError(f"piece {index} was told to fail")
    return {"index": index, "value": index * index * _STATE["context"]["scale"],
            "pid": os.getpid(), "inits": _STATE["inits"]}


@pytest.fixture(scope="module")
def ray_local():
    ray = pytest.importorskip("ray", reason="ray is not installed (pip install 'groundlang[ray]')")
    from groundlang.distributed import ray_session

    # Workers import this module's functions by name, as they import groundlang's.
    here = os.path.dirname(os.path.abspath(__file__))
    with ray_session("local", num_cpus=2, runtime_env={"env_vars": {"PYTHONPATH": here}}):
        yield ray


@pytest.fixture(scope="module")
def example():
    path = example_corpus_path()
    return read_corpus(path, "sokoban"), read_labels(path / "labels.csv")


@pytest.mark.slow
def test_results_in_index_order_with_one_init_per_worker_and_errors_as_records(ray_local):
    from groundlang.distributed import run_on_ray

    indices = [7, 3, 0, 5, 2, 6, 1, 4]
    records = run_on_ray(_init, _square, {"scale": 10, "fail": {5}}, indices, "local")
    assert [r["index"] for r in records] == indices
    assert [r.get("value") for r in records] == [490, 90, 0, None, 40, 360, 10, 160]
    failed = records[3]
    assert failed["error"] == "KeyError: 'piece 5 was told to fail'"
    assert failed["instance"] == "piece 5" and failed["seconds"] >= 0
    # The context is fetched and initialised once per worker process, however many pieces it runs.
    assert all(r["inits"] == 1 for r in records if "error" not in r)
    assert len({r["pid"] for r in records if "error" not in r}) <= 2


def test_a_new_context_reinitialises_reused_workers(ray_local):
    from groundlang.distributed import run_on_ray

    first = run_on_ray(_init, _square, {"scale": 1, "fail": set()}, [1, 2, 3], "local")
    second = run_on_ray(_init, _square, {"scale": 2, "fail": set()}, [1, 2, 3], "local")
    assert [r["value"] for r in first] == [1, 4, 9]
    assert [r["value"] for r in second] == [2, 8, 18]  # not the first run's cached context


@pytest.mark.slow
def test_leave_one_out_on_ray_matches_the_process_pool(ray_local, example):
    from groundlang.evaluation import evaluate

    corpus, labels = example
    local = evaluate(corpus, labels, protocol="loo", language_model="parse", limit=4)
    on_ray = evaluate(corpus, labels, protocol="loo", language_model="parse", limit=4, ray_address="local")
    assert on_ray.failed_folds == [] and on_ray.n == 4
    assert [r["instance"] for r in on_ray.records] == [i.name for i in corpus.instances[:4]]
    assert [(r["predicted"], r["correct"]) for r in on_ray.records] == \
        [(r["predicted"], r["correct"]) for r in local.records]
    assert on_ray.correct == local.correct >= 3


@pytest.mark.slow
def test_ablation_cells_on_ray_match_the_serial_run(ray_local, example):
    from groundlang.ablation import run_ablation

    corpus, labels = example
    grid = dict(language_models=["parse", "bow"], libraries=["authored"], sizes=[12], protocol="train")
    serial = run_ablation(corpus, labels, **grid)
    on_ray = run_ablation(corpus, labels, ray_address="local", **grid)
    assert [(r.language_model, r.size, r.protocol, r.n) for r in on_ray.rows] == [
        ("parse", 12, "train", 12), ("bow", 12, "train", 12)]
    assert [r.error for r in on_ray.rows] == [None, None]
    assert [(r.correct, r.accuracy) for r in on_ray.rows] == [(r.correct, r.accuracy) for r in serial.rows]


def test_an_address_nothing_answers_at_is_refused_at_once(monkeypatch):
    """Before, ``ray.init`` retried an unreachable address for more than ten minutes."""
    import socket
    import time

    from groundlang.distributed import ray_session

    ray = pytest.importorskip("ray")
    monkeypatch.setattr(ray, "is_initialized", lambda: False)  # as in a fresh process (another test's may run)
    monkeypatch.setattr(ray, "init", lambda *a, **k: pytest.fail("ray.init called with an unreachable address"))
    with socket.socket() as s:  # a port nothing listens at: bound, never listening
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        started = time.monotonic()
        with pytest.raises(ValueError, match=rf"Ray address 127.0.0.1:{port}: no Ray cluster answers there"):
            with ray_session(f"127.0.0.1:{port}"):
                pass
    assert time.monotonic() - started < 10


def test_an_address_with_no_tcp_port_is_refused(monkeypatch):
    from groundlang.distributed import ray_session

    ray = pytest.importorskip("ray")
    monkeypatch.setattr(ray, "is_initialized", lambda: False)
    with pytest.raises(ValueError, match="Ray address 127.0.0.1:99999: port 99999 is not a TCP port"):
        with ray_session("127.0.0.1:99999"):
            pass
