"""Observations, and the part of their padded tensor encoding every language model reads.

An :class:`Observation` is what the model sees of one instance: the
command's words and logical-form readings, the interpretations (L, T, C) of
its initial state and, when training, the behaviour log-likelihood of the
demonstration under each interpretation's grounded task. Candidate sets are
ragged across instances, so an :class:`Encoder` pads them and keeps masks.

A language model's batch is a :class:`Batch` (what the generative model and
every language model read) or a subclass with the model's own fields, which
the model fills in its ``encode_fields`` (``LanguageModel.encode``): the bag of
words reads only this one, IBM Model 2 adds its machine strings
(``model.ibm2``), the parse model its readings and roles
(``model.parse_encoding``).

Shapes below use I instances, J interpretations, S semantic tokens,
X token mixtures, W words, U distinct words of a command.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, fields

import torch

from groundlang.grammar.logical_form import Reading
from groundlang.model.interpretations import Interpretation
from groundlang.model.vocabulary import NULL, Vocabulary, class_token
from groundlang.model.world import object_class

__all__ = ["Observation", "Batch", "Encoder", "machine_string", "token_exclusions", "pad_rows", "PAD_LOGIT"]

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
    """Padded tensors for a list of observations: what every language model reads.

    Words are generated from *mixtures*: uniform mixtures over a set of
    semantic tokens ({L} + C + {NULL} for a bag of words, the tokens of the
    object in a role, ...). The distinct sets are few, so their emission
    probabilities are computed once per evaluation as ``mixtures @ phi`` and
    gathered, instead of mixing per instance and interpretation.
    """

    log_prior: torch.Tensor  # [I, J], PAD_LOGIT where padded
    behaviour: torch.Tensor  # [I, J], 0 where padded or unobserved
    mask: torch.Tensor  # [I, J] bool
    mixtures: torch.Tensor  # [X, S] rows: uniform weights over a token set
    token_name: torch.Tensor  # [S] the word the schema names each token by, or -1 (Vocabulary.names)
    token_family: torch.Tensor  # [S] the family of names of each token, or -1 (Vocabulary.token_families)
    token_excluded: torch.Tensor  # [S, W] bool: a word the token does not say (Vocabulary.other_kinds)
    uniq: torch.Tensor  # [I, U] distinct word ids of the command (0-padded)
    word_counts: torch.Tensor  # [I, U] occurrences of each distinct word
    task_token: torch.Tensor  # [I, J] token id of L
    task_index: torch.Tensor  # [I, J] index of L among the vocabulary's lifted tasks
    # [I, J] mixture of {L} + C + {NULL}: the bag of words' (which the other models start from); a bag
    # of words without NULL encodes its own
    bow_mix: torch.Tensor

    @property
    def num_instances(self) -> int:
        return self.log_prior.shape[0]

    def subset(self, indices) -> "Batch":
        """The same encoding restricted to some instances (e.g. a leave-one-out fold).

        Padding widths stay those of the full batch, which changes no
        likelihood: padded entries are masked or carry zero counts.
        """
        index = torch.as_tensor(indices, dtype=torch.long)
        values = {}
        for f in fields(self):
            value = getattr(self, f.name)
            values[f.name] = value if f.name in _SHARED else value[index]
        return type(self)(**values)


_SHARED = ("mixtures", "token_name", "token_family", "token_excluded")  # fields of the vocabulary, not of instances


def token_exclusions(vocab: Vocabulary) -> torch.Tensor:
    """``[S, W]`` bool: the words each token does not say (:meth:`Vocabulary.other_kinds`)."""
    out = torch.zeros(len(vocab.tokens), len(vocab.words), dtype=torch.bool)
    pairs = vocab.other_kinds()
    if pairs:
        token, word = torch.tensor(pairs, dtype=torch.long).T
        out[token, word] = True
    return out


def machine_string(interp: Interpretation) -> list[str]:
    """IBM Model 2's target: goal PFs and constraint PFs with their argument classes."""
    out = []
    for atom in interp.goal:
        out.append(atom.predicate)
        out.extend(class_token(object_class(a)) for a in atom.args)
    for atom in interp.constraint.atoms:
        out.append(atom.predicate)
        out.extend(class_token(object_class(a)) for a in atom.args)
    return out


def pad_rows(rows: list[list], fill, dtype) -> torch.Tensor:
    """Ragged rows as one tensor, each padded with ``fill`` to the longest (at least 1)."""
    width = max((len(r) for r in rows), default=0) or 1
    return torch.tensor([list(r) + [fill] * (width - len(r)) for r in rows], dtype=dtype)


