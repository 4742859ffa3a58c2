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
- ``parse``: words are generated through the logical form (``model.parse_aligned``).
"""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass

import pyro
import pyro.distributions as dist
import torch

from groundlang.model.encoding import Batch, Encoder, machine_string, pad_rows
from groundlang.model.language_model_base import NULL_MIXTURE, LanguageModel, gather_mixtures, mixture_log_emissions
from groundlang.model.parse_aligned import ParseAligned

__all__ = ["LanguageModel", "BagOfWords", "IBMModel2", "MachineBatch", "ParseAligned", "LANGUAGE_MODELS", "get_language_model",
           "register_language_model", "setting_names", "NULL_MIXTURE", "mixture_log_emissions"]


class BagOfWords(LanguageModel):
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


@dataclass
class MachineBatch(Batch):
    """A :class:`Batch` with the command's words in order and each interpretation's machine string."""

    words: torch.Tensor  # [I, N] word ids in order
    word_mask: torch.Tensor  # [I, N] bool
    machine: torch.Tensor  # [I, J, M] token ids of the machine string (NULL first)
    machine_mask: torch.Tensor  # [I, J, M] bool


class IBMModel2(LanguageModel):
    """IBM Model 2: word n aligns with machine position m with a learned distortion.

    The distortion is Brown et al.'s a(m | n, N, M) with the word's position
    coarsened to ``POSITION_BINS`` bins of n / N: one categorical over the
    machine positions (NULL first) per (bin, M). Everything is then a
    Dirichlet-categorical, so EM through the Pyro model is exact, as for the
    other language models.
    """

    name = "ibm2"
    # A machine token need not generate any word, so the string can carry every
    # colour/shape PF of the bound objects and alignment picks what was said.
    enumerates_constraints = False
    batch_type = MachineBatch

    def encode_fields(self, enc: Encoder) -> dict:
        vocab = enc.vocab
        machines = [[[enc.null]] * enc.num_interpretations for _ in range(enc.num_instances)]
        for i, j, interp in enc.interpretations():
            machines[i][j] = [enc.null] + [vocab.token_id(t) for t in machine_string(interp)]
        M = max(len(m) for row in machines for m in row)
        machine = torch.full((enc.num_instances, enc.num_interpretations, M), enc.null, dtype=torch.long)
        machine_mask = torch.zeros(machine.shape, dtype=torch.bool)
        for i, row in enumerate(machines):
            for j, m in enumerate(row):
                machine[i, j, : len(m)] = torch.tensor(m)
                machine_mask[i, j, : len(m)] = j < len(enc.observations[i].interpretations)
        return {"words": pad_rows([[vocab.word_id(w) for w in o.words] for o in enc.observations], 0, torch.long),
                "word_mask": pad_rows([[True] * len(o.words) for o in enc.observations], False, torch.bool),
                "machine": machine, "machine_mask": machine_mask}

    def sample_globals(self, num_tokens, num_words, num_roles, num_preps, role_names=(), num_tasks=0, offered=(),
                       name_families=0):
        g = super().sample_globals(num_tokens, num_words, num_roles, num_preps, name_families=name_families)
        contexts = POSITION_BINS * (MAX_MACHINE + 1)
        with pyro.plate("distortion_contexts", contexts, dim=-1):
            g["distortion"] = pyro.sample(
                "distortion", dist.Dirichlet(torch.full((MAX_MACHINE,), self.word_concentration))
            )
        return g

    def log_likelihood(self, g: dict, batch: Batch) -> torch.Tensor:
        words, wmask = batch.words, batch.word_mask  # [I, N]
        machine, mmask = batch.machine, batch.machine_mask  # [I, J, M]
        M = machine.shape[2]
        if M > MAX_MACHINE:
            raise ValueError(f"machine strings of {M} tokens exceed IBM Model 2's limit of {MAX_MACHINE}")
        n_len = wmask.sum(-1).clamp_min(1)  # [I]
        position_bin = (torch.arange(words.shape[1])[None, :] * POSITION_BINS) // n_len[:, None]
        position_bin = position_bin.clamp_max(POSITION_BINS - 1)  # [I, N]
        m_len = mmask.sum(-1)  # [I, J]
        context = position_bin[:, None, :] * (MAX_MACHINE + 1) + m_len[:, :, None]  # [I, J, N]
        d = g["distortion"][context][..., :M]  # [I, J, N, M]
        d = d * mmask[:, :, None, :]
        emit = g["phi"][machine[:, :, None, :], words[:, None, :, None]]  # [I, J, N, M]
        p = (d * emit).sum(-1)  # [I, J, N]
        return (p.clamp_min(1e-30).log() * wmask[:, None, :]).sum(-1)


POSITION_BINS = 4  # IBM Model 2: word positions coarsened to quarters of the command
MAX_MACHINE = 24  # IBM Model 2: longest machine string (NULL included)

LANGUAGE_MODELS = {"bow": BagOfWords, "ibm2": IBMModel2, "parse": ParseAligned}


def register_language_model(model: type[LanguageModel]) -> type[LanguageModel]:
    """Make a language model available by its ``name`` (``Learner("mine")``, saved models, ablations);
    usable as a class decorator. A model is a :class:`LanguageModel` subclass: its globals as Pyro
    sites (``sample_globals``), ``log P(words | interpretation)`` (``log_likelihood``) and, if it
    reads parses, ``words_by_reading``. ValueError for a name taken by another model."""
    if not (isinstance(model, type) and issubclass(model, LanguageModel)) or model is LanguageModel:
        raise TypeError(f"register_language_model: expected a LanguageModel subclass, got {model!r}")
    known = LANGUAGE_MODELS.get(model.name)
    if known is not None and known is not model:
        raise ValueError(f"a language model called {model.name!r} exists already ({known.__qualname__})")
    LANGUAGE_MODELS[model.name] = model
    return model


def get_language_model(name: str, **settings) -> LanguageModel:
    """The language model ``name`` with ``settings`` (its constructor's keywords, e.g.
    ``get_language_model("parse", mention_phrases="any")``). Raises ValueError naming the model
    and what it takes for an unknown name, an unknown setting or a value of the wrong kind."""
    params = _parameters(name)
    for key, value in settings.items():
        if key not in params:
            raise ValueError(f"language model {name} has no setting {key!r}; its settings: {', '.join(params)}")
        problem = _setting_problem(params[key], value)
        if problem:
            raise ValueError(f"language model {name}, setting {key}: {problem}")
    return LANGUAGE_MODELS[name](**settings)


def setting_names(name: str) -> tuple[str, ...]:
    """The settings (constructor keywords) language model ``name`` takes."""
    return tuple(_parameters(name))


def _parameters(name: str) -> dict[str, inspect.Parameter]:
    """Constructor keyword -> its parameter, for language model ``name``; ValueError for an unknown name."""
    if name not in LANGUAGE_MODELS:
        raise ValueError(f"unknown language model {name!r}; expected one of {', '.join(LANGUAGE_MODELS)}")
    return {k: p for k, p in inspect.signature(LANGUAGE_MODELS[name].__init__).parameters.items() if k != "self"}


def _setting_problem(param: inspect.Parameter, value) -> str | None:
    """What is wrong with ``value`` for a constructor keyword, judged by its default and annotation."""
    default, optional = param.default, "None" in str(param.annotation)
    if value is None:
        return None if optional or default is None else "None is not allowed here"
    if isinstance(default, bool):
        return None if isinstance(value, bool) else f"expected true or false, not {value!r}"
    if "dict" in str(param.annotation):  # checked by the model itself, which knows the keys
        return None if isinstance(value, dict) else f"expected names with values, e.g. {{\"name\": 1.0}}, not {value!r}"
    if isinstance(default, (int, float)) or default is None:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
        return None if ok else f"expected a number, not {value!r}"
    if isinstance(default, str):
        return None if isinstance(value, str) else f"expected a string, not {value!r}"
    return None
