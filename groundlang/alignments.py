"""Which object each noun phrase of a command names: the alignment posterior of a trained learner.

``P(phrase k aligns with the object in role v | words, interpretation j, reading s)`` comes from the
language model's own words term with the phrase's alignment fixed (``alignment_probabilities``), so it is
exact with the mention model, not a second copy of the model.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from groundlang.inference.joint import local_posteriors

__all__ = ["PhraseAlignment", "phrase_alignments"]


@dataclass(frozen=True)
class PhraseAlignment:
    """One noun phrase: its preposition key, its words, and the objects it may name with their
    probabilities (``None`` for "nothing"), most probable first."""

    key: str
    words: tuple[str, ...]
    objects: tuple[tuple[str | None, str, float], ...]  # (object, role, probability)


def phrase_alignments(learner, command: str, state, interpretation: int | None = None) -> list[PhraseAlignment]:
    """The alignments of ``command``'s phrases in ``state`` under interpretation ``interpretation`` (an
    index of ``learner.posterior(command, state).interpretations``; default the most probable) and the
    most probable reading. Empty for a language model that aligns no phrases."""
    learner._require_fitted()
    learner._check_state("alignments", command, state)
    obs = learner._command_observation(command, state)
    batch = learner.lm.encode([obs], learner.vocab)
    z, structures = local_posteriors(batch, learner.lm, learner.globals, use_behaviour=False)
    if structures is None:
        return []
    J = len(obs.interpretations)
    j = int(z[0, :J].argmax()) if interpretation is None else interpretation
    if isinstance(j, bool) or not isinstance(j, int) or not 0 <= j < J:  # 1.5 indexed a tensor, "0" compared a str
        raise ValueError(f"alignments: interpretation must be an index below {J}, not {interpretation!r:.40}")
    s = int(structures[0].argmax())
    table = learner.lm.alignment_probabilities(learner.globals, batch, j, s)
    if table is None:
        return []
    roles = obs.interpretations[j].roles
    vocab, out = learner.vocab, []
    for k in range(int(batch.type_mask[0].sum())):
        if batch.reading_types[0, s, k] == 0:
            continue
        said = (batch.type_counts[0, k] + batch.type_head_counts[0, k]) > 0
        words = tuple(vocab.words[int(u)] for u in batch.uniq[0][said])
        order = torch.argsort(table[k], descending=True)
        objects = tuple((None if v == 0 else roles[v - 1].obj, "none" if v == 0 else roles[v - 1].role,
                         float(table[k, v])) for v in order.tolist() if table[k, v] > 0)
        out.append(PhraseAlignment(vocab.preps[int(batch.type_prep[0, k])], words, objects))
    return out
