"""The three language models E | L, C, switchable by name for ablations.

Each model declares its global parameters as Pyro sample sites with
Dirichlet (or other) priors and computes, from them, the table
``log P(words_i | interpretation j)`` of shape ``[I, J]``. No discrete latent
is sampled here: alignments and readings are summed out exactly inside the
table, and the interpretation itself is enumerated by the model in
:mod:`groundlang.model.generative`.

- ``bow``: each word comes from a uniform mixture over the semantic tokens
  of L and C plus ``NULL`` (Model 0 of the paper is this with one token per
  reward function and no ``NULL``).
- ``ibm2``: IBM Model 2 over the machine string of (L, C), with a learned
  distortion that prefers words and tokens at the same relative position.
- ``parse``: words are generated through the logical form. Each noun phrase
  aligns with a role of the interpretation (the toy, the goal room, the
  agent's start room, ...) or with nothing, with a learned table
  ``P(role | preposition)``; its words come from the tokens of the object in
  that role, the remaining words from L or ``NULL``. Readings are weighted by
  the parser's probabilities.
"""

from __future__ import annotations

import pyro
import pyro.distributions as dist
import torch

from groundlang.model.encoding import PAD_LOGIT, Batch

__all__ = ["LanguageModel", "BagOfWords", "IBMModel2", "ParseAligned", "LANGUAGE_MODELS", "get_language_model"]


class LanguageModel:
    """Base: Dirichlet word distributions per semantic token."""

    name = "base"

    def __init__(self, word_concentration: float = 1.05, null_token: bool = True):
        # Dirichlet(1 + eps) MAP == EM with add-eps smoothing (Model 0's epsilon).
        self.word_concentration = word_concentration
        self.null_token = null_token

    def settings(self) -> dict:
        return {"word_concentration": self.word_concentration, "null_token": self.null_token}

    def sample_globals(self, num_tokens: int, num_words: int, num_roles: int, num_preps: int) -> dict:
        with pyro.plate("tokens", num_tokens, dim=-1):
            phi = pyro.sample(
                "phi", dist.Dirichlet(torch.full((num_words,), self.word_concentration))
            )
        return {"phi": phi}

    def log_likelihood(self, g: dict, batch: Batch) -> torch.Tensor:
        raise NotImplementedError


class BagOfWords(LanguageModel):
    name = "bow"

    def log_likelihood(self, g: dict, batch: Batch) -> torch.Tensor:
        phi = g["phi"]  # [S, W]
        tokens = batch.bow_tokens  # [I, J, S]
        if not self.null_token:
            tokens = tokens.clone()
            tokens[..., 0] = 0.0
        weights = tokens / tokens.sum(-1, keepdim=True).clamp_min(1.0)
        per_word = phi[:, batch.words].permute(1, 0, 2)  # [I, S, N]
        mix = torch.bmm(weights, per_word)  # [I, J, N]
        return (mix.clamp_min(1e-30).log() * batch.word_mask[:, None, :]).sum(-1)


