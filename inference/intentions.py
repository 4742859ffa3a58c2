"""Multiple intentions: EM clustering of demonstrations by reward function (Babeş-Vroman et al., ICML 2011).

K linear reward functions (weights ``[K, F]`` and temperatures) and mixing
proportions ``rho [K]``. E-step: responsibilities
``r[d, k] ∝ rho[k] * P(demo d | reward k)`` from the per-demonstration
log-likelihoods of :class:`~groundlang.inference.mlirl.MLIRLProblem`. M-step:
MLIRL for each cluster with the responsibilities as demonstration weights
(warm-started from the previous iteration's weights and values), and
``rho = mean_d r[d, :]``.

Initialisation (EM's local optima make it matter): farthest-first seeding,
as k-means++ does for points. The first cluster is fitted to one
demonstration drawn with ``seed``; each further cluster is fitted to the
demonstration that the clusters so far explain worst (lowest best
log-likelihood per decision). The first E-step then starts from those K
fits. The same seed gives the same clusters.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
import torch

from groundlang.inference.mlirl import MLIRLProblem, mlirl
from groundlang.inference.planning import PlanningError, threads_for

__all__ = ["IntentionsResult", "multiple_intentions"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class IntentionsResult:
    """EM output: ``weights [K, F]``, ``temperatures [K]``, ``responsibilities [D, K]``,
    ``priors [K]``, the marginal ``log_likelihood`` of all demonstrations, ``iterations``, ``converged``."""

    weights: np.ndarray
    temperatures: np.ndarray
    responsibilities: np.ndarray
    priors: np.ndarray
    log_likelihood: float
    iterations: int
    converged: bool

    @property
    def assignments(self) -> np.ndarray:
        """``[D]`` most responsible cluster of each demonstration."""
        return self.responsibilities.argmax(axis=1)


def multiple_intentions(
    next_state,
    features,
    demonstrations,
    num_intentions: int,
    seed: int = 0,
    max_iterations: int = 30,
    tol: float = 1e-4,
    temperature: float | None = None,
    mlirl_steps: int = 30,
    **problem_kwargs,
) -> IntentionsResult:
    """Cluster demonstrations into ``num_intentions`` reward functions by EM.

    ``next_state [S, A]``, ``features [S, F]``, ``demonstrations`` as for
    :func:`~groundlang.inference.mlirl.mlirl`. ``temperature`` fixes every
    cluster's temperature (None: learned). Converged when the marginal
    log-likelihood improves by less than ``tol`` per demonstration.
    ``problem_kwargs`` go to MLIRLProblem (reward_on, step_cost, discount, ...).
    """
    K = int(num_intentions)
    D = len(demonstrations)
    if not 1 <= K <= D:
        raise PlanningError(f"num_intentions must be between 1 and the number of demonstrations ({D}), got {K}")
    rng = np.random.default_rng(seed)
    problems = [MLIRLProblem(next_state, features, demonstrations, **problem_kwargs) for _ in range(K)]
    F = problems[0].num_features
    weights = np.zeros((K, F))
    temps = np.full(K, 1.0 if temperature is None else float(temperature))
    decisions = np.array([len(d.actions) + 1 for d in problems[0].demonstrations])
    previous, converged, total = -math.inf, False, -math.inf
    iteration = 0

    def fit(k: int, demo_weights: np.ndarray) -> None:
        result = mlirl(None, None, None, demo_weights=demo_weights, temperature=temperature,
                       initial_temperature=temps[k], initial_weights=weights[k], max_steps=mlirl_steps,
                       problem=problems[k])
        weights[k], temps[k] = result.weights, result.temperature

    def log_likelihoods() -> np.ndarray:  # [D, K]
        with torch.no_grad():
            return np.stack([
                problems[k].per_demo_log_likelihood(torch.as_tensor(weights[k], dtype=problems[k].dtype),
                                                    torch.tensor(temps[k], dtype=problems[k].dtype)).numpy()
                for k in range(K)
            ], axis=1).astype(np.float64)

    with threads_for(problems[0].next_state.shape[0]):
        seeds = [int(rng.integers(D))]
        fit(0, np.eye(D)[seeds[0]])
        for k in range(1, K):
            explained = log_likelihoods()[:, :k].max(axis=1) / decisions
            explained[seeds] = np.inf
            seeds.append(int(np.argmin(explained)))
            fit(k, np.eye(D)[seeds[-1]])
        priors = np.full(K, 1.0 / K)
        for iteration in range(1, max_iterations + 1):
            # E-step.
            ll = log_likelihoods()
            joint = ll + np.log(np.maximum(priors, 1e-300))
            norm = np.logaddexp.reduce(joint, axis=1)
            resp = np.exp(joint - norm[:, None])
            total = float(norm.sum())
            logger.debug("intentions EM iteration %d: log-likelihood %.4f", iteration, total)
            if total - previous < tol * D:
                converged = True
                break
            previous = total
            # M-step.
            priors = resp.mean(axis=0)
            for k in range(K):
                fit(k, resp[:, k])
    return IntentionsResult(weights.copy(), temps.copy(), resp, resp.mean(axis=0), total, iteration, converged)
