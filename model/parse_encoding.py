"""The parse model's batch: noun-phrase types, reading structures and the roles phrases align with.

Shapes below use I instances, J interpretations, R merged reading structures, K noun-phrase types,
U distinct words of a command, V role bindings (0 = aligned with nothing), G mentionable objects.
"""

from __future__ import annotations

import itertools
import math
from collections import Counter
from dataclasses import dataclass, replace

import torch

from groundlang.logic.classes import domain_classes
from groundlang.model.encoding import PAD_LOGIT, Batch, Encoder, Observation, pad_rows
from groundlang.model.interpretations import UNALIGNED_CLASSES, RoleBinding
from groundlang.model.phrase_keys import PhraseKeys, backoff_prep_ids, bare_preposition, entity_words, is_referring
from groundlang.model.vocabulary import Vocabulary, class_token, is_task_role

__all__ = ["ParseBatch", "encode_parse_fields", "is_mentionable", "CLAUSE_ARITY_BINS"]

CLAUSE_ARITY_BINS = 5  # clauses with 4 or more noun phrases share the last bin
# The fixed cost of computing one part of a batch (ParseBatch.by_width), in [I, J, V, K] entries: the words
# terms take about 0.1 us per entry and 20 ms per part (measured one thread: benchmarks/bench_pair_training.py).
PART_OVERHEAD = 200_000


@dataclass
class ParseBatch(Batch):
    """A :class:`Batch` with what the parse model reads of the readings and the interpretations' roles."""

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
    align_context: torch.Tensor  # [I, J, K] row of the per-task alignment table: task_index * preps + type_prep
    cover_slot: torch.Tensor  # [I, J, G] role slot (index into V) of each mentionable object (is_mentionable)
    cover_mask: torch.Tensor  # [I, J, G] bool
    role: torch.Tensor  # [I, J, V] role ids (0 = aligned with nothing)
    role_mask: torch.Tensor  # [I, J, V] bool
    role_logw: torch.Tensor  # [I, J, V] -log(objects sharing the role's label): "other:room" picks one room
    role_mix: torch.Tensor  # [I, J, V] mixture a modifier aligned with the role comes from (index into mixes):
    # the PFs the phrase may express of the role's object, and NULL ("left", "far")
    role_head_mix: torch.Tensor  # [I, J, V] mixture the head noun comes from (index into mixes): the object's class
    mixes: torch.Tensor  # [I, M] the distinct mixtures of an instance's roles (rows of mixtures; 0: NULL's)
    type_refers: torch.Tensor  # [I, K] bool: a phrase of the type can name an object (is_referring)
    type_base_prep: torch.Tensor  # [I, K] the preposition key the type's key backs off to (backoff_key)
    type_preposition: torch.Tensor  # [I, K] the phrase's bare preposition (bare_preposition), -1 for a direct object

    # The axes after I of each field padded in J (interpretations), V (role bindings) or K (noun-phrase
    # types): what :meth:`by_width` narrows.
    _AXES = {"log_prior": "J", "behaviour": "J", "mask": "J", "task_token": "J", "task_index": "J", "bow_mix": "J",
             "type_counts": "KU", "type_head_counts": "KU", "type_prep": "K", "type_mask": "K",
             "reading_types": "RK", "align_context": "JK", "cover_slot": "JG", "cover_mask": "JG", "role": "JV",
             "role_mask": "JV", "role_logw": "JV", "role_mix": "JV", "role_head_mix": "JV", "type_refers": "K",
             "type_base_prep": "K", "type_preposition": "K"}

    def by_width(self) -> tuple[list["ParseBatch"], torch.Tensor]:
        """The batch cut into parts of instances with about as many noun-phrase types, each part's J, V and
        K as wide as its own widest instance needs, and the order that puts the parts' rows back
        (``torch.cat(rows)[order]``). Computed once per batch.

        Padding is most of a corpus's batch: on the Williams corpus two thirds of the commands have one
        noun-phrase type and one has 12, and a dense [I, J, V, K] table is 16 times the real entries.
        Padded entries are masked, so a part gives its instances' terms as the whole batch does."""
        if "_parts" not in self.__dict__:
            types = self.type_mask.sum(1).clamp_min(1)
            bucket = torch.ceil(torch.log2(types.double())).long()  # widths 1, 2, 4, 8, ...
            interps = self.mask.sum(1).clamp_min(1)
            # The last role binding a phrase may align with or the mention model asks about (bindings
            # of the agent, say, are neither, yet keep their place).
            V = self.role_mask.shape[2]
            last = torch.where(self.role_mask.any(1), torch.arange(V), 0).amax(1)
            named = torch.where(self.cover_mask, self.cover_slot, 0).flatten(1).amax(1)
            roles = torch.maximum(last, named) + 1
            groups = [(bucket == b).nonzero(as_tuple=True)[0] for b in bucket.unique().tolist()]

            def widths(index):
                return {"J": int(interps[index].max()), "V": int(roles[index].max()), "K": int(types[index].max())}

            runs = _cheapest_runs(groups, lambda index: PART_OVERHEAD + len(index) * math.prod(widths(index).values()))
            parts = [self._narrowed(index, widths(index)) for index in runs]
            self.__dict__["_parts"] = (parts, torch.argsort(torch.cat(runs)))
        return self.__dict__["_parts"]

    def _narrowed(self, index: torch.Tensor, widths: dict[str, int]) -> "ParseBatch":
        """:meth:`subset` of ``index``, each padded axis cut to ``widths``."""
        part = self.subset(index)
        narrowed = {}
        for name, axes in self._AXES.items():
            value = getattr(part, name)
            for axis, letter in enumerate(axes, start=1):
                if letter in widths:
                    value = value.narrow(axis, 0, widths[letter])
            narrowed[name] = value
        return replace(part, **narrowed)


