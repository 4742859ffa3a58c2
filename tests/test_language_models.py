"""The parse-aligned language model's parts, checked against brute-force enumeration.

The mention model sums, in closed form by inclusion-exclusion, over every
alignment of the command's noun phrases to roles, weighting each by whether
each toy ends up named. These tests enumerate the alignments one by one on a
two-toy layout and compare.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import pyro
import pytest
import torch

from groundlang.corpus import read_state_file
from groundlang.learner import Learner
from groundlang.model.generative import global_sizes
from groundlang.model.language_models import ParseAligned
from groundlang.model.vocabulary import Vocabulary, is_task_role

TWO_TOYS = Path(__file__).parent / "fixtures" / "sokoban2_corpus" / "L1_novel.state"
COMMANDS = [
    "take the red chair to the green room",
    "go with the bag into the blue room and push the chair there",
    "walk to the red room",
    "push the bag to the right into the blue room",  # "the right": a phrase that names nothing
]


@pytest.fixture(scope="module")
def setting():
    state = read_state_file(TWO_TOYS, "sokoban2")
    learner = Learner("parse")
    observations = [learner._command_observation(c, state) for c in COMMANDS]
    learner.vocab = learner._build_vocabulary(observations, [state.layout.palette])
    # Observations made before the vocabulary existed still encode with it.
    batch = learner.lm.encode(observations, learner.vocab)
    pyro.set_rng_seed(3)
    with pyro.poutine.block():
        g = learner.lm.sample_globals(**global_sizes(learner.vocab))  # a random draw from the prior
    return learner, observations, batch, g


def test_the_mention_model_asks_about_every_toy_and_every_object_the_task_binds(setting):
    """Both toys of the two-toy layout, bound or bystanders, and the task's rooms; never the agent."""
    _, observations, batch, _ = setting
    for j, interp in enumerate(observations[0].interpretations):
        slots = batch.cover_slot[0, j][batch.cover_mask[0, j]].tolist()
        asked = [interp.roles[v - 1] for v in slots]
        bound_rooms = [rb.obj for rb in interp.roles if rb.cls == "room" and not rb.role.startswith("other:")]
        assert sorted(rb.obj for rb in asked if rb.cls == "toy") == ["block0", "block1"]
        assert sorted(rb.obj for rb in asked if rb.cls != "toy") == sorted(bound_rooms)
        assert bound_rooms and all(rb.cls != "agent" for rb in asked)
    # the conjunctive task binds two rooms: 2 toys + 2 rooms
    assert batch.cover_mask.shape[-1] == 4


def _alignments(batch, joint, g, i, j, r):
    """Every alignment of reading r's phrase occurrences to the roles interpretation j offers:
    (roles chosen, product of the phrases' terms, mention weight of the toys' named/unnamed states)."""
    K = int(batch.type_mask[i].sum())
    phrases = [k for k in range(K) for _ in range(int(batch.reading_types[i, r, k]))]
    options = [v for v in range(joint.shape[2]) if batch.role_mask[i, j, v]]
    slots = batch.cover_slot[i, j][batch.cover_mask[i, j]].tolist()
    for choice in itertools.product(options, repeat=len(phrases)):
        p = math.exp(sum(float(joint[i, j, v, k]) for v, k in zip(choice, phrases)))
        # Only a referring phrase ("the bag", not "the right") names the object it aligns with.
        named = {v for v, k in zip(choice, phrases) if batch.type_refers[i, k]}
        states = [(int(batch.role[i, j, slot]), 0 if slot in named else 1) for slot in slots]
        weight = math.prod(float(g["mention"][role, named]) for role, named in states)
        yield states, p, weight


@pytest.mark.slow
def test_mention_model_equals_summing_over_every_alignment(setting):
    learner, observations, batch, g = setting
    _, with_mentions, joint = learner.lm.reading_table(g, batch)
    without = {k: v for k, v in g.items() if k != "mention"}
    _, plain, _ = learner.lm.reading_table(without, batch)
    checked = 0
    for i, obs in enumerate(observations):
        for j in range(len(obs.interpretations)):
            for r in range(batch.reading_types.shape[1]):
                if batch.reading_logp[i, r] < -1e3:
                    continue
                terms = [(p * w, p) for _, p, w in _alignments(batch, joint, g, i, j, r)]
                total, plain_total = sum(t for t, _ in terms), sum(p for _, p in terms)
                got = float(with_mentions[i, j, r] - plain[i, j, r])
                assert got == pytest.approx(math.log(total / plain_total), abs=1e-4)
                checked += 1
    assert checked > 50
    assert not bool(batch.type_refers[3][batch.type_mask[3]].all())  # "the right" was among them


