"""The parse-aligned language model (``parse``): words generated through the logical form.

Each noun phrase aligns with a role of the interpretation (the toy, the goal room, the agent's start
room, ...) or with nothing, with a learned table ``P(role | preposition, L)`` per lifted task ("go
*into* the tan room" names the goal of "go somewhere" but, in a command that then pushes the star, the
room the star is in); its words come from the tokens of the object in that role, the remaining words
from L or ``NULL``. Readings are weighted by the parser's probabilities. More parts of the logical
form depend on the task:

- which objects it names: a learned ``P(named | role)`` for every toy and every object the task binds
  (``parse_encoding.is_mentionable``): a command that never mentions a toy speaks against "take the toy
  somewhere", one that names a bystander toy against the tasks that leave it alone; only a referring
  phrase names what it aligns with (``phrase_keys.is_referring``: "on right" does not name the star);
- how many noun phrases each of its clauses has (``P(arity | L)``, per clause; the number of clauses
  is not modelled: a reading that splits a command into more clauses pays one more arity factor);
- each phrase's preposition (``P(preposition | L)``): "to the right of the chair" says the relation
  the task asks for, which the alignment table, conditioned on the preposition, cannot say.

The prior over alignments favours the task's own roles (``argument_bonus``), which decides for
prepositions training never saw ("go *with* the star to green"). Each task's table spans only the
roles its interpretations can offer (``Vocabulary.task_roles``). What each part measured: ABLATIONS.md.
"""

from __future__ import annotations

import pyro
import pyro.distributions as dist
import torch

from groundlang.grammar.parser import checked_weights
from groundlang.model.encoding import PAD_LOGIT, Encoder
from groundlang.model.language_model_base import (NULL_MIXTURE, LanguageModel, gather_mixtures,
                                                  mixture_log_emissions, require_positive)
from groundlang.model.mentions import mention_factor
from groundlang.model.parse_encoding import CLAUSE_ARITY_BINS, ParseBatch, encode_parse_fields
from groundlang.model.phrase_keys import PhraseKeys, is_negated_key
from groundlang.model.relational import is_relational_role
from groundlang.model.vocabulary import is_task_role

__all__ = ["ParseAligned"]