def _cheapest_runs(groups: list[torch.Tensor], cost) -> list[torch.Tensor]:
    """The split of ``groups`` (instance indices, narrowest first) into runs of neighbours, each run one part,
    with the least total ``cost(run)``: a part's fixed cost outweighs the padding that a small group saves
    (a small batch stays whole). Every split is tried: 2^(groups - 1), and widths 1, 2, 4, 8, 16 make 16."""
    best, best_cost = None, math.inf
    for cuts in itertools.product((False, True), repeat=len(groups) - 1):
        runs, start = [], 0
        for n, cut in enumerate(cuts, start=1):
            if cut:
                runs.append(torch.cat(groups[start:n]))
                start = n
        runs.append(torch.cat(groups[start:]))
        total = sum(cost(run) for run in runs)
        if total < best_cost:
            best, best_cost = runs, total
    return best


def is_mentionable(rb: RoleBinding, task_objects: bool = True) -> bool:
    """Whether the mention model asks if a phrase names this object: every toy (a command
    names the toys its task moves, not bystanders) and, with ``task_objects``, every other object
    the task binds but the agent, who is "you" (a command names the room its task ends in; the
    parse model's ``mention_task_objects``). Measured: ABLATIONS.md."""
    return rb.cls in domain_classes().mentioned or (
        task_objects and rb.cls not in UNALIGNED_CLASSES and is_task_role(rb.role))
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


def encode_parse_fields(enc: Encoder, keys: PhraseKeys, *, negated_verbs_frame: bool = True,
                        mention_task_objects: bool = True) -> dict:
    """The fields of :class:`ParseBatch` beyond the shared ones, for ``enc``'s observations. ``keys``:
    the marks of the noun phrases' preposition keys (the model's ``phrase_keys()``; the vocabulary's
    keys were made with the same); ``negated_verbs_frame``: the verb of a negated clause is a frame
    word, not one of the task's verbs; ``mention_task_objects``: see :func:`is_mentionable` (the parse
    model's settings of these names)."""
    observations, vocab = enc.observations, enc.vocab
    I = enc.num_instances
    fields = _role_fields(enc, mention_task_objects)
    structures = [_reading_structure(obs, vocab, col, keys, negated_verbs_frame)
                  for obs, col in zip(observations, enc.columns)]
    U = enc.shared["uniq"].shape[1]
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
    reading_group = pad_rows([groups for _, _, groups in structures], -1, torch.long)
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
    align_context = enc.shared["task_index"][:, :, None] * len(vocab.preps) + type_prep[:, None, :]  # [I, J, K]
    return dict(fields, reading_logp=reading_logp, type_counts=type_counts, type_head_counts=type_head_counts,
                type_prep=type_prep, type_mask=type_mask, reading_types=reading_types, frame_counts=frame_counts,
                verb_counts=verb_counts, clause_arity=clause_arity, reading_group=reading_group,
                align_context=align_context, type_refers=type_refers, type_base_prep=type_base_prep,
                type_preposition=type_preposition)


