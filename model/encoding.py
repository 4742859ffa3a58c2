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

import math
from collections import Counter
from dataclasses import dataclass, fields

import torch

from groundlang.grammar.logical_form import Reading
from groundlang.logic.classes import domain_classes
from groundlang.model.interpretations import UNALIGNED_CLASSES, Interpretation, RoleBinding
from groundlang.model.phrase_keys import (PhraseKeys, backoff_key, backoff_prep_ids, bare_preposition,
                                          entity_words, is_referring)
from groundlang.model.vocabulary import NULL, Vocabulary, class_token, is_task_role
from groundlang.model.world import object_class

__all__ = ["Observation", "Batch", "encode", "PhraseKeys", "entity_words", "is_mentionable", "is_referring", "machine_string",
           "backoff_key", "backoff_prep_ids", "bare_preposition", "PAD_LOGIT"]

CLAUSE_ARITY_BINS = 5  # clauses with 4 or more noun phrases share the last bin

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
    """Padded tensors for a list of observations; see the module docstring for shapes.

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
    bow_mix: torch.Tensor  # [I, J] mixture of {L} + C + {NULL}
    bow_mix_no_null: torch.Tensor  # [I, J] mixture of {L} + C (Model 0 has no NULL)
    uniq: torch.Tensor  # [I, U] distinct word ids of the command (0-padded)
    word_counts: torch.Tensor  # [I, U] occurrences of each distinct word
    words: torch.Tensor  # [I, N] word ids in order
    word_mask: torch.Tensor  # [I, N] bool
    machine: torch.Tensor  # [I, J, M] token ids of the machine string (NULL first)
    machine_mask: torch.Tensor  # [I, J, M] bool
    reading_logp: torch.Tensor  # [I, R], PAD_LOGIT where padded
    type_counts: torch.Tensor  # [I, K, U] modifiers (adjectives, colour words) of each noun-phrase type
    type_head_counts: torch.Tensor  # [I, K, U] head noun of each noun-phrase type
    type_prep: torch.Tensor  # [I, K] preposition class of each type
    type_mask: torch.Tensor  # [I, K] bool
    reading_types: torch.Tensor  # [I, R, K] occurrences of each type in each reading
    frame_counts: torch.Tensor  # [I, R, U] words outside noun phrases and verbs, per reading
    verb_counts: torch.Tensor  # [I, R, U] the clauses' verbs, per reading
    clause_arity: torch.Tensor  # [I, R, B] clauses of each reading with 0, 1, ..., B-1 (or more) noun phrases
    reading_group: torch.Tensor  # [I, Q] per parser reading, its merged structure (index into R); -1 padded
    task_token: torch.Tensor  # [I, J] token id of L
    task_index: torch.Tensor  # [I, J] index of L among the vocabulary's lifted tasks
    align_context: torch.Tensor  # [I, J, K] row of the per-task alignment table: task_index * preps + type_prep
    cover_slot: torch.Tensor  # [I, J, G] role slot (index into V) of each mentionable object (is_mentionable)
    cover_mask: torch.Tensor  # [I, J, G] bool
    role: torch.Tensor  # [I, J, V] role ids (0 = aligned with nothing)
    role_mask: torch.Tensor  # [I, J, V] bool
    role_logw: torch.Tensor  # [I, J, V] -log(objects sharing the role's label): "other:room" picks one room
    role_mix: torch.Tensor  # [I, J, V] mixture a modifier aligned with the role comes from:
    # the PFs the phrase may express of the role's object, and NULL ("left", "far")
    role_head_mix: torch.Tensor  # [I, J, V] mixture the head noun comes from: the object's class
    type_refers: torch.Tensor  # [I, K] bool: a phrase of the type can name an object (is_referring)
    type_base_prep: torch.Tensor  # [I, K] the preposition key the type's key backs off to (backoff_key)
    type_preposition: torch.Tensor  # [I, K] the phrase's bare preposition (bare_preposition), -1 for a direct object

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
        return Batch(**values)


def token_exclusions(vocab: Vocabulary) -> torch.Tensor:
    """``[S, W]`` bool: the words each token does not say (:meth:`Vocabulary.other_kinds`)."""
    out = torch.zeros(len(vocab.tokens), len(vocab.words), dtype=torch.bool)
    pairs = vocab.other_kinds()
    if pairs:
        token, word = torch.tensor(pairs, dtype=torch.long).T
        out[token, word] = True
    return out


_SHARED = ("mixtures", "token_name", "token_family", "token_excluded")  # fields of the vocabulary, not of instances


def is_mentionable(rb: RoleBinding, task_objects: bool = True) -> bool:
    """Whether the mention model asks if a phrase names this object: every toy (a command
    names the toys its task moves, not bystanders) and, with ``task_objects``, every other object
    the task binds but the agent, who is "you" (a command names the room its task ends in; the
    parse model's ``mention_task_objects``). Measured: ABLATIONS.md."""
    return rb.cls in domain_classes().mentioned or (
        task_objects and rb.cls not in UNALIGNED_CLASSES and is_task_role(rb.role))


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


def _pad(rows: list[list], fill, dtype) -> torch.Tensor:
    width = max((len(r) for r in rows), default=0) or 1
    return torch.tensor([list(r) + [fill] * (width - len(r)) for r in rows], dtype=dtype)


class _Mixtures:
    """Interning of token sets as rows of a mixture table."""

    def __init__(self):
        self.index: dict[frozenset[int], int] = {}

    def __call__(self, tokens) -> int:
        key = frozenset(tokens)
        if key not in self.index:
            self.index[key] = len(self.index)
        return self.index[key]

    def table(self, num_tokens: int) -> torch.Tensor:
        out = torch.zeros(len(self.index), num_tokens)
        for key, row in self.index.items():
            out[row, sorted(key)] = 1.0 / len(key)
        return out


def _reading_structure(obs: Observation, vocab: Vocabulary, col: dict[int, int], keys: PhraseKeys,
                       negated_verbs_frame: bool):
    """Distinct noun-phrase types and, per distinct reading structure, their counts.

    Readings that give the same multiset of (preposition key, words), the
    same frame words and verbs, and the same number of noun phrases per
    clause (``clause_arity``) are indistinguishable to the language model;
    their probabilities are summed.
    """
    types: dict[tuple, int] = {}
    merged: dict[tuple, float] = {}
    order: dict[tuple, int] = {}  # signature -> its index in ``merged``
    groups: list[int] = []  # per reading, the index of its structure in ``merged``
    for reading in obs.readings:
        ents = entity_words(reading.logical_form, vocab.lexicon, keys)
        inside = Counter(w for _, mods, head in ents for w in mods + head)
        frame = Counter(obs.words)
        frame.subtract(inside)
        # The verb of a negated clause ("do not *enter* the green room", "without *crossing* the doorway")
        # says what not to do: a frame word, not one of the task's verbs. Counted as verbs, the toy commands'
        # "... but do not enter it" taught the toy task "enter" and "dont cross over to orange" taught it
        # "cross": in a layout with a toy, "cross path from green room to orange room" read as moving it
        # (measured: ABLATIONS.md).
        said = Counter(c.verb for c in reading.logical_form.clauses
                       if c.verb and not (negated_verbs_frame and c.negated))
        verbs = Counter({v: min(n, frame[v]) for v, n in said.items() if frame[v] > 0})  # a word counts once
        frame.subtract(verbs)
        ent_types = Counter()
        for prep, mods, head in ents:
            if not mods and not head:
                continue  # a pronoun: nothing to generate
            key = (
                vocab.prep_id(prep),
                tuple(sorted(col[vocab.word_id(w)] for w in mods)),
                tuple(col[vocab.word_id(w)] for w in head),
                # Judged on the words as written: an unseen "left" is <unk> to the vocabulary, yet no name.
                is_referring(mods, head, vocab.lexicon),
            )
            ent_types[types.setdefault(key, len(types))] += 1
        frame_key = tuple(sorted((col[vocab.word_id(w)], c) for w, c in frame.items() if c > 0))
        verb_key = tuple(sorted((col[vocab.word_id(w)], c) for w, c in verbs.items() if c > 0))
        named = Counter(e.clause for e in reading.logical_form.entities if e.modifiers or e.head)
        clause_key = tuple(sorted(Counter(min(named.get(c, 0), CLAUSE_ARITY_BINS - 1)
                                          for c in range(len(reading.logical_form.clauses))).items()))
        signature = (tuple(sorted(ent_types.items())), frame_key, verb_key, clause_key)
        merged[signature] = merged.get(signature, 0.0) + reading.probability
        groups.append(order.setdefault(signature, len(order)))
    return types, merged, groups


def encode(observations: list[Observation], vocab: Vocabulary, keys: PhraseKeys = PhraseKeys(), *,
           negated_verbs_frame: bool = True, mention_task_objects: bool = True) -> Batch:
    """Pad and index a list of observations with a fixed vocabulary; ``keys``: the marks of the noun
    phrases' preposition keys (the language model's ``phrase_keys()``; the vocabulary's keys were made
    with the same). ``negated_verbs_frame``: the verb of a negated clause is a frame word, not one of
    the task's verbs; ``mention_task_objects``: see :func:`is_mentionable` (the parse model's settings of
    these names; :meth:`LanguageModel.encode` passes a model's own)."""
    if not observations:
        raise ValueError("cannot encode an empty list of observations")
    I = len(observations)
    J = max(len(o.interpretations) for o in observations)
    S = len(vocab.tokens)
    null = vocab.token_id(NULL)
    mix = _Mixtures()

    log_prior = torch.full((I, J), PAD_LOGIT)
    behaviour = torch.zeros(I, J)
    mask = torch.zeros(I, J, dtype=torch.bool)
    pad_mix = mix([null])  # first, so always mixture 0 (language_models.NULL_MIXTURE)
    bow_mix = torch.full((I, J), pad_mix, dtype=torch.long)
    bow_mix_no_null = torch.full((I, J), pad_mix, dtype=torch.long)
    task_token = torch.full((I, J), null, dtype=torch.long)
    task_index = torch.zeros((I, J), dtype=torch.long)
    machines = [[[null] for _ in range(J)] for _ in range(I)]
    V = max(len(interp.roles) for o in observations for interp in o.interpretations) + 1
    role = torch.zeros(I, J, V, dtype=torch.long)
    role_mask = torch.zeros(I, J, V, dtype=torch.bool)
    role_logw = torch.zeros(I, J, V)
    # A phrase aligned with nothing draws its words from NULL, which every
    # frame word shares: a free distribution of its own would learn to
    # explain every phrase (see model.interpretations).
    role_mix = torch.full((I, J, V), pad_mix, dtype=torch.long)
    role_head_mix = torch.full((I, J, V), pad_mix, dtype=torch.long)
    G = max(1, max(sum(1 for rb in interp.roles if is_mentionable(rb, mention_task_objects))
                   for o in observations for interp in o.interpretations))
    cover_slot = torch.zeros(I, J, G, dtype=torch.long)
    cover_mask = torch.zeros(I, J, G, dtype=torch.bool)

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
            said = [vocab.token_id(t) for t in interp.constraint_tokens]
            bow_mix[i, j] = mix([lid, null] + said)
            bow_mix_no_null[i, j] = mix([lid] + said)
            task_token[i, j] = lid
            # Learner vocabularies always list the lifted tasks; one built by hand for the bag of
            # words or IBM Model 2 (no per-task tables) need not.
            task_index[i, j] = vocab.task_id(interp.lifted) if vocab.tasks else 0
            machines[i][j] = [null] + [vocab.token_id(t) for t in machine_string(interp)]
            role_mask[i, j, 0] = True  # aligned with nothing
            sharing = Counter(rb.role for rb in interp.roles)
            slots = 0
            for v, rb in enumerate(interp.roles, start=1):
                if is_mentionable(rb, mention_task_objects):  # the mention model asks whether it is named
                    cover_slot[i, j, slots] = v
                    cover_mask[i, j, slots] = True
                    slots += 1
                if rb.cls in UNALIGNED_CLASSES:
                    # The addressee is "you", which the parser leaves without
                    # words. Alignable, its class token had no words of its own
                    # to learn and took the toy's noun: trained on three "take
                    # the star ..." commands, "star" named the agent.
                    continue
                role_logw[i, j, v] = -math.log(sharing[rb.role])
                role[i, j, v] = vocab.role_id(rb.role)
                role_mask[i, j, v] = True
                tokens = [vocab.token_id(t) for t in rb.constraint_tokens]
                # Adjectives say properties, nouns say kinds: a class token
                # that could emit modifiers would learn every colour word.
                role_mix[i, j, v] = mix(tokens + [null])
                # A head noun names the class ("block") or, for a toy, its shape ("chair").
                role_head_mix[i, j, v] = mix(
                    [vocab.token_id(class_token(rb.cls))] + [vocab.token_id(t) for t in rb.kind_tokens]
                )

    M = max(len(m) for row in machines for m in row)
    machine = torch.full((I, J, M), null, dtype=torch.long)
    machine_mask = torch.zeros(I, J, M, dtype=torch.bool)
    for i in range(I):
        for j in range(len(observations[i].interpretations)):
            m = machines[i][j]
            machine[i, j, : len(m)] = torch.tensor(m)
            machine_mask[i, j, : len(m)] = True

    words = _pad([[vocab.word_id(w) for w in o.words] for o in observations], 0, torch.long)
    word_mask = _pad([[True] * len(o.words) for o in observations], False, torch.bool)

    uniq_rows, count_rows, structures = [], [], []
    for obs in observations:
        counts = Counter(vocab.word_id(w) for w in obs.words)
        ids = sorted(counts) or [0]
        col = {w: u for u, w in enumerate(ids)}
        uniq_rows.append(ids)
        count_rows.append([float(counts.get(w, 0)) for w in ids])
        structures.append(_reading_structure(obs, vocab, col, keys, negated_verbs_frame))
    uniq = _pad(uniq_rows, 0, torch.long)
    word_counts = _pad(count_rows, 0.0, torch.float32)
    U = uniq.shape[1]
    R = max(len(merged) for _, merged, _ in structures) or 1
    K = max(len(types) for types, _, _ in structures) or 1
    reading_logp = torch.full((I, R), PAD_LOGIT)
    type_counts = torch.zeros(I, K, U)
    type_head_counts = torch.zeros(I, K, U)
    type_prep = torch.zeros(I, K, dtype=torch.long)
    type_mask = torch.zeros(I, K, dtype=torch.bool)
    reading_types = torch.zeros(I, R, K)
    frame_counts = torch.zeros(I, R, U)
    verb_counts = torch.zeros(I, R, U)
    clause_arity = torch.zeros(I, R, CLAUSE_ARITY_BINS)
    reading_group = _pad([groups for _, _, groups in structures], -1, torch.long)
    type_refers = torch.zeros(I, K, dtype=torch.bool)
    type_base_prep = torch.zeros(I, K, dtype=torch.long)
    type_preposition = torch.full((I, K), -1, dtype=torch.long)
    base_of = backoff_prep_ids(vocab)
    for i, (types, merged, _) in enumerate(structures):
        for (prep, mods, head, refers), k in types.items():
            type_prep[i, k] = prep
            type_base_prep[i, k] = base_of[prep]
            bare = bare_preposition(vocab.preps[prep])
            if bare is not None:
                type_preposition[i, k] = vocab.prep_id(bare)
            type_mask[i, k] = True
            type_refers[i, k] = refers
            for u in mods:
                type_counts[i, k, u] += 1.0
            for u in head:
                type_head_counts[i, k, u] += 1.0
        for r, ((ent_types, frame_key, verb_key, clause_key), prob) in enumerate(merged.items()):
            for b, c in clause_key:
                clause_arity[i, r, b] = c
            for u, c in verb_key:
                verb_counts[i, r, u] = c
            reading_logp[i, r] = math.log(max(prob, 1e-12))
            for k, c in ent_types:
                reading_types[i, r, k] = c
            for u, c in frame_key:
                frame_counts[i, r, u] = c

    align_context = task_index[:, :, None] * len(vocab.preps) + type_prep[:, None, :]  # [I, J, K]
    return Batch(
        log_prior=log_prior, behaviour=behaviour, mask=mask, mixtures=mix.table(S),
        token_name=torch.tensor(vocab.token_names(), dtype=torch.long),
        token_family=torch.tensor(vocab.token_families(), dtype=torch.long),
        token_excluded=token_exclusions(vocab), bow_mix=bow_mix,
        bow_mix_no_null=bow_mix_no_null, uniq=uniq, word_counts=word_counts, words=words, word_mask=word_mask,
        machine=machine, machine_mask=machine_mask, reading_logp=reading_logp, type_counts=type_counts,
        type_head_counts=type_head_counts, type_prep=type_prep, type_mask=type_mask, reading_types=reading_types,
        frame_counts=frame_counts, verb_counts=verb_counts, clause_arity=clause_arity, reading_group=reading_group,
        task_token=task_token, task_index=task_index, align_context=align_context, cover_slot=cover_slot,
        cover_mask=cover_mask, role=role, role_mask=role_mask, role_logw=role_logw, role_mix=role_mix,
        role_head_mix=role_head_mix, type_refers=type_refers, type_base_prep=type_base_prep,
        type_preposition=type_preposition,
    )