class Encoder:
    """The encoding of one list of observations under one vocabulary, as the language models share it.

    It checks the observations, pads what every batch holds (:class:`Batch`), gives each command's
    distinct words their columns (``columns``) and interns token sets as mixture rows
    (:meth:`mixture`, for the fields a model adds); :meth:`batch` assembles the model's batch.
    """

    def __init__(self, observations: list[Observation], vocab: Vocabulary):
        if not observations:
            raise ValueError("cannot encode an empty list of observations")
        for i, obs in enumerate(observations):
            if obs.behaviour is not None and len(obs.behaviour) != len(obs.interpretations):
                raise ValueError(f"observation {i}: {len(obs.behaviour)} behaviour values for "
                                 f"{len(obs.interpretations)} interpretations")
        self.observations = observations
        self.vocab = vocab
        self.num_instances = len(observations)
        self.num_interpretations = max(len(o.interpretations) for o in observations)
        self.null = vocab.token_id(NULL)
        self._mixtures: dict[frozenset[int], int] = {}
        self.null_mixture = self.mixture([self.null])  # first, so always mixture 0 (NULL_MIXTURE)
        self.columns: list[dict[int, int]] = []  # per command: word id -> its column in ``uniq``
        uniq_rows, count_rows = [], []
        for obs in observations:
            counts = Counter(vocab.word_id(w) for w in obs.words)
            ids = sorted(counts) or [0]
            self.columns.append({w: u for u, w in enumerate(ids)})
            uniq_rows.append(ids)
            count_rows.append([float(counts.get(w, 0)) for w in ids])
        # The fields of every batch but the vocabulary's; a model's own fields may read them.
        self.shared = dict(self._per_interpretation_fields(), uniq=pad_rows(uniq_rows, 0, torch.long),
                           word_counts=pad_rows(count_rows, 0.0, torch.float32))

    def mixture(self, tokens) -> int:
        """The row of the mixture table that is uniform over ``tokens`` (token ids), interned."""
        key = frozenset(tokens)
        if key not in self._mixtures:
            self._mixtures[key] = len(self._mixtures)
        return self._mixtures[key]

    def interpretations(self):
        """``(i, j, interpretation)`` for every interpretation of every observation."""
        for i, obs in enumerate(self.observations):
            for j, interp in enumerate(obs.interpretations):
                yield i, j, interp

    def said_tokens(self, interp: Interpretation) -> tuple[int, list[int]]:
        """The token ids of the interpretation's lifted task and of what its binding constraints say."""
        return self.vocab.token_id(interp.lifted), [self.vocab.token_id(t) for t in interp.constraint_tokens]

    def per_interpretation(self, fill, dtype=torch.long) -> torch.Tensor:
        """An ``[I, J]`` tensor of ``fill``, for a field with one value per interpretation."""
        return torch.full((self.num_instances, self.num_interpretations), fill, dtype=dtype)

    def batch(self, batch_type: type[Batch] = Batch, **fields_) -> Batch:
        """``batch_type`` with the shared fields and the model's own ``fields_`` (which may replace a
        shared one); the mixture table last, so that it holds every mixture the model interned."""
        vocab = self.vocab
        values = dict(self.shared, token_name=torch.tensor(vocab.token_names(), dtype=torch.long),
                      token_family=torch.tensor(vocab.token_families(), dtype=torch.long),
                      token_excluded=token_exclusions(vocab))
        values.update(fields_)
        table = torch.zeros(len(self._mixtures), len(vocab.tokens))
        for key, row in self._mixtures.items():
            table[row, sorted(key)] = 1.0 / len(key)
        return batch_type(mixtures=table, **values)

    def _per_interpretation_fields(self) -> dict:
        vocab = self.vocab
        at, priors, observed, tokens, tasks, mixtures = [], [], [], [], [], []
        for i, j, interp in self.interpretations():
            at.append((i, j))
            priors.append(interp.log_prior)
            behaviour = self.observations[i].behaviour
            observed.append(0.0 if behaviour is None else behaviour[j])
            lid, said = self.said_tokens(interp)
            tokens.append(lid)
            mixtures.append(self.mixture([lid, self.null] + said))
            # Learner vocabularies always list the lifted tasks; one built by hand for the bag of
            # words or IBM Model 2 (no per-task tables) need not.
            tasks.append(vocab.task_id(interp.lifted) if vocab.tasks else 0)
        log_prior = self.per_interpretation(PAD_LOGIT, torch.float32)
        behaviour = self.per_interpretation(0.0, torch.float32)
        mask = self.per_interpretation(False, torch.bool)
        task_token = self.per_interpretation(self.null)
        task_index = self.per_interpretation(0)
        bow_mix = self.per_interpretation(self.null_mixture)
        if at:  # one indexed assignment per field (element by element it dominated encoding a large corpus)
            ii, jj = torch.tensor(at, dtype=torch.long).T
            mask[ii, jj] = True
            log_prior[ii, jj] = torch.tensor(priors, dtype=torch.float32)
            behaviour[ii, jj] = torch.tensor(observed, dtype=torch.float32)
            task_token[ii, jj] = torch.tensor(tokens, dtype=torch.long)
            task_index[ii, jj] = torch.tensor(tasks, dtype=torch.long)
            bow_mix[ii, jj] = torch.tensor(mixtures, dtype=torch.long)
        return dict(log_prior=log_prior, behaviour=behaviour, mask=mask, task_token=task_token,
                    task_index=task_index, bow_mix=bow_mix)