def test_only_a_head_noun_a_colour_or_an_open_class_word_names_an_object(setting):
    from groundlang.model.phrase_keys import is_referring

    assert is_referring([], ["door"]) and is_referring(["left"], ["door"])
    assert is_referring(["orange"], []) and is_referring(["salmon"], [])  # "to orange": a colour word
    assert is_referring(["periwinkle"], [])  # open class: maybe a name
    assert not is_referring(["right"], []) and not is_referring(["straight"], [])
    assert not is_referring(["a", "little"], [])
    _, observations, batch, _ = setting
    vocab_words = setting[0].vocab.words
    refers = {}
    for k in range(int(batch.type_mask[3].sum())):
        words = [vocab_words[int(batch.uniq[3, u])] for u in range(batch.uniq.shape[1])
                 if batch.type_counts[3, k, u] > 0 or batch.type_head_counts[3, k, u] > 0]
        refers[" ".join(sorted(words))] = bool(batch.type_refers[3, k])
    assert refers == {"bag": True, "right": False, "blue room": True}


def test_a_closed_class_word_training_never_saw_still_names_nothing(setting):
    """"left" is not in the vocabulary of COMMANDS, so it is <unk> to the language model; the phrase
    is judged on the word as written all the same."""
    learner, _, _, _ = setting
    state = read_state_file(TWO_TOYS, "sokoban2")
    assert learner.vocab.word_id("left") == 0
    batch = learner.lm.encode([learner._command_observation("push the bag to the left", state)], learner.vocab)
    refers = {}
    for k in range(int(batch.type_mask[0].sum())):
        has_head = bool(batch.type_head_counts[0, k].sum() > 0)
        refers.setdefault("the bag" if has_head else "the left", set()).add(bool(batch.type_refers[0, k]))
    assert refers == {"the bag": {True}, "the left": {False}}  # in every reading ("to the left" of the bag or not)


def test_any_phrase_names_what_it_aligns_with_when_asked(setting):
    """``mention_phrases="any"`` (the ablation): "the right" aligned with the bag names it too."""
    learner, _, batch, g = setting
    referring = learner.lm.reading_table(g, batch)[1]
    anything = ParseAligned(mention_phrases="any").reading_table(g, batch)[1]
    assert torch.allclose(referring[:3], anything[:3])  # every phrase of the first commands refers
    assert not torch.allclose(referring[3], anything[3])
    with pytest.raises(ValueError, match="mention_phrases must be 'referring' or 'any'"):
        ParseAligned(mention_phrases="all")


def test_gradient_times_mention_parameters_gives_the_expected_counts(setting):
    """What EM's M step relies on: mention * dlogP/dmention = expected (named, unnamed) counts."""
    learner, observations, batch, g = setting
    i, j, r = 1, 0, 0  # the two-phrase command, its first interpretation and reading
    mention = g["mention"].clone().requires_grad_(True)
    _, per_reading, joint = learner.lm.reading_table({**g, "mention": mention}, batch)
    per_reading[i, j, r].backward()
    counts = (mention * mention.grad).detach()
    expected = torch.zeros_like(counts, dtype=torch.float64)
    total = 0.0
    for states, p, weight in _alignments(batch, joint, g, i, j, r):
        total += p * weight
        for role, named in states:
            expected[role, named] += p * weight
    assert int(batch.reading_types[i, r].sum()) >= 2 and int(batch.cover_mask[i, j].sum()) == 3  # 2 toys, 1 room
    assert torch.allclose(counts.double(), expected / total, atol=1e-4)


