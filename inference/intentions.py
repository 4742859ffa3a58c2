"""Multiple intentions: EM clustering of demonstrations by reward function (Babeş-Vroman et al., ICML 2011).

K linear reward functions (weights ``[K, F]`` and temperatures) and mixing
proportions ``rho [K]``. E-step: responsibilities
``r[d, k] ∝ rho[k] * P(demo d | reward k)`` from the per-demonstration
log-likelihoods of :class:`~groundlang.inference.mlirl.MLIRLProblem`. M-step:
MLIRL for each cluster with the responsibilities as demonstration weights
(warm-started from the previous iteration's weights and values), and
``rho = mean_d r[d, :]``. Initialisation is seeded: K distinct demonstrations
are drawn as cluster seeds (responsibility one for their cluster), the rest
get Dirichlet(1) responsibilities; the same seed gives the same clusters.
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
    resp = rng.dirichlet(np.ones(K), size=D)
    for k, d in enumerate(rng.choice(D, size=K, replace=False)):
        resp[d] = np.eye(K)[k]
    F = problems[0].num_features
    weights = np.zeros((K, F))
    temps = np.full(K, 1.0 if temperature is None else float(temperature))
    previous, converged, total = -math.inf, False, -math.inf
    iteration = 0
    with threads_for(problems[0].next_state.shape[0]):
        for iteration in range(1, max_iterations + 1):
            # M-step.
            priors = resp.mean(axis=0)
            for k in range(K):
                fit = mlirl(None, None, None, demo_weights=resp[:, k], temperature=temperature,
                            initial_temperature=temps[k], initial_weights=weights[k], max_steps=mlirl_steps,
                            problem=problems[k])
                weights[k], temps[k] = fit.weights, fit.temperature
            # E-step.
            with torch.no_grad():
                ll = np.stack([
                    problems[k].per_demo_log_likelihood(torch.as_tensor(weights[k], dtype=problems[k].dtype),
                                                        torch.tensor(temps[k], dtype=problems[k].dtype)).numpy()
                    for k in range(K)
                ], axis=1).astype(np.float64)  # [D, K]
            joint = ll + np.log(np.maximum(priors, 1e-300))
            norm = np.logaddexp.reduce(joint, axis=1)
            resp = np.exp(joint - norm[:, None])
            total = float(norm.sum())
            logger.debug("intentions EM iteration %d: log-likelihood %.4f", iteration, total)
            if total - previous < tol * D:
                converged = True
                break
            previous = total
    return IntentionsResult(weights.copy(), temps.copy(), resp, resp.mean(axis=0), total, iteration, converged)
