"""Folding one more example into trained globals: incremental EM on the word distributions.

MAP-EM (:func:`groundlang.inference.joint.fit_globals`) stops at a fixed point where each row of a
Dirichlet global is its expected counts plus the prior's ``alpha - 1``, normalised::

    phi[s] = (n[s] + alpha - 1) / Z[s],    Z[s] = sum_w n[s, w] + W (alpha - 1)

Column 0 of ``phi`` is ``<unk>``, which no training word is (every word of the training commands
is in the vocabulary), so ``n[s, <unk>] = 0`` and ``Z[s] = (alpha - 1) / phi[s, <unk>]``: the old
data's counts ``phi * Z`` come back exactly from a saved model, with no training data. A new
example then adds its own expected counts, recomputed by E steps on it alone while the old ones
stay as they were: incremental EM (Neal and Hinton 1998) with the old instances' responsibilities
frozen at the fixed point, which is what refitting would move least. A word the vocabulary never
had gets a column with no old counts, ``(alpha - 1) / Z[s]``, exactly what training with it in the
vocabulary but never seen would have given.

The other globals (alignment, mention, arity, frame and verb shares) keep their values: their rows
have no entry that is never observed, so their old counts are not recoverable from the model, and
one example of a construction the model knows says little about them.
"""

from __future__ import annotations

import torch

from groundlang.inference.joint import log_joint, prior_concentrations, single_threaded
from groundlang.model.encoding import Batch
from groundlang.model.language_models import LanguageModel
from groundlang.model.vocabulary import Vocabulary

__all__ = ["word_totals", "grow_words", "fold_in"]

WORDS = "phi"


def word_totals(phi: torch.Tensor, word_concentration: float) -> torch.Tensor:
    """``Z [S]``: per semantic token, its expected word count in training plus the prior's
    ``W (alpha - 1)``, read off the ``<unk>`` column of ``phi [S, W]`` (see the module docstring).

    ValueError when the prior adds no pseudo-count (``word_concentration <= 1``: ``<unk>`` then
    carries nothing to read the totals from) or ``phi`` has no positive ``<unk>`` column."""
    if not word_concentration > 1:
        raise ValueError(f"updating needs a word_concentration above 1 (the model's is {word_concentration!r}): "
                         "the old counts are read from the prior's pseudo-count of <unk>")
    unk = phi[:, 0]
    if not bool((unk > 0).all()):
        raise ValueError("the word distributions give <unk> no probability; their training counts cannot be read")
    return (word_concentration - 1) / unk.double()


def grow_words(phi: torch.Tensor, totals: torch.Tensor, new: int, word_concentration: float):
    """``(phi [S, W + new], totals [S])``: ``new`` word columns with no counts, appended."""
    if new == 0:
        return phi, totals
    pseudo = word_concentration - 1
    counts = phi.double() * totals[:, None]  # n + alpha - 1
    counts = torch.cat([counts, torch.full((phi.shape[0], new), pseudo, dtype=counts.dtype)], dim=1)
    totals = totals + new * pseudo
    return (counts / totals[:, None]).to(phi.dtype), totals


def fold_in(batch: Batch, lm: LanguageModel, vocab: Vocabulary, globals_: dict[str, torch.Tensor],
            totals: torch.Tensor, steps: int = 50, tol: float = 1e-6) -> tuple[dict[str, torch.Tensor], int]:
    """EM on ``batch`` (the new example, encoded with ``vocab``) with the old counts ``phi * totals``
    held fixed; returns the new globals (only ``phi`` changes) and the number of E steps run.

    ``globals_["phi"]`` must already have a column for every word of ``vocab`` (:func:`grow_words`).
    Stops when no probability of ``phi`` moves by more than ``tol``, or after ``steps``."""
    phi = globals_[WORDS]
    if phi.shape != (len(vocab.tokens), len(vocab.words)):
        raise ValueError(f"phi is {tuple(phi.shape)}; the vocabulary has {len(vocab.tokens)} tokens and "
                         f"{len(vocab.words)} words")
    old = phi.double() * totals[:, None]  # [S, W]: n_old + alpha - 1
    pseudo = prior_concentrations(batch, lm, vocab)[WORDS] - 1  # [S, W]
    values = dict(globals_)
    done = 0
    with single_threaded():
        for done in range(1, steps + 1):
            leaf = values[WORDS].clone().requires_grad_(True)
            log_joint(batch, lm, vocab, {**values, WORDS: leaf}).backward()
            with torch.no_grad():
                # phi * d log p / d phi = the new example's expected counts + alpha - 1 (the prior's share).
                new = (leaf * leaf.grad - pseudo).clamp_min(0).double()
                counts = old + new
                updated = (counts / counts.sum(-1, keepdim=True)).to(phi.dtype)
                moved = float((updated - values[WORDS]).abs().max())
                values[WORDS] = updated
            if moved <= tol:
                break
    return values, done