class ParseAligned(LanguageModel):
    name = "parse"
    enumerates_constraints = False

    def __init__(
        self,
        word_concentration: float = 1.05,
        align_concentration: float = 1.5,
        argument_bonus: float = 3.0,
        mention_concentration: float | None = 1.05,
        arity_concentration: float | None = 1.05,
        align_by_task: bool = True,
        mention_phrases: str = "referring",
        align_backoff: bool = False,
        relation_words: bool = False,
        preposition_concentration: float | None = 1.05,
        held_parts: bool = True,
        relational_descriptions: bool = False,
        schema_names: bool = False,
        last_phrase_key: bool = True,
        object_key: bool = True,
        last_passes_over_source: bool = True,
        noun_attached_key: bool = True,
        negation_key: bool = True,
        last_passes_over_negated: bool = True,
        negated_phrases_unbiased: bool = True,
        start_role: bool = True,
        bystander_roles: bool = True,
        largest_constraint: bool = True,
        negated_verbs_frame: bool = True,
        mention_task_objects: bool = True,
        parser_weights: dict | None = None,
        achievable_goals: bool = True,
        expected_success: bool = True,
        step_cost: float = 0.005,
        end_habits: bool = True,
        moved_toys: bool = False,
        habits_made_true: bool = False,
        bound_habits: bool = True,
        habit_prior: str = "absent",
        success_confidence: bool = True,
        held_goals_confidence: bool = False,
        other_starts: bool = True,
    ):
        """``argument_bonus`` is added to the alignment prior's concentration of
        the task's own roles (a phrase names an argument of the task more often
        than a bystander; it decides for prepositions training never saw).
        ``mention_concentration`` turns on the mention model (None: off),
        ``arity_concentration`` the number of noun phrases of a clause given L (None: off);
        both are Dirichlet concentrations, so EM stays exact. ``align_by_task``:
        one alignment table ``P(role | preposition, L)`` per lifted task (False:
        one ``P(role | preposition)`` shared by all tasks). ``mention_phrases``: which phrases name
        the object they align with for the mention model, ``"referring"`` (a head noun, a colour
        word or an open-class word, see ``phrase_keys.is_referring``) or ``"any"``. ``align_backoff``: each
        alignment context reads roles from a mixture of its own table and that of the key it backs off to
        (``phrase_keys.backoff_key``: ``onto+obj|last`` -> ``onto``), weights learned per context, so a rare
        key ("onto ..." as the last phrase) is no longer read by its prior alone. Off by default: it
        explains the words better, but "|last" says where things go, and a rare "with ...|last" backed off
        to "with" read "to one with orange floor" as a room passed. ``relation_words``: a phrase aligned
        with an argument of the task may say the goal's relation ("the *left side* of the chair"): the
        goal PFs join the tokens its modifiers and head noun come from (``interpretations.interpretations``).
        ``preposition_concentration`` turns on a model of each phrase's bare preposition given L (None:
        off; a Dirichlet concentration): a preposition says the relation ("to the right of the chair",
        "into the room"), which the alignment table, conditioned on it, cannot. ``held_parts``: a
        conjunction may name a part that holds at the start, which the plan breaks and restores ("... and
        come back to the green room"); a demonstration that never breaks it rules the reading out
        (``interpretations.unbroken_held_parts``). ``relational_descriptions``: a bystander related to an object the task binds by a PF of two objects (a toy in the goal room)
        is offered in a role named by that relation, so "the room *with the red chair*" can say which
        room (``model.relational``). ``last_phrase_key``, ``object_key``, ``last_passes_over_source``, ``noun_attached_key``,
        ``negation_key``, ``last_passes_over_negated``: the
        marks of a phrase's preposition key (``phrase_keys.PhraseKeys`` says the regularity each states).
        ``negated_phrases_unbiased``: the alignment prior of a negated clause's phrases (``not:to``) gives the
        task's own roles no argument bonus.
        ``start_role``: the room the agent starts in has a role of its own ("go *from the orange room*");
        ``bystander_roles``: objects the task leaves alone have one role per class (``other:room``), not
        one for all (``interpretations.interpretations``). ``largest_constraint``: each grounding is offered once,
        described by every property PF of its objects, and each word picks the property it says; off, one
        interpretation per binding constraint, each with its share of the prior. ``negated_verbs_frame``: the
        verb of a negated clause ("do not *enter*") says what not to do, a frame word rather than one of the
        task's verbs. ``mention_task_objects``: the mention model asks whether each object the task binds
        (a room it ends in) is named, not only toys. ``parser_weights``: overrides of the grammar's rule
        weights by name (``grammar.parser.DEFAULT_WEIGHTS``, e.g. ``{"nmods_coord": 1.0}``), which weigh
        the readings of an ambiguous command. ``schema_names``: see
        :class:`LanguageModel`. What each measured: ABLATIONS.md."""
        if mention_phrases not in ("referring", "any"):
            raise ValueError(f"language model {self.name}: mention_phrases must be 'referring' or 'any', "
                             f"not {mention_phrases!r}")
        require_positive(self.name, "align_concentration", align_concentration)
        for name, value in (("mention_concentration", mention_concentration),
                            ("arity_concentration", arity_concentration),
                            ("preposition_concentration", preposition_concentration)):
            if value is not None:
                require_positive(self.name, name, value)
        require_positive(self.name, "argument_bonus", argument_bonus, added=True)
        super().__init__(word_concentration, schema_names=schema_names, achievable_goals=achievable_goals,
                         expected_success=expected_success, step_cost=step_cost, end_habits=end_habits,
                         moved_toys=moved_toys, habits_made_true=habits_made_true, bound_habits=bound_habits,
                         habit_prior=habit_prior, success_confidence=success_confidence,
                         held_goals_confidence=held_goals_confidence, other_starts=other_starts)
        self.align_concentration = align_concentration
        self.argument_bonus = argument_bonus
        self.mention_concentration = mention_concentration
        self.arity_concentration = arity_concentration
        self.align_by_task = align_by_task
        self.mention_phrases = mention_phrases
        self.align_backoff = align_backoff
        self.relation_words = relation_words
        self.preposition_concentration = preposition_concentration
        self.held_parts = held_parts
        self.relational_descriptions = relational_descriptions
        self.last_phrase_key = last_phrase_key
        self.object_key = object_key
        self.last_passes_over_source = last_passes_over_source
        self.noun_attached_key = noun_attached_key
        self.negation_key = negation_key
        self.last_passes_over_negated = last_passes_over_negated
        self.negated_phrases_unbiased = negated_phrases_unbiased
        self.start_role = start_role
        self.bystander_roles = bystander_roles
        self.enumerates_constraints = not largest_constraint
        self.negated_verbs_frame = negated_verbs_frame
        self.mention_task_objects = mention_task_objects
        try:
            self.parser_weights = checked_weights(parser_weights) if parser_weights else None
        except ValueError as exc:
            raise ValueError(f"language model {self.name}: parser_weights: {exc}") from None

    def phrase_keys(self) -> PhraseKeys:
        return PhraseKeys(self.last_phrase_key, self.object_key, self.last_passes_over_source, self.noun_attached_key,
                          self.negation_key, self.last_passes_over_negated)

    batch_type = ParseBatch

    def encode_fields(self, enc: Encoder) -> dict:
        return encode_parse_fields(enc, self.phrase_keys(), negated_verbs_frame=self.negated_verbs_frame,
                                   mention_task_objects=self.mention_task_objects)

    # What settings() reports, in this order (each an attribute of the same name but largest_constraint).
    _SETTINGS = ("word_concentration", "align_concentration", "argument_bonus", "mention_concentration",
                 "arity_concentration", "align_by_task", "mention_phrases", "align_backoff", "relation_words",
                 "preposition_concentration", "held_parts", "relational_descriptions", "schema_names",
                 "achievable_goals", "expected_success", "step_cost", "end_habits", "moved_toys", "habits_made_true",
                 "bound_habits", "habit_prior", "success_confidence", "held_goals_confidence", "other_starts",
                 "last_phrase_key", "object_key", "last_passes_over_source", "noun_attached_key", "negation_key",
                 "last_passes_over_negated", "negated_phrases_unbiased", "start_role", "bystander_roles", "largest_constraint",
                 "negated_verbs_frame", "mention_task_objects", "parser_weights")

    def settings(self) -> dict:
        return {name: (not self.enumerates_constraints if name == "largest_constraint" else getattr(self, name))
                for name in self._SETTINGS}

    def sample_globals(self, num_tokens, num_words, num_roles, num_preps, role_names=(), num_tasks=0, offered=(),
                       name_families=0, prep_names=()):
        g = super().sample_globals(num_tokens, num_words, num_roles, num_preps, name_families=name_families)
        if num_tasks < 1:
            raise ValueError("the parse model needs the lifted tasks of the vocabulary (Vocabulary.add_tasks)")
        task_role = torch.tensor([is_task_role(name) for name in role_names], dtype=torch.bool)
        if task_role.numel() != num_roles:  # no names given: every role is a bystander's
            task_role = torch.zeros(num_roles, dtype=torch.bool)
        concentration = torch.full((num_roles,), self.align_concentration) + self.argument_bonus * task_role
        by_prep = concentration.expand(num_preps, num_roles).clone()  # [preps, roles]
        if self.negated_phrases_unbiased and len(prep_names) == num_preps:
            # What a negated phrase names may be the task's ("push the star into the teal room without walking
            # into the teal room") or not ("... do not go through the orange room"): no bonus either way.
            by_prep[torch.tensor([is_negated_key(k) for k in prep_names], dtype=torch.bool)] = self.align_concentration
        share = torch.full((2,), self.align_concentration)
        g["frame_source"] = pyro.sample("frame_source", dist.Dirichlet(share))
        g["verb_source"] = pyro.sample("verb_source", dist.Dirichlet(share))
        # One table per (lifted task, preposition) when aligning by task, kept flat
        # (one plate); reading_table views it as [tasks, preps, roles].
        if self.align_by_task:
            # A task's table spans only the roles its interpretations can offer: the roles of another
            # task's variables get concentration 1, a flat prior that adds no pseudo-count, so the MAP
            # gives them exactly nothing (they never have counts). With the bonus of every task's
            # roles in every table, a "go somewhere" table kept a third of its mass for the toy's
            # roles, and in a layout with a toy an agent command read cheaper as moving it.
            own = torch.tensor(offered, dtype=torch.bool) if offered else torch.ones(num_tasks, num_roles, dtype=torch.bool)
            per_task = torch.where(own[:, None, :], by_prep[None], torch.ones(()))  # [tasks, preps, roles]
            concentration = per_task.reshape(-1, num_roles)
        else:
            concentration = by_prep
        contexts = concentration.shape[0]
        with pyro.plate("align_contexts", contexts, dim=-1):
            g["align"] = pyro.sample("align", dist.Dirichlet(concentration))
            if self.align_backoff:
                # Per context: the share of its own table and of its back-off key's (phrase_keys.backoff_key).
                g["backoff"] = pyro.sample("backoff", dist.Dirichlet(share))
        if self.mention_concentration is not None:
            # Per role: P(an object in this role is named by some phrase), P(it is not).
            # A priori a task's object is named and a bystander is not, by as many
            # pseudo-counts as the alignment prior's argument bonus.
            # A relational role's object (model.relational) is named when the relation describes the
            # object it relates to ("the room with the chair") and not otherwise: no prior either way.
            relational = torch.tensor([is_relational_role(name) for name in role_names], dtype=torch.bool)
            if relational.numel() != num_roles:
                relational = torch.zeros(num_roles, dtype=torch.bool)
            mention = torch.full((num_roles, 2), self.mention_concentration)
            mention += self.argument_bonus * torch.stack([task_role, ~task_role & ~relational], dim=-1)
            with pyro.plate("mention_roles", num_roles, dim=-1):
                g["mention"] = pyro.sample("mention", dist.Dirichlet(mention))
        if self.arity_concentration is not None:
            # Per lifted task: how many noun phrases a clause of a command of the task has.
            with pyro.plate("arity_tasks", num_tasks, dim=-1):
                g["arity"] = pyro.sample(
                    "arity", dist.Dirichlet(torch.full((CLAUSE_ARITY_BINS,), self.arity_concentration))
                )
        if self.preposition_concentration is not None:
            # Per lifted task: the preposition key of each noun phrase.
            with pyro.plate("preposition_tasks", num_tasks, dim=-1):
                g["preposition"] = pyro.sample(
                    "preposition", dist.Dirichlet(torch.full((num_preps,), self.preposition_concentration))
                )
        return g

    def log_likelihood(self, g: dict, batch: ParseBatch) -> torch.Tensor:
        return self.reading_table(g, batch)[0]

    def alignment_probabilities(self, g: dict, batch: ParseBatch, j: int, s: int) -> torch.Tensor:
        """For the one command of ``batch``, interpretation ``j`` and merged reading structure ``s``:
        ``P(phrase type k aligns with role binding v | words, j, s)`` as ``[K, V]`` (``v`` indexes
        ``batch.role[0, j]``, 0 = nothing), exact with the mention model: each ``(k, v)`` is the same
        words term with type k's alignment fixed to v, over the term with it free. A type said twice in
        the reading is fixed in both places, so its row is the probability that both align with v."""
        with torch.no_grad():
            free = self._words_given_reading(g, batch)[0][0, j, s]
            K, V = batch.type_mask.shape[1], batch.role.shape[2]
            out = torch.zeros(K, V)
            for k in range(int(batch.type_mask[0].sum())):
                if batch.reading_types[0, s, k] == 0:
                    continue
                for v in range(V):
                    if batch.role_mask[0, j, v]:
                        fixed = self._words_given_reading(g, batch, fix=(k, v))[0][0, j, s]
                        out[k, v] = (fixed - free).exp()
            return out

    def _words_given_reading(self, g: dict, batch: ParseBatch, fix: tuple[int, int] | None = None):
        """``(log P(words | j, s) [I, J, S] per merged structure s of the parser's readings, per type and
        role [I, J, V, K])``; with ``fix=(k, v)`` the words and phrase type k aligned with role binding v.

        A noun phrase of type k aligns with role v with probability
        ``align[prep_k, role_v]`` (with ``align_backoff``, a mixture of that and
        the back-off key's row, the component one more latent choice); a role
        that interpretation j does not offer cannot be chosen, so its share of
        the probability is lost (the model stays a sum of products of
        categoricals, which keeps EM exact). The phrase's words then come from
        that role's mixture.
        """
        log_emit = mixture_log_emissions(g, batch)  # [X, W]
        own = gather_mixtures(log_emit, batch.mixes, batch.uniq)  # [I, M, U]: each instance's mixtures
        modifiers = torch.einsum("imu,iku->imk", own, batch.type_counts)  # [I, M, K]
        heads = torch.einsum("imu,iku->imk", own, batch.type_head_counts)
        type_ll = per_role(modifiers, batch.role_mix) + per_role(heads, batch.role_head_mix)  # [I, J, V, K]
        # Row of the alignment table per phrase type: (task, key) when aligning by task, else the key.
        if self.align_by_task:
            context = batch.align_context  # [I, J, K]
        else:
            context = batch.type_prep[:, None, :].expand(-1, batch.role.shape[1], -1)
        roles = batch.role[:, :, :, None]
        if "backoff" in g:
            base = context - batch.type_prep[:, None, :] + batch.type_base_prep[:, None, :]  # same task, back-off key
            own = g["align"][context[:, :, None, :], roles]  # [I, J, V, K]
            backed = g["align"][base[:, :, None, :], roles]
            # A mixture of the key's own table and its back-off key's, with learned weights per context:
            # one more latent choice, so EM stays exact (weights * gradient = expected counts).
            weights = g["backoff"][context][:, :, None, :, :]  # [I, J, 1, K, 2]
            log_align = (weights[..., 0] * own + weights[..., 1] * backed).clamp_min(1e-30).log()
        else:
            log_align = g["align"].clamp_min(1e-30).log()[context[:, :, None, :], roles]  # [I, J, V, K]
        log_align = (log_align + batch.role_logw[..., None]).masked_fill(~batch.role_mask[..., None], PAD_LOGIT)
        joint = type_ll + log_align
        if fix is not None:  # phrase type k aligned with role binding v only (alignment_probabilities)
            k, v = fix
            others = torch.arange(joint.shape[2]) != v
            joint = joint.clone()
            joint[:, :, others, k] = PAD_LOGIT
        per_type = torch.logsumexp(joint, dim=2) * batch.type_mask[:, None, :]  # [I, J, K]
        entities = torch.einsum("ijk,irk->ijr", per_type, batch.reading_types)
        if "mention" in g:
            entities = entities + mention_factor(g, batch, joint, entities, self.mention_phrases == "referring")
        # Words outside noun phrases come from the lifted task's token or NULL
        # with learned shares, one pair for verbs and one for the other words:
        # a verb says more about the task than "to" or "the" does. A negated clause's verb
        # ("do not enter it") is one of the other words (see parse_encoding._reading_structure).
        # Mixed per (token, word) of the vocabulary, then gathered: fewer entries than [I, J, U].
        task_words = g["phi"].clamp_min(1e-30).log()  # [S, W]
        both = torch.stack([task_words, log_emit[NULL_MIXTURE].expand_as(task_words)], dim=-1)  # [S, W, 2]
        said = (batch.task_token[:, :, None], batch.uniq[:, None, :])
        frame_words = torch.logsumexp(both + g["frame_source"].log(), dim=-1)[said]  # [I, J, U]
        verb_words = torch.logsumexp(both + g["verb_source"].log(), dim=-1)[said]
        frame = torch.einsum("iju,iru->ijr", frame_words, batch.frame_counts)
        verbs = torch.einsum("iju,iru->ijr", verb_words, batch.verb_counts)
        per_reading = entities + frame + verbs
        if "arity" in g:
            arity = g["arity"].clamp_min(1e-30).log()
            # Each clause's number of noun phrases given L: a command's length is its number of clauses,
            # which says little about the task (see ``arity_concentration``).
            per_reading = per_reading + torch.einsum("ijb,irb->ijr", arity[batch.task_index], batch.clause_arity)
        if "preposition" in g:
            # Each phrase's preposition key given L, then its role given (L, key), then its words.
            # The preposition itself (``phrase_keys.bare_preposition``): the marks of the phrase's place and
            # attachment are the reading's, which the alignment table is conditioned on already, and a
            # direct object has none, so nothing is generated for it.
            said = batch.type_preposition >= 0  # [I, K]
            keys = g["preposition"].clamp_min(1e-30).log()[batch.task_index[:, :, None],
                                                            batch.type_preposition.clamp_min(0)[:, None, :]]
            keys = keys * (batch.type_mask & said)[:, None, :]  # [I, J, K]
            per_reading = per_reading + torch.einsum("ijk,irk->ijr", keys, batch.reading_types)
        return per_reading, joint

    def reading_table(self, g: dict, batch: ParseBatch):
        """``(log P(words | j) [I, J], log P(words, s | j) per merged structure s [I, J, S], per type and role
        [I, J, V, K])``: :meth:`words_by_reading` with the readings' prior, summed over readings too."""
        per_reading, joint = self._words_given_reading(g, batch)
        with_prior = per_reading + batch.reading_logp[:, None, :]
        return torch.logsumexp(with_prior, dim=-1), with_prior, joint

    def words_by_reading(self, g: dict, batch: ParseBatch):
        # A padded structure's words carry PAD_LOGIT, not 0: Pyro sums an enumerated site in log space
        # shifted by its largest term, and a padded 0 would shift a real -150 to nothing.
        padded = batch.reading_logp <= PAD_LOGIT
        parts, order = batch.by_width()  # the same terms, without computing the padding
        J = batch.mask.shape[1]
        rows = [_pad_interpretations(self._words_given_reading(g, part)[0], J) for part in parts]
        return torch.cat(rows)[order].masked_fill(padded[:, None, :], PAD_LOGIT), batch.reading_logp


def _pad_interpretations(per_reading: torch.Tensor, J: int) -> torch.Tensor:
    """``[I, j, S]`` -> ``[I, J, S]``, the interpretations a part lacks at PAD_LOGIT (their prior's too)."""
    missing = J - per_reading.shape[1]
    return torch.nn.functional.pad(per_reading, (0, 0, 0, missing), value=PAD_LOGIT) if missing else per_reading


def per_role(per_mixture: torch.Tensor, at: torch.Tensor) -> torch.Tensor:
    """``per_mixture [I, M, K]`` at each role binding's mixture ``at [I, J, V]`` (an index into M) ->
    ``[I, J, V, K]``."""
    I, J, V = at.shape
    K = per_mixture.shape[-1]
    out = per_mixture.gather(1, at.reshape(I, J * V, 1).expand(I, J * V, K))
    return out.reshape(I, J, V, K)
