"""Which candidate lifted tasks form the discovered library: the two-part code length ``J`` of
:mod:`groundlang.inference.discovery`, maximised over subsets of the candidates.
"""

from __future__ import annotations

import logging
import math
from itertools import combinations
from typing import Sequence

import numpy as np

__all__ = ["MAX_EXHAUSTIVE_SUBSETS", "RANKED_LIBRARIES", "library_score", "select_library"]

logger = logging.getLogger(__name__)

# Exhaustive library search when it has at most this many subsets; backward elimination beyond.
MAX_EXHAUSTIVE_SUBSETS = 200_000
# How many of the best libraries the result lists (to show the winning margin).
RANKED_LIBRARIES = 5


def library_score(table: np.ndarray, chosen: Sequence[int], sizes: np.ndarray, atom_cost: float) -> float:
    """``J`` of :mod:`groundlang.inference.discovery`'s docstring. ``table``: ``[D, L]`` per-demonstration scores (-inf: not applicable)."""
    best = table[:, list(chosen)].max(axis=1)
    if not np.isfinite(best).all():
        return -math.inf
    return float(best.sum() - len(table) * math.log(len(chosen)) - atom_cost * sizes[list(chosen)].sum())


def select_library(table: np.ndarray, sizes: np.ndarray, atom_cost: float,
                    max_tasks: int) -> list[tuple[tuple[int, ...], float]]:
    """Candidate-task index sets with their ``J``, best first (at most RANKED_LIBRARIES of them).

    Exhaustive over subsets of up to ``max_tasks`` tasks; ties go to fewer tasks, then earlier
    candidates. With too many subsets: backward elimination from all candidates (one result).
    """
    n = table.shape[1]
    total = sum(math.comb(n, k) for k in range(1, min(max_tasks, n) + 1))
    if total <= MAX_EXHAUSTIVE_SUBSETS:
        scored = [(subset, library_score(table, subset, sizes, atom_cost))
                  for k in range(1, min(max_tasks, n) + 1) for subset in combinations(range(n), k)]
        scored = [item for item in scored if math.isfinite(item[1])]
        # Stable sort: among equal scores, smaller and earlier subsets (generation order) come first.
        scored.sort(key=lambda item: -round(item[1], 9))
        return scored[:RANKED_LIBRARIES]
    logger.info("discovery: %d candidate tasks, searching the library by backward elimination", n)
    best = list(range(n))
    best_score = library_score(table, best, sizes, atom_cost)
    while len(best) > 1:
        trials = [(library_score(table, [j for j in best if j != i], sizes, atom_cost), i) for i in best]
        score, drop = max(trials, key=lambda si: (si[0], -si[1]))
        if score < best_score - 1e-9 and len(best) <= max_tasks:
            break
        best.remove(drop)
        best_score = score
    return [(tuple(best), best_score)] if math.isfinite(best_score) else []