class IBMModel2(LanguageModel):
    name = "ibm2"

    def sample_globals(self, num_tokens, num_words, num_roles, num_preps):
        g = super().sample_globals(num_tokens, num_words, num_roles, num_preps)
        # Sharpness of the diagonal preference, and the share of NULL.
        g["distortion"] = pyro.sample("distortion", dist.Gamma(2.0, 0.5))
        g["null_share"] = pyro.sample("null_share", dist.Beta(2.0, 8.0))
        return g

    def log_likelihood(self, g: dict, batch: Batch) -> torch.Tensor:
        phi = g["phi"]
        words, wmask = batch.words, batch.word_mask  # [I, N]
        machine, mmask = batch.machine, batch.machine_mask  # [I, J, M]
        n_len = wmask.sum(-1).clamp_min(1).float()  # [I]
        m_len = (mmask.sum(-1) - 1).clamp_min(1).float()  # [I, J] non-NULL positions
        N, M = words.shape[1], machine.shape[2]
        rel_n = (torch.arange(N).float() + 0.5)[None, :] / n_len[:, None]  # [I, N]
        rel_m = (torch.arange(M).float() - 0.5)[None, None, :] / m_len[..., None]  # [I, J, M]
        dist_logits = -g["distortion"] * (rel_m[:, :, :, None] - rel_n[:, None, None, :]).abs()
        real = mmask.clone()
        real[..., 0] = False
        dist_logits = dist_logits.masked_fill(~real[..., None], PAD_LOGIT)
        d = torch.softmax(dist_logits, dim=2) * (1 - g["null_share"])  # [I, J, M, N]
        d[:, :, 0, :] = g["null_share"]
        emit = phi[machine[:, :, :, None], words[:, None, None, :]]  # [I, J, M, N]
        p = (d * emit).sum(2)  # [I, J, N]
        return (p.clamp_min(1e-30).log() * wmask[:, None, :]).sum(-1)


class ParseAligned(LanguageModel):
    name = "parse"

    def __init__(self, word_concentration: float = 1.05, align_concentration: float = 1.5):
        super().__init__(word_concentration)
        self.align_concentration = align_concentration

    def settings(self) -> dict:
        return {**super().settings(), "align_concentration": self.align_concentration}

    def sample_globals(self, num_tokens, num_words, num_roles, num_preps):
        g = super().sample_globals(num_tokens, num_words, num_roles, num_preps)
        with pyro.plate("preps", num_preps, dim=-1):
            g["align"] = pyro.sample(
                "align", dist.Dirichlet(torch.full((num_roles,), self.align_concentration))
            )
        return g

    def log_likelihood(self, g: dict, batch: Batch) -> torch.Tensor:
        return self.reading_table(g, batch)[0]

    def reading_table(self, g: dict, batch: Batch):
        """``(log P(words | j) [I, J], per-reading [I, J, R], entity-role log-weights [I, J, V, R, E])``."""
        phi, align = g["phi"], g["align"]
        phi_u = phi[:, batch.uniq].permute(1, 0, 2)  # [I, S, U]
        weights = batch.role_tokens / batch.role_tokens.sum(-1, keepdim=True)  # [I, J, V, S]
        log_emit = torch.einsum("ijvs,isu->ijvu", weights, phi_u).clamp_min(1e-30).log()
        entity_ll = torch.einsum("ijvu,ireu->ijvre", log_emit, batch.entity_counts)
        log_align = align.clamp_min(1e-30).log()[
            batch.entity_prep[:, None, None, :, :], batch.role[:, :, :, None, None]
        ]  # [I, J, V, R, E]
        joint = (entity_ll + log_align).masked_fill(~batch.role_mask[..., None, None], PAD_LOGIT)
        per_entity = torch.logsumexp(joint, dim=2)  # [I, J, R, E]
        entities = (per_entity * batch.entity_mask[:, None]).sum(-1)  # [I, J, R]
        U = phi_u.shape[-1]
        task_word = torch.gather(phi_u, 1, batch.lifted[:, :, None].expand(-1, -1, U))  # [I, J, U]
        log_frame = (0.5 * (task_word + phi_u[:, None, 0, :])).clamp_min(1e-30).log()
        frame = torch.einsum("iju,iru->ijr", log_frame, batch.frame_counts)
        per_reading = entities + frame + batch.reading_logp[:, None, :]
        return torch.logsumexp(per_reading, dim=-1), per_reading, joint


LANGUAGE_MODELS = {"bow": BagOfWords, "ibm2": IBMModel2, "parse": ParseAligned}


def get_language_model(name: str, **kwargs) -> LanguageModel:
    try:
        return LANGUAGE_MODELS[name](**kwargs)
    except KeyError:
        raise ValueError(
            f"unknown language model {name!r}; expected one of {', '.join(LANGUAGE_MODELS)}"
        ) from None
