"""Model 0 of the paper (Algorithm 1): hand-coded EM for unigram words given reward functions.

Kept as a baseline for the Pyro model. With J reward functions R_j whose
behaviour likelihoods ``Pr(T_i | R_j)`` come from planning (or MLIRL),

    E step:  z_ji ∝ Pr(R_j) Pr(T_i | R_j) prod_{w in S_i} x_wj
    M step:  x_kj = (sum_i count_ik z_ji + eps) / (sum_i N(S_i) z_ji + K eps)

which is exactly the MAP fixed point of the Pyro ``bow`` model with one
token per reward function, no ``NULL`` token and a Dirichlet(1 + eps) prior.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

__all__ = ["Model0Result", "model0_em", "sentence_log_likelihood"]


@dataclass
class Model0Result:
    word_probs: torch.Tensor  # [J, K]: x_kj = Pr(w_k | R_j), rows sum to 1
    responsibilities: torch.Tensor  # [I, J]: z_ji
    iterations: int
    log_likelihoods: list[float]  # marginal log-likelihood of the data (words and behaviour) per iteration


def model0_em(
    word_counts: torch.Tensor,
    behaviour: torch.Tensor,
    log_prior: torch.Tensor | None = None,
    epsilon: float = 0.05,
    iterations: int = 200,
    seed: int = 0,
    tol: float = 1e-10,
) -> Model0Result:
    """Run Algorithm 1.

    ``word_counts``: ``[I, K]`` counts of each vocabulary word in each sentence.
    ``behaviour``: ``[I, J]`` log Pr(T_i | R_j). ``log_prior``: ``[J]`` (uniform by default).
    Stops after ``iterations`` or when the log-likelihood improves by less than ``tol``.
    """
    counts = torch.as_tensor(word_counts, dtype=torch.float64)
    behaviour = torch.as_tensor(behaviour, dtype=torch.float64)
    if counts.ndim != 2 or behaviour.ndim != 2 or counts.shape[0] != behaviour.shape[0]:
        raise ValueError(
            f"word_counts [I, K] and behaviour [I, J] must agree on I; got {tuple(counts.shape)} and {tuple(behaviour.shape)}"
        )
    I, K = counts.shape
    J = behaviour.shape[1]
    prior = torch.full((J,), -torch.log(torch.tensor(float(J), dtype=torch.float64))) if log_prior is None else torch.as_tensor(log_prior, dtype=torch.float64)
    gen = torch.Generator().manual_seed(seed)
    x = torch.rand(J, K, generator=gen, dtype=torch.float64) + 0.5  # "Initialize x randomly"
    x = x / x.sum(-1, keepdim=True)
    history: list[float] = []
    z = torch.full((I, J), 1.0 / J, dtype=torch.float64)
    it = 0
    for it in range(1, iterations + 1):
        logits = prior + behaviour + counts @ x.log().T  # [I, J]
        norm = torch.logsumexp(logits, -1, keepdim=True)
        z = torch.exp(logits - norm)
        history.append(float(norm.sum()))
        x = (z.T @ counts + epsilon) / ((z * counts.sum(-1, keepdim=True)).sum(0)[:, None] + K * epsilon)
        if len(history) > 1 and abs(history[-1] - history[-2]) < tol:
            break
    return Model0Result(x, z, it, history)


def sentence_log_likelihood(result: Model0Result, word_counts: torch.Tensor) -> torch.Tensor:
    """``log Pr(S | R_j)`` for each reward function: ``[J]`` for counts ``[K]`` (or ``[N, J]`` for ``[N, K]``)."""
    counts = torch.as_tensor(word_counts, dtype=torch.float64)
    return counts @ result.word_probs.log().T