def _bindings(enc: Encoder, interp, mention_task_objects: bool) -> tuple[list[int], list[tuple]]:
    """An interpretation's mentionable role bindings (their indices v), and per binding a phrase may align
    with, ``(v, role id, -log(bindings sharing its role), modifier mixture, head mixture)``."""
    vocab = enc.vocab
    sharing = Counter(rb.role for rb in interp.roles)
    slots, aligned = [], []
    for v, rb in enumerate(interp.roles, start=1):
        if is_mentionable(rb, mention_task_objects):  # the mention model asks whether it is named
            slots.append(v)
        if rb.cls in UNALIGNED_CLASSES:
            # The addressee is "you", which the parser leaves without
            # words. Alignable, its class token had no words of its own
            # to learn and took the toy's noun: trained on three "take
            # the star ..." commands, "star" named the agent.
            continue
        tokens = [vocab.token_id(t) for t in rb.constraint_tokens]
        # Adjectives say properties, nouns say kinds: a class token
        # that could emit modifiers would learn every colour word.
        modifier = enc.mixture(tokens + [enc.null])
        # A head noun names the class ("block") or, for a toy, its shape ("chair").
        head = enc.mixture([vocab.token_id(class_token(rb.cls))] + [vocab.token_id(t) for t in rb.kind_tokens])
        aligned.append((v, vocab.role_id(rb.role), -math.log(sharing[rb.role]), modifier, head))
    return slots, aligned


def _role_fields(enc: Encoder, mention_task_objects: bool) -> dict:
    """Per interpretation, its role bindings (``role*``) and the slots of its mentionable objects (``cover_*``).

    Entries are gathered in lists and written with one indexed assignment per field: element by element,
    writing the tensors took most of the time of encoding a corpus of 1619 commands."""
    I, J = enc.num_instances, enc.num_interpretations
    interps = {id(interp): interp for _, _, interp in enc.interpretations()}.values()
    V = max(len(interp.roles) for interp in interps) + 1
    G = max(1, max(sum(1 for rb in interp.roles if is_mentionable(rb, mention_task_objects)) for interp in interps))
    at, role_ids, logw, mix, head_mix = [], [], [], [], []  # one entry per aligned role binding (i, j, v)
    # Per instance, its distinct mixtures, NULL's first: the words' likelihoods are computed once per
    # (instance, mixture), about 7, not once per role binding, [J, V] = 170 on the Williams corpus.
    mixes = [{enc.null_mixture: 0} for _ in range(I)]
    cover_at = []  # (i, j, slot, v) per mentionable object
    interp_at = []  # (i, j) per interpretation: a phrase may align with nothing
    bindings: dict[int, tuple] = {}  # id(interpretation) -> its bindings' entries: instances of a state share them
    for i, j, interp in enc.interpretations():
        interp_at.append((i, j))
        if id(interp) not in bindings:
            bindings[id(interp)] = _bindings(enc, interp, mention_task_objects)
        slots, aligned = bindings[id(interp)]
        cover_at.extend((i, j, slot, v) for slot, v in enumerate(slots))
        own = mixes[i]
        for v, role_id, weight, modifier, head in aligned:
            at.append((i, j, v))
            logw.append(weight)
            role_ids.append(role_id)
            mix.append(own.setdefault(modifier, len(own)))
            head_mix.append(own.setdefault(head, len(own)))
    role = torch.zeros(I, J, V, dtype=torch.long)
    role_mask = torch.zeros(I, J, V, dtype=torch.bool)
    role_logw = torch.zeros(I, J, V)
    # A phrase aligned with nothing draws its words from NULL, which every
    # frame word shares: a free distribution of its own would learn to
    # explain every phrase (see model.interpretations).
    role_mix = torch.zeros(I, J, V, dtype=torch.long)  # NULL's mixture, each instance's first
    role_head_mix = torch.zeros(I, J, V, dtype=torch.long)
    cover_slot = torch.zeros(I, J, G, dtype=torch.long)
    cover_mask = torch.zeros(I, J, G, dtype=torch.bool)
    if interp_at:
        ii, jj = torch.tensor(interp_at, dtype=torch.long).T
        role_mask[ii, jj, 0] = True
    if at:
        ii, jj, vv = torch.tensor(at, dtype=torch.long).T
        role[ii, jj, vv] = torch.tensor(role_ids, dtype=torch.long)
        role_mask[ii, jj, vv] = True
        role_logw[ii, jj, vv] = torch.tensor(logw, dtype=role_logw.dtype)
        role_mix[ii, jj, vv] = torch.tensor(mix, dtype=torch.long)
        role_head_mix[ii, jj, vv] = torch.tensor(head_mix, dtype=torch.long)
    if cover_at:
        ii, jj, gg, vv = torch.tensor(cover_at, dtype=torch.long).T
        cover_slot[ii, jj, gg] = vv
        cover_mask[ii, jj, gg] = True
    return dict(role=role, role_mask=role_mask, role_logw=role_logw, role_mix=role_mix, role_head_mix=role_head_mix,
                mixes=pad_rows([list(own) for own in mixes], enc.null_mixture, torch.long),
                cover_slot=cover_slot, cover_mask=cover_mask)
