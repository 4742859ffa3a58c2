"""The bag of words (``bow``): each word of a command comes from a uniform mixture over the semantic
tokens of L and C plus ``NULL``; the paper's Model 0 is this with one token per reward function and no
``NULL`` (``null_token=False``). It reads the batch every model reads (``model.encoding.Batch``)."""

from __future__ import annotations

import torch

from groundlang.model.encoding import Batch, Encoder
from groundlang.model.language_model_base import LanguageModel, gather_mixtures, mixture_log_emissions

__all__ = ["BagOfWords"]


class BagOfWords(LanguageModel):
    """Words from the mixture of the interpretation's tokens; every model's training starts from it."""

    name = "bow"
    starts_from_bag_of_words = False

    def encode_fields(self, enc: Encoder) -> dict:
        if self.null_token:
            return {}  # the shared bow_mix is {L} + C + {NULL}
        mix = enc.per_interpretation(enc.null_mixture)
        for i, j, interp in enc.interpretations():
            lid, said = enc.said_tokens(interp)
            mix[i, j] = enc.mixture([lid] + said)
        return {"bow_mix": mix}

    def log_likelihood(self, g: dict, batch: Batch) -> torch.Tensor:
        per_word = gather_mixtures(mixture_log_emissions(g, batch), batch.bow_mix, batch.uniq)  # [I, J, U]
        return (per_word * batch.word_counts[:, None, :]).sum(-1)
