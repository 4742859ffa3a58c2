"""Shared fixtures: paths to the project's fixtures and to the optional shared corpus."""

from __future__ import annotations

from pathlib import Path

import pytest

from groundlang.published import CORPUS_VARIABLE, crowd_corpus_path

TESTS = Path(__file__).parent
FIXTURES = TESTS / "fixtures"
SHARED_CORPUS = crowd_corpus_path(TESTS.parent)


@pytest.fixture
def fixtures() -> Path:
    return FIXTURES


@pytest.fixture(scope="module")
def corpus():
    """The example corpus the package ships (24 commands with demonstrations); a module may define its own."""
    from groundlang.corpus import example_corpus_path, read_corpus

    return read_corpus(example_corpus_path(), "sokoban")


@pytest.fixture(scope="module")
def learner(corpus):
    """The default model trained on the example corpus, once per module (a test may change its settings and put
    them back); a module may define its own."""
    from groundlang.learner import Learner

    return Learner("parse").fit(corpus.instances)


@pytest.fixture
def shared_corpus() -> Path:
    """The crowd-sourced corpus in ../shared (or $GROUNDLANG_CORPUS); tests using it skip where it is absent."""
    if not (SHARED_CORPUS / "allTurkTrain").is_dir():
        pytest.skip(f"commands-to-tasks corpus not found at {SHARED_CORPUS} (it is not part of the repository; "
                    f"set {CORPUS_VARIABLE} to its folder)")
    return SHARED_CORPUS


@pytest.fixture(scope="session")
def williams_library():
    """The package's Williams et al. (2018) domain (relations, superlatives, tasks)."""
    from groundlang.bdm_check import default_library

    return default_library()


@pytest.fixture(scope="session")
def williams_commands():
    """The project's own two-command .bdm fixture, three pairs each."""
    from groundlang.bdm import read_bdm

    return read_bdm(FIXTURES / "williams2018" / "small.bdm")


@pytest.fixture(autouse=True)
def _pyro_state():
    """Pyro validation on and an empty parameter store for every test."""
    try:
        import pyro
    except ImportError:  # pragma: no cover
        yield
        return
    pyro.enable_validation(True)
    pyro.clear_param_store()
    yield
    pyro.clear_param_store()


@pytest.fixture(autouse=True)
def _groundlang_log_level():
    """The CLI sets the `groundlang` logger's level (WARNING under --quiet); a test calling it in-process
    must not decide what a later test's caplog sees."""
    import logging

    log = logging.getLogger("groundlang")
    level = log.level
    yield
    log.setLevel(level)


def _shortest_plan(start, goal, library):
    """A shortest plan to ``goal`` under ``library``'s PFs (soft value iteration, greedy rollout): states
    and actions. (``groundlang.examples.build.shortest_demonstration`` knows only the package's PFs.)"""
    from groundlang.inference.acting import rollout, rollout_states
    from groundlang.inference.planning import solve_task
    from groundlang.model.features import goal_mask
    from groundlang.model.pf_tables import pf_tables
    from groundlang.model.statespace import enumerate_states

    space = enumerate_states(start)
    mask = goal_mask(space, goal, pf_tables(start.layout, library.tabulation_program))
    trajectory = rollout(space.next_state, solve_task(space.next_state, mask), 0, goal_mask=mask)
    assert trajectory.reason == "goal"
    return rollout_states(space, trajectory)


@pytest.fixture(scope="session")
def shortest_plan():
    """Demonstrations for a user's domain: see _shortest_plan."""
    return _shortest_plan


_EXIT_STATUS = {}


def pytest_sessionfinish(session, exitstatus):
    _EXIT_STATUS["status"] = int(exitstatus)


def pytest_unconfigure(config):
    """A test that makes a grounding time out leaves clingo grounding in a thread no one can stop; the
    interpreter's teardown then crashes in clingo's native code (exit 139 after every test passed). The CLI
    ends at once in that case (groundlang.cli), and so does a test run, with its own status. Not in an xdist
    worker: its controller waits for the worker's last messages."""
    from groundlang.logic.program import grounding_left_running

    if not hasattr(config, "workerinput") and grounding_left_running():
        import os
        import sys

        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_EXIT_STATUS.get("status", 0))
