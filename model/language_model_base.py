"""The base of the language models E | L, C: Dirichlet word distributions per semantic token and the
mixtures of tokens words are emitted from (``model.language_models`` lists the models)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pyro
import pyro.distributions as dist
import torch

from groundlang.model.encoding import Batch, PhraseKeys

__all__ = ["LanguageModel", "NULL_MIXTURE", "mixture_log_emissions", "gather_mixtures", "require_positive"]


class LanguageModel:
    """Base: Dirichlet word distributions per semantic token."""

    name = "base"
    # Whether interpretations enumerate binding constraints C (see model.interpretations).
    enumerates_constraints = True
    # Whether training starts from the bag of words' word distributions: an alignment model's MAP from a
    # flat start lands in poor local optima, as IBM Model 2 is classically started from Model 1.
    starts_from_bag_of_words = True
    # What the interpretations offer (model.interpretations.interpretations); the parse model has these
    # as settings, and its preposition keys' marks (phrase_keys).
    relation_words = False
    held_parts = False
    relational_descriptions = False
    start_role = True
    bystander_roles = True

    def __init__(self, word_concentration: float = 1.05, null_token: bool = True):
        # Dirichlet(1 + eps) MAP == EM with add-eps smoothing (Model 0's epsilon).
        require_positive(self.name, "word_concentration", word_concentration)
        self.word_concentration = word_concentration
        self.null_token = null_token

    def settings(self) -> dict:
        return {"word_concentration": self.word_concentration, "null_token": self.null_token}

    def phrase_keys(self) -> PhraseKeys:
        """The marks of the noun phrases' preposition keys this model's batches are encoded with."""
        return PhraseKeys()

    def sample_globals(
        self, num_tokens: int, num_words: int, num_roles: int, num_preps: int, role_names: tuple[str, ...] = (),
        num_tasks: int = 0, offered: tuple[tuple[bool, ...], ...] = (),
    ) -> dict:
        with pyro.plate("tokens", num_tokens, dim=-1):
            phi = pyro.sample(
                "phi", dist.Dirichlet(torch.full((num_words,), self.word_concentration))
            )
        return {"phi": phi}

    def log_likelihood(self, g: dict, batch: Batch) -> torch.Tensor:
        """``log P(words_i | interpretation j)`` as ``[I, J]``, readings and alignments summed out."""
        raise NotImplementedError

    def reading_probabilities(self, g: dict, batch: Batch, prior: Sequence[float]) -> np.ndarray | None:
        """``P(reading | words)`` for the one command of ``batch``, whose parser readings have prior
        probabilities ``prior``; None for a model that reads no parse."""
        return None


def require_positive(model: str, name: str, value: float) -> None:
    if not value > 0:  # also refuses NaN
        raise ValueError(f"language model {model}: {name} must be > 0 (a Dirichlet concentration), not {value!r}")


NULL_MIXTURE = 0  # encode() interns the {NULL} mixture first


def mixture_log_emissions(g: dict, batch: Batch) -> torch.Tensor:
    """``log P(word u of instance i | mixture x)`` as ``[X, I, U]``."""
    emit = batch.mixtures @ g["phi"]  # [X, W]
    return emit[:, batch.uniq].clamp_min(1e-30).log()


def gather_mixtures(log_emit: torch.Tensor, mix_ids: torch.Tensor) -> torch.Tensor:
    """``log_emit [X, I, U]`` at ``mix_ids [I, ...]`` -> ``[I, ..., U]``."""
    I, U = log_emit.shape[1], log_emit.shape[2]
    flat = mix_ids.reshape(I, -1)  # [I, Q]
    per_instance = log_emit.permute(1, 0, 2)  # [I, X, U]
    out = torch.gather(per_instance, 1, flat[..., None].expand(-1, -1, U))
    return out.reshape(*mix_ids.shape, U)