def test_prior_favours_the_tasks_own_roles_and_unnamed_bystanders(setting):
    learner, _, _, _ = setting
    vocab: Vocabulary = learner.vocab
    sizes = global_sizes(vocab)
    lm = ParseAligned()
    trace = pyro.poutine.trace(lm.sample_globals).get_trace(**sizes)

    def concentration(site):
        fn = trace.nodes[site]["fn"]
        fn = getattr(fn, "base_dist", fn)
        return fn.concentration.reshape(-1, fn.concentration.shape[-1])

    align_c = concentration("align").reshape(len(vocab.tasks), len(vocab.preps), -1)
    mention_c = concentration("mention")
    from groundlang.model.phrase_keys import is_negated_key

    negated = [is_negated_key(p) for p in vocab.preps]
    assert any(negated) and not negated[0]  # the unseen negated key, "<not>", is always there
    for t, task in enumerate(vocab.tasks):
        said = align_c[t][[not n for n in negated]]
        assert torch.equal(said, said[:1].expand_as(said))  # the same prior for every unnegated preposition
        for r, name in enumerate(vocab.roles):
            if name in vocab.task_roles[task]:  # a negated phrase: no bonus for the task's own roles
                assert float(align_c[t][negated][:, r].max()) == pytest.approx(lm.align_concentration)
        for r, name in enumerate(vocab.roles):
            if name not in vocab.task_roles[task]:  # another task's variable, or the agent: never offered
                assert float(align_c[t, 0, r]) == 1.0  # no pseudo-count, so the MAP gives it nothing
            elif is_task_role(name):
                assert float(align_c[t, 0, r]) == pytest.approx(lm.align_concentration + lm.argument_bonus)
            else:
                assert float(align_c[t, 0, r]) == pytest.approx(lm.align_concentration)
    for r, name in enumerate(vocab.roles):
        if is_task_role(name):
            assert float(mention_c[r, 0]) > float(mention_c[r, 1])
        else:
            assert float(mention_c[r, 1]) > float(mention_c[r, 0])


def test_each_tasks_alignment_table_spans_only_the_roles_its_interpretations_offer(setting):
    """"Go somewhere" has no toy to move and no phrase names the agent ("you"): fitted, agentToRoom's
    tables give the toy's roles and the agent's nothing, and so keep all their mass for what its
    interpretations can offer (with every task's roles in every table, a third of it was lost)."""
    learner, observations, batch, _ = setting
    vocab = learner.vocab
    assert vocab.task_roles["agentToRoom"] == ("none", "agentInRoom.1", "other:room", "other:door", "other:toy",
                                              "other:start")
    assert vocab.task_roles["toyToRoom"] == ("none", "toyInRoom.0", "toyInRoom.1", "other:room", "other:door",
                                             "other:toy", "other:start")
    for obs in observations:
        for interp in obs.interpretations:
            offered = {rb.role for rb in interp.roles if rb.cls != "agent"}
            assert offered <= set(vocab.task_roles[interp.lifted])
    from groundlang.inference.joint import fit_globals

    g = fit_globals(batch, learner.lm, vocab, steps=50).globals
    tables = g["align"].reshape(len(vocab.tasks), len(vocab.preps), -1)
    for t, task in enumerate(vocab.tasks):
        never = [r for r, name in enumerate(vocab.roles) if name not in vocab.task_roles[task]]
        assert float(tables[t][:, never].sum(-1).max()) < 1e-9
        assert torch.allclose(tables[t].sum(-1), torch.ones(len(vocab.preps)))


def test_switching_the_parts_off_removes_their_globals(setting):
    learner, _, _, _ = setting
    sizes = global_sizes(learner.vocab)
    with pyro.poutine.block():
        full = ParseAligned().sample_globals(**sizes)
        bare = ParseAligned(argument_bonus=0.0, mention_concentration=None, arity_concentration=None).sample_globals(**sizes)
    assert {"mention", "arity"} <= set(full)
    assert not {"mention", "arity"} & set(bare)


def test_doors_are_described_by_their_side_of_the_agent(setting):
    from groundlang.model.tasks import spatial_descriptions

    learner, observations, _, _ = setting
    state = read_state_file(TWO_TOYS, "sokoban2")
    sides = spatial_descriptions(state, learner.library)
    assert sides and all(o.startswith("door") for o in sides)
    for interp in observations[0].interpretations:
        for rb in interp.roles:
            spatial = tuple(t for t in rb.constraint_tokens if t in learner.library.spatial_pfs)
            assert spatial == sides.get(rb.obj, ())
    assert set(learner.library.spatial_pfs) <= set(learner.vocab.tokens)


def test_each_lifted_task_reads_prepositions_with_its_own_alignment_table(setting):
    """P(role | preposition, L): changing the table of one lifted task changes only its interpretations."""
    learner, observations, batch, g = setting
    vocab = learner.vocab
    before = learner.lm.log_likelihood(g, batch)
    assert g["align"].shape[0] == len(vocab.tasks) * len(vocab.preps)  # one table per lifted task, not per token
    assert g["arity"].shape[0] == len(vocab.tasks)
    tables = g["align"].reshape(len(vocab.tasks), len(vocab.preps), -1).clone()
    agent = vocab.task_id("agentToRoom")
    tables[agent] = torch.roll(tables[agent], 1, dims=-1)  # another valid table for agentToRoom only
    after = learner.lm.log_likelihood({**g, "align": tables.reshape(g["align"].shape)}, batch)
    for i, obs in enumerate(observations):
        for j, interp in enumerate(obs.interpretations):
            changed = not torch.isclose(before[i, j], after[i, j])
            assert changed == (interp.lifted == "agentToRoom"), (i, interp.lifted)
    shared = ParseAligned(align_by_task=False)
    with pyro.poutine.block():
        assert shared.sample_globals(**global_sizes(vocab))["align"].shape[0] == len(vocab.preps)


