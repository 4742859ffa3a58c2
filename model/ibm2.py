"""IBM Model 2 (``ibm2``) over the machine string of (L, C): each word aligns with a position of the
string (``NULL`` first) with a learned distortion that prefers words and tokens at the same relative
position, and comes from that token's word distribution."""

from __future__ import annotations

from dataclasses import dataclass

import pyro
import pyro.distributions as dist
import torch

from groundlang.model.encoding import Batch, Encoder, machine_string, pad_rows
from groundlang.model.language_model_base import LanguageModel

__all__ = ["IBMModel2", "MachineBatch", "POSITION_BINS", "MAX_MACHINE"]

POSITION_BINS = 4  # IBM Model 2: word positions coarsened to quarters of the command
MAX_MACHINE = 24  # IBM Model 2: longest machine string (NULL included)


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
                       name_families=0, prep_names=()):
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
