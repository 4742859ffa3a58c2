"""What `groundlang evaluate` is measured against on the RSS 2015 commands-to-tasks corpus.

The published leave-one-out accuracies (MacGlashan et al., "Grounding English Commands to
Reward Functions", RSS 2015, Table I; as listed in the corpus's README) and the project's goals,
keyed by the corpus folder's name. ``comparison`` lines them up with a measured result, so a run
on either folder prints how it stands without a trip to the paper.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Reference", "REFERENCES", "CORPUS_VARIABLE", "crowd_corpus_path", "comparison", "format_comparison"]

# The corpus is not part of the repository: tests and benchmarks look for it beside the clone
# (../shared/data/commands-to-tasks) unless this environment variable names its folder.
CORPUS_VARIABLE = "GROUNDLANG_CORPUS"


def crowd_corpus_path(repository: Path) -> Path:
    """Where the commands-to-tasks corpus (the folder holding ``allTurkTrain``) is looked for: the folder
    ``$GROUNDLANG_CORPUS`` names, else ``../shared/data/commands-to-tasks`` beside ``repository``."""
    named = os.environ.get(CORPUS_VARIABLE)
    return Path(named) if named else repository.resolve().parent / "shared" / "data" / "commands-to-tasks"


@dataclass(frozen=True)
class Reference:
    """One row to beat: the published accuracies of one setting and the project's goal there."""

    setting: str  # "loo" or "novel environments"
    published: tuple[tuple[str, float], ...]  # (model, accuracy), as published
    goal: float

    @property
    def best(self) -> tuple[str, float]:
        return max(self.published, key=lambda item: item[1])


_LOO_SIMPLIFIED = (("bag of words", 0.8375), ("IBM Model 2", 0.8125))
_LOO_ORIGINAL = (("bag of words", 0.5375), ("IBM Model 2", 0.7416))
_NOVEL_ORIGINAL = (("bag of words", 0.5180), ("IBM Model 2", 0.7333))

REFERENCES: dict[str, tuple[Reference, ...]] = {
    "allTurkTrainLimitedCommand": (Reference("loo", _LOO_SIMPLIFIED, 0.95),),
    "allTurkTrain": (Reference("loo", _LOO_ORIGINAL, 0.90), Reference("novel environments", _NOVEL_ORIGINAL, 0.90)),
}


def comparison(corpus_name: str, result) -> list[dict]:
    """Rows comparing ``result`` (an ``EvaluationResult`` of the whole corpus, leave-one-out) with the
    published accuracies and goal of ``corpus_name``; empty for another corpus, protocol or a partial run.

    Each row: ``setting``, ``accuracy``, ``correct``, ``n``, ``published`` (model -> accuracy),
    ``best_model``, ``best``, ``goal``, ``goal_correct`` (executions the goal needs) and ``reached``.
    """
    if result.protocol != "loo":
        return []
    rows = []
    for ref in REFERENCES.get(corpus_name, ()):
        if ref.setting == "loo":
            accuracy, correct, n = result.accuracy, result.correct, result.n
        elif result.novel_n:
            accuracy, correct, n = result.novel_accuracy, result.novel_correct, result.novel_n
        else:
            continue
        model, best = ref.best
        needed = math.ceil(ref.goal * n - 1e-9)
        rows.append({
            "setting": ref.setting, "accuracy": accuracy, "correct": correct, "n": n,
            "published": dict(ref.published), "best_model": model, "best": best,
            "goal": ref.goal, "goal_correct": needed, "reached": correct >= needed,
        })
    return rows


def format_comparison(rows: list[dict]) -> str:
    """The rows as lines for the terminal; empty string for no rows."""
    if not rows:
        return ""
    lines = ["against RSS 2015 (Table I) and the project's goals:"]
    for row in rows:
        status = "reached" if row["reached"] else f"not reached ({row['goal_correct']}/{row['n']} needed)"
        lines.append(
            f"  {row['setting']:<19} {row['accuracy']:.2%} ({row['correct']}/{row['n']}); "
            f"published best {row['best']:.2%} ({row['best_model']}); goal {row['goal']:.0%}: {status}"
        )
    return "\n".join(lines)