def test_arity_counts_the_noun_phrases_of_each_clause(setting):
    """P(arity | L) is per clause: batch.clause_arity[i, r, b] is how many clauses of reading
    structure r have b noun phrases with words (the last bin: b or more)."""
    from groundlang.model.parse_encoding import CLAUSE_ARITY_BINS

    learner, observations, batch, _ = setting
    for i, obs in enumerate(observations):
        for q, reading in enumerate(obs.readings):
            lf = reading.logical_form
            r = int(batch.reading_group[i, q])
            named = [sum(1 for e in lf.entities if e.clause == c and (e.modifiers or e.head))
                     for c in range(len(lf.clauses))]
            expected = torch.zeros(CLAUSE_ARITY_BINS)
            for n in named:
                expected[min(n, CLAUSE_ARITY_BINS - 1)] += 1
            assert torch.equal(batch.clause_arity[i, r], expected), (obs.words, named)
    two = [o for o in observations if len(o.readings[0].logical_form.clauses) > 1]
    assert two, "the commands include one of two clauses"


def test_each_lifted_task_has_its_own_arity_per_clause(setting):
    """Changing P(arity | agentToRoom) changes only agentToRoom's interpretations, and for
    "walk to the red room" (one clause, one noun phrase) by exactly log a'[1] - log a[1]."""
    learner, observations, batch, g = setting
    t = learner.vocab.task_id("agentToRoom")
    arity = g["arity"].clone()
    arity[t] = torch.roll(arity[t], 1)
    _, before, _ = learner.lm.reading_table(g, batch)
    _, after, _ = learner.lm.reading_table({**g, "arity": arity}, batch)
    walk = COMMANDS.index("walk to the red room")
    assert all(len(r.logical_form.clauses) == 1 for r in observations[walk].readings)
    for i, obs in enumerate(observations):
        R = len(set(batch.reading_group[i, : len(obs.readings)].tolist()))
        for j, interp in enumerate(obs.interpretations):
            changed = not torch.allclose(before[i, j, :R], after[i, j, :R])
            assert changed == (interp.lifted == "agentToRoom"), (i, interp.lifted)
            if i == walk and interp.lifted == "agentToRoom":
                expected = float(arity[t, 1].log() - g["arity"][t, 1].log())
                assert torch.allclose(after[i, j, :R] - before[i, j, :R], torch.full((R,), expected), atol=1e-5)


def test_mention_factor_is_the_same_summed_one_subset_at_a_time(setting, monkeypatch):
    """The blocks that bound the mention factor's memory change nothing but the memory."""
    from groundlang.model import mentions

    learner, _, batch, g = setting
    whole = learner.lm.reading_table(g, batch)[1]
    monkeypatch.setattr(mentions, "MENTION_SUBSETS_PER_BLOCK", 1)
    assert torch.allclose(learner.lm.reading_table(g, batch)[1], whole, atol=1e-6)


def test_with_back_off_each_context_mixes_its_table_with_its_base_keys(setting):
    """Weights (1, 0) read every key by its own table; (0, 1) by its base key's table."""
    learner, _, batch, g = setting
    vocab = learner.vocab
    plain = learner.lm.log_likelihood(g, batch)
    backing = ParseAligned(align_backoff=True)
    C = g["align"].shape[0]
    own_only = {**g, "backoff": torch.tensor([1.0, 0.0]).expand(C, 2)}
    assert torch.allclose(backing.log_likelihood(own_only, batch), plain)
    # The same as the plain model with every key's rows replaced by its base key's.
    from groundlang.model.phrase_keys import backoff_prep_ids

    base_of = backoff_prep_ids(vocab)
    assert base_of != list(range(len(vocab.preps)))  # some key here does back off
    tables = g["align"].reshape(len(vocab.tasks), len(vocab.preps), -1)
    based = {**g, "align": tables[:, base_of].reshape(C, -1)}
    base_only = {**g, "backoff": torch.tensor([0.0, 1.0]).expand(C, 2)}
    assert torch.allclose(backing.log_likelihood(base_only, batch), learner.lm.log_likelihood(based, batch))
    with pyro.poutine.block():
        assert backing.sample_globals(**global_sizes(vocab))["backoff"].shape == (C, 2)


