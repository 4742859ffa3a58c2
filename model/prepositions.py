"""What the parse model learned prepositions to say: ``P(lifted task | preposition)`` from its table
``P(preposition | L)`` (``ParseAligned``'s ``preposition_concentration``); ``groundlang lexicon --prepositions``
prints it, notebook 05 draws it."""

from __future__ import annotations

import torch

from groundlang.model.language_model_base import LEARNED_SHARE
from groundlang.model.phrase_keys import bare_preposition
from groundlang.model.vocabulary import DIRECT_OBJECT, NEGATED_PREP, OTHER_PREP

__all__ = ["preposition_table", "preposition_tasks"]

# Keys of the vocabulary that are no preposition anyone says.
_RESERVED = frozenset({OTHER_PREP, DIRECT_OBJECT, NEGATED_PREP})


def preposition_table(g: dict, vocab) -> tuple[list[str], list[str], torch.Tensor]:
    """``(lifted tasks, prepositions, P(L | preposition) [tasks, prepositions])`` from the parse model's
    table ``P(preposition | L)`` under a uniform prior over L: what "left of" was learned to say.

    The prepositions are those training gave mass to (the rule :func:`word_meanings` uses for words);
    the unseen and direct-object keys are left out (neither is a word, and a direct object generates no
    key), and so are the keys the alignment table uses (``to|last``): this table is indexed by the bare
    preposition. Empty for globals without the table (``preposition_concentration`` None, another model)."""
    if "preposition" not in g or not vocab.tasks:
        return [], [], torch.zeros(0, 0)
    by_task = g["preposition"].detach().double()  # [L, P]
    learned = by_task.max(0).values > LEARNED_SHARE / by_task.shape[1]
    shown = [k for k, prep in enumerate(vocab.preps)
             if prep not in _RESERVED and learned[k] and bare_preposition(prep) == prep]
    given = by_task / by_task.sum(0, keepdim=True).clamp_min(1e-300)
    return list(vocab.tasks), [vocab.preps[k] for k in shown], given[:, shown]


def preposition_tasks(g: dict, vocab, top: int = 3) -> dict[str, list[tuple[str, float]]]:
    """Each preposition of :func:`preposition_table` with its ``top`` most probable lifted tasks."""
    tasks, preps, given = preposition_table(g, vocab)
    out = {}
    for j, prep in enumerate(preps):
        order = torch.argsort(given[:, j], descending=True)[:top]
        out[prep] = [(tasks[int(t)], float(given[t, j])) for t in order]
    return out
