"""The generative model of words, interpretations and demonstrations, in Pyro.

Per instance i with initial state S_i::

    z_i = (L, T, C) ~ prior over interpretations of S_i   # uniform L, T | L, C | L, T
    B_i | T         ~ Boltzmann policy on T's reward       # pyro.factor from a cached table
    E_i | L, C      ~ language model with global params    # pyro.factor, alignments summed out

The interpretation is enumerated exactly (``TraceEnum_ELBO``); the global
word distributions are Dirichlet-distributed and fitted by MAP.
"""

from __future__ import annotations

import pyro
import pyro.distributions as dist
import torch
from pyro.ops.indexing import Vindex

from groundlang.model.encoding import Batch
from groundlang.model.language_models import LanguageModel
from groundlang.model.vocabulary import Vocabulary

__all__ = ["instance_model", "global_sizes", "LOCAL_SITES"]

# The sites enumerated per instance (the rest are the globals): the interpretation, and the reading
# for a language model that reads parses.
LOCAL_SITES = ("z", "reading")


def global_sizes(vocab: Vocabulary) -> dict:
    return {
        "num_tokens": len(vocab.tokens),
        "num_tasks": len(vocab.tasks),
        "num_words": len(vocab.words),
        "num_roles": len(vocab.roles),
        "num_preps": len(vocab.preps),
        "prep_names": tuple(vocab.preps),
        "role_names": tuple(vocab.roles),
        "name_families": len(vocab.families),
        # offered[t][v]: whether lifted task t can offer role v (Vocabulary.offers_role)
        "offered": tuple(tuple(vocab.offers_role(t, r) for r in vocab.roles) for t in vocab.tasks),
    }


def instance_model(batch: Batch, lm: LanguageModel, sizes: dict, use_behaviour: bool = True) -> torch.Tensor:
    """The Pyro model; returns the words table ``[I, J]`` for inspection.

    For a language model that reads parses (``words_by_reading``), the reading is a site too, given
    the interpretation, enumerated with it."""
    g = lm.sample_globals(**sizes)
    by_reading = lm.words_by_reading(g, batch)
    if by_reading is None:
        words_ll = lm.log_likelihood(g, batch)  # [I, J]
    else:
        table, reading_logits = by_reading  # [I, J, S], [I, S]
        words_ll = torch.logsumexp(table + reading_logits[:, None, :], dim=-1)
    I = batch.num_instances
    idx = torch.arange(I)
    with pyro.plate("instances", I, dim=-1):
        z = pyro.sample(
            "z", dist.Categorical(logits=batch.log_prior), infer={"enumerate": "parallel"}
        )
        if use_behaviour:
            pyro.factor("behaviour", Vindex(batch.behaviour)[idx, z])
        if by_reading is None:
            pyro.factor("words", Vindex(words_ll)[idx, z])
        else:
            reading = pyro.sample("reading", dist.Categorical(logits=reading_logits),
                                  infer={"enumerate": "parallel"})
            pyro.factor("words", Vindex(table)[idx, z, reading])
    return words_ll
