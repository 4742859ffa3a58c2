"""groundlang: learn what verbal commands mean from demonstrations, then follow new ones.

The public API (loaded on first use, so that ``import groundlang.logic`` and
the CLI's ``--help`` stay light):

    Learner, Posterior, FollowResult      the joint model: fit, posterior, follow, clarify, update, save/load
    read_corpus, read_instance, read_state_file, write_instance, format_state, example_corpus_path
    read_labels, goal_holds               gold labels and goal checks
    evaluate, EvaluationResult            evaluation protocols
    TaskLibrary                           lifted tasks authored or discovered in ASP
    parse                                 commands to logical forms
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

_EXPORTS = {
    "Learner": "groundlang.learner",
    "Posterior": "groundlang.learner",
    "FollowResult": "groundlang.learner",
    "read_corpus": "groundlang.corpus",
    "read_instance": "groundlang.corpus",
    "read_state_file": "groundlang.corpus",
    "write_instance": "groundlang.corpus",
    "format_state": "groundlang.corpus",
    "example_corpus_path": "groundlang.corpus",
    "read_labels": "groundlang.labels",
    "goal_holds": "groundlang.labels",
    "evaluate": "groundlang.evaluation",
    "EvaluationResult": "groundlang.evaluation",
    "TaskLibrary": "groundlang.logic.tasks",
    "parse": "groundlang.grammar.parser",
}

__all__ = sorted(_EXPORTS) + ["__version__"]


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'groundlang' has no attribute {name!r}")


def __dir__():
    return __all__