def test_the_verb_of_a_negated_clause_is_a_frame_word_not_the_tasks(setting):
    """"do not *walk* into the red room" says what not to do: "walk" is generated as a frame word."""
    learner, _, _, _ = setting
    state = read_state_file(TWO_TOYS, "sokoban2")
    obs = learner._command_observation("push the bag into the blue room and do not walk into the red room", state)
    assert any(c.negated and c.verb == "walk" for c in obs.readings[0].logical_form.clauses)
    batch = learner.lm.encode([obs], learner.vocab)
    words = [learner.vocab.words[w] for w in batch.uniq[0].tolist()]
    for r in range(int((batch.reading_logp[0] > -1e3).sum())):
        verbs = {w for u, w in enumerate(words) if batch.verb_counts[0, r, u] > 0}
        frame = {w for u, w in enumerate(words) if batch.frame_counts[0, r, u] > 0}
        assert verbs == {"push"} and "walk" in frame, r


def test_alignment_posterior_equals_summing_over_every_alignment(setting):
    # P(phrase type k aligns with role binding v | words, j, s), mention model included, against listing
    # every alignment of the reading's phrases.
    learner, observations, batch, g = setting
    _, _, joint = learner.lm.reading_table(g, batch)
    checked = 0
    for i in range(len(observations)):
        one = batch.subset([i])
        for j in (0, len(observations[i].interpretations) - 1):
            for r in range(batch.reading_types.shape[1]):
                if batch.reading_logp[i, r] < -1e3:
                    continue
                got = learner.lm.alignment_probabilities(g, one, j, r)
                K = int(batch.type_mask[i].sum())
                phrases = [k for k in range(K) for _ in range(int(batch.reading_types[i, r, k]))]
                options = [v for v in range(joint.shape[2]) if batch.role_mask[i, j, v]]
                total, fixed = 0.0, {}
                for choice, (_, p, w) in zip(itertools.product(options, repeat=len(phrases)),
                                             _alignments(batch, joint, g, i, j, r)):
                    total += p * w
                    for k in set(phrases):
                        same = {v for v, kk in zip(choice, phrases) if kk == k}
                        if len(same) == 1:
                            key = (k, same.pop())
                            fixed[key] = fixed.get(key, 0.0) + p * w
                for k in set(phrases):
                    for v in options:
                        assert float(got[k, v]) == pytest.approx(fixed.get((k, v), 0.0) / total, abs=1e-4)
                    checked += 1
    assert checked > 20


def _copy(batch):
    """The batch without what it computed of itself (its parts)."""
    from dataclasses import fields

    return type(batch)(**{f.name: getattr(batch, f.name) for f in fields(batch)})


def test_parts_by_width_give_the_words_terms_and_gradients_of_the_whole_batch(setting, monkeypatch):
    """``words_by_reading`` computes each part of instances with as many interpretations, roles and
    noun-phrase types as its own widest needs (``ParseBatch.by_width``): the same terms, and the same
    gradient (EM's expected counts), as the padded whole."""
    from groundlang.model import parse_encoding
    from groundlang.model.encoding import PAD_LOGIT

    learner, _, batch, g = setting
    assert len(_copy(batch).by_width()[0]) == 1  # four commands: a part's fixed cost outweighs the padding
    monkeypatch.setattr(parse_encoding, "PART_OVERHEAD", 0)  # every width its own part
    batch = _copy(batch)
    parts, order = batch.by_width()
    widths = sorted(int(p.type_mask.shape[1]) for p in parts)
    assert len(parts) >= 2 and widths[0] < batch.type_mask.shape[1]  # the test has something to cut
    assert sorted(order.tolist()) == list(range(batch.num_instances))
    real = batch.mask[:, :, None] & (batch.reading_logp > PAD_LOGIT)[:, None, :]  # [I, J, S]

    def terms(compute):
        leaves = {k: v.detach().clone().requires_grad_(True) for k, v in g.items()}
        values = compute(leaves)
        values[real].sum().backward()
        return values.detach(), {k: v.grad for k, v in leaves.items() if v.grad is not None}

    by_width, grads = terms(lambda leaves: learner.lm.words_by_reading(leaves, batch)[0])
    whole, whole_grads = terms(lambda leaves: learner.lm._words_given_reading(leaves, batch)[0])
    assert torch.allclose(by_width[real], whole[real], atol=1e-4)
    assert (by_width[~real] <= PAD_LOGIT / 2).all()  # padding stays padding
    assert grads.keys() == whole_grads.keys() and "phi" in grads
    for name, grad in grads.items():
        assert torch.allclose(grad, whole_grads[name], atol=1e-4, rtol=1e-4), name
