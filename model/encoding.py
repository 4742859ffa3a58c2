"""Observations and their padded tensor encoding for the generative model.

An :class:`Observation` is what the model sees of one instance: the
command's words and logical-form readings, the interpretations (L, T, C) of
its initial state and, when training, the behaviour log-likelihood of the
demonstration under each interpretation's grounded task. Candidate sets are
ragged across instances, so :func:`encode` pads them and keeps masks.

Shapes below use I instances, J interpretations, S semantic tokens,
N word positions, M machine-string positions, R readings, E entities,
U distinct entity/frame words, V roles.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import torch

from groundlang.grammar.logical_form import LogicalForm, Reading
from groundlang.model.interpretations import Interpretation, class_of
from groundlang.model.vocabulary import NULL, Vocabulary, class_token

__all__ = ["Observation", "Batch", "encode", "entity_words", "machine_string", "PAD_LOGIT"]

# Padded interpretations get this log-weight: exp() underflows to 0 while
# logsumexp and its gradient stay finite (an -inf would give NaN gradients).
PAD_LOGIT = -1.0e4


@dataclass(frozen=True)
class Observation:
    """One instance as the model sees it."""

    words: tuple[str, ...]
    readings: tuple[Reading, ...]
    interpretations: tuple[Interpretation, ...]
    behaviour: tuple[float, ...] | None = None  # per interpretation; None when only words are seen


@dataclass
class Batch:
    """Padded tensors for a list of observations; see the module docstring for shapes."""

    log_prior: torch.Tensor  # [I, J], PAD_LOGIT where padded
    behaviour: torch.Tensor  # [I, J], 0 where padded or unobserved
    mask: torch.Tensor  # [I, J] bool
    lifted: torch.Tensor  # [I, J] token id of the lifted task
    bow_tokens: torch.Tensor  # [I, J, S] 0/1: {L} + C + {NULL}
    words: torch.Tensor  # [I, N] word ids
    word_mask: torch.Tensor  # [I, N] bool
    machine: torch.Tensor  # [I, J, M] token ids of the machine string (NULL first)
    machine_mask: torch.Tensor  # [I, J, M] bool
    uniq: torch.Tensor  # [I, U] distinct word ids of the command
    reading_logp: torch.Tensor  # [I, R], PAD_LOGIT where padded
    entity_counts: torch.Tensor  # [I, R, E, U] counts of each word in each entity
    entity_prep: torch.Tensor  # [I, R, E] preposition class ids
    entity_mask: torch.Tensor  # [I, R, E] bool
    frame_counts: torch.Tensor  # [I, R, U] counts of words outside entities
    role: torch.Tensor  # [I, J, V] role ids (0 = aligned with nothing)
    role_mask: torch.Tensor  # [I, J, V] bool
    role_tokens: torch.Tensor  # [I, J, V, S] 0/1 tokens a word aligned with the role may come from

    @property
    def num_instances(self) -> int:
        return self.log_prior.shape[0]


def entity_words(lf: LogicalForm) -> list[tuple[str | None, tuple[str, ...]]]:
    """(preposition key, content words) per entity of a logical form.

    The key is the preposition for a verb-attached phrase, ``prep@np`` for a
    phrase attached to another noun phrase (the two readings of "push the
    star into the green room" differ here) and None for a direct object.
    Phrases in a negated clause ("do not enter the green room") get a
    ``not:`` prefix, so they may learn to align with nothing.
    """
    negated = {i for i, clause in enumerate(lf.clauses) if getattr(clause, "negated", False)}
    result = []
    for entity in lf.entities:
        if entity.role == "npp":
            key = f"{entity.prep}@np"
        elif entity.prep is not None:
            key = entity.prep
        else:
            key = None
        if entity.clause in negated:
            key = f"not:{key or 'dobj'}"
        content = tuple(entity.modifiers) + ((entity.head,) if entity.head else ())
        result.append((key, content))
    return result


def machine_string(interp: Interpretation) -> list[str]:
    """IBM Model 2's target: goal PFs and constraint PFs with their argument classes."""
    out = []
    for atom in interp.goal:
        out.append(atom.predicate)
        out.extend(class_token(class_of(a)) for a in atom.args)
    for atom in interp.constraint.atoms:
        out.append(atom.predicate)
        out.extend(class_token(class_of(a)) for a in atom.args)
    return out


def _pad(rows: list[list], fill, dtype) -> torch.Tensor:
    width = max((len(r) for r in rows), default=0) or 1
    return torch.tensor([list(r) + [fill] * (width - len(r)) for r in rows], dtype=dtype)


def encode(observations: list[Observation], vocab: Vocabulary) -> Batch:
    """Pad and index a list of observations with a fixed vocabulary."""
    if not observations:
        raise ValueError("cannot encode an empty list of observations")
    I = len(observations)
    J = max(len(o.interpretations) for o in observations)
    S = len(vocab.tokens)
    null = vocab.token_id(NULL)

    log_prior = torch.full((I, J), PAD_LOGIT)
    behaviour = torch.zeros(I, J)
    mask = torch.zeros(I, J, dtype=torch.bool)
    lifted = torch.zeros(I, J, dtype=torch.long)
    bow_tokens = torch.zeros(I, J, S)
    machines = [[[null] for _ in range(J)] for _ in range(I)]
    V = max(len(interp.roles) for o in observations for interp in o.interpretations) + 1
    role = torch.zeros(I, J, V, dtype=torch.long)
    role_mask = torch.zeros(I, J, V, dtype=torch.bool)
    role_tokens = torch.zeros(I, J, V, S)
    role_tokens[..., null] = 1.0

    for i, obs in enumerate(observations):
        if obs.behaviour is not None and len(obs.behaviour) != len(obs.interpretations):
            raise ValueError(
                f"observation {i}: {len(obs.behaviour)} behaviour values for "
                f"{len(obs.interpretations)} interpretations"
            )
        for j, interp in enumerate(obs.interpretations):
            mask[i, j] = True
            log_prior[i, j] = interp.log_prior
            if obs.behaviour is not None:
                behaviour[i, j] = obs.behaviour[j]
            lid = vocab.token_id(interp.lifted)
            lifted[i, j] = lid
            bow_tokens[i, j, [lid, null] + [vocab.token_id(t) for t in interp.constraint_tokens]] = 1.0
            machines[i][j] = [null] + [vocab.token_id(t) for t in machine_string(interp)]
            role_mask[i, j, 0] = True  # aligned with nothing: NULL only
            for v, rb in enumerate(interp.roles, start=1):
                role[i, j, v] = vocab.role_id(rb.role)
                role_mask[i, j, v] = True
                said = [vocab.token_id(t) for t in rb.constraint_tokens]
                role_tokens[i, j, v, said + [vocab.token_id(class_token(rb.cls))]] = 1.0

    M = max(len(m) for row in machines for m in row)
    machine = torch.full((I, J, M), null, dtype=torch.long)
    machine_mask = torch.zeros(I, J, M, dtype=torch.bool)
    for i in range(I):
        for j in range(J):
            m = machines[i][j] if j < len(observations[i].interpretations) else [null]
            machine[i, j, : len(m)] = torch.tensor(m)
            machine_mask[i, j, : len(m)] = True

    words = _pad([[vocab.word_id(w) for w in o.words] for o in observations], 0, torch.long)
    word_mask = _pad([[True] * len(o.words) for o in observations], False, torch.bool)

    # Parse-aligned pieces: distinct words per command, counted per entity.
    uniq_rows, per_reading = [], []
    for obs in observations:
        ids = sorted({vocab.word_id(w) for w in obs.words}) or [0]
        col = {w: u for u, w in enumerate(ids)}
        uniq_rows.append(ids)
        readings = []
        for reading in obs.readings:
            ents = entity_words(reading.logical_form)
            inside = Counter(w for _, content in ents for w in content)
            frame = Counter(obs.words)
            frame.subtract(inside)
            readings.append(
                (
                    reading.probability,
                    [
                        (vocab.prep_id(prep), Counter(col[vocab.word_id(w)] for w in content))
                        for prep, content in ents
                    ],
                    Counter({col[vocab.word_id(w)]: c for w, c in frame.items() if c > 0}),
                )
            )
        per_reading.append(readings)
    uniq = _pad(uniq_rows, 0, torch.long)
    U = uniq.shape[1]
    R = max(len(r) for r in per_reading) or 1
    E = max((len(ents) for rs in per_reading for _, ents, _ in rs), default=0) or 1
    reading_logp = torch.full((I, R), PAD_LOGIT)
    entity_counts = torch.zeros(I, R, E, U)
    entity_prep = torch.zeros(I, R, E, dtype=torch.long)
    entity_mask = torch.zeros(I, R, E, dtype=torch.bool)
    frame_counts = torch.zeros(I, R, U)
    for i, readings in enumerate(per_reading):
        for r, (prob, ents, frame) in enumerate(readings):
            reading_logp[i, r] = float(torch.log(torch.tensor(max(prob, 1e-12))))
            for u, c in frame.items():
                frame_counts[i, r, u] = c
            for e, (prep, counts) in enumerate(ents):
                entity_prep[i, r, e] = prep
                entity_mask[i, r, e] = True
                for u, c in counts.items():
                    entity_counts[i, r, e, u] = c

    return Batch(
        log_prior, behaviour, mask, lifted, bow_tokens, words, word_mask, machine, machine_mask,
        uniq, reading_logp, entity_counts, entity_prep, entity_mask, frame_counts,
        role, role_mask, role_tokens,
    )
