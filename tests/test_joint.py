"""Joint inference: EM through the Pyro model, posteriors, warm starts and fold subsets."""

from __future__ import annotations

import dataclasses
import math

import pytest
import torch
from torch.distributions import constraints

from groundlang.corpus import example_corpus_path, read_corpus
from groundlang.inference import em
from groundlang.inference.joint import (_log_joint, fit_globals, local_posteriors, posterior,
                                       posterior_by_enumeration, posteriors_by_enumeration)
from groundlang.model.generative import global_sizes, instance_model
from groundlang.learner import Learner
from groundlang.model.language_models import BagOfWords, get_language_model


@pytest.fixture(scope="module")
def example():
    corpus = read_corpus(example_corpus_path(), "sokoban")
    learner = Learner("parse")
    observations = learner.observe(corpus.instances)
    learner.fit(corpus.instances, observations=observations)
    return corpus, learner, observations


def test_em_never_decreases_the_map_objective(example):
    _, learner, observations = example
    batch = learner.lm.encode(observations, learner.vocab)
    result = fit_globals(batch, learner.lm, learner.vocab, steps=60, optimizer="em")
    losses = result.losses
    # The loss is -log p(data, globals); EM may only lower it (float32 rounding aside).
    assert all(b <= a + 1e-5 * abs(a) for a, b in zip(losses, losses[1:]))
    assert losses[-1] < losses[0] - 10.0


def test_posterior_equals_pyro_compute_marginals(example):
    _, learner, observations = example
    batch = learner.lm.encode(observations, learner.vocab)
    direct = posterior(batch, learner.lm, learner.globals)
    pyro_marginals = posterior_by_enumeration(batch, learner.lm, learner.vocab, learner.globals)
    assert torch.allclose(direct, pyro_marginals, atol=1e-5)
    assert torch.allclose(direct.sum(-1), torch.ones(batch.num_instances), atol=1e-5)


def test_training_posterior_puts_the_demonstrated_goal_first(example):
    corpus, learner, observations = example
    from groundlang.labels import label_for, read_labels

    labels = read_labels(example_corpus_path() / "labels.csv")
    batch = learner.lm.encode(observations, learner.vocab)
    probs = posterior(batch, learner.lm, learner.globals)
    for i, (inst, obs) in enumerate(zip(corpus.instances, observations)):
        best = obs.interpretations[int(probs[i].argmax())]
        assert set(label_for(inst, labels)) <= set(best.goal), inst.name


def test_subset_of_an_encoding_gives_the_same_likelihoods_as_encoding_the_subset(example):
    _, learner, observations = example
    full = learner.lm.encode(observations, learner.vocab)
    keep = [0, 3, 7, 12, 20]
    alone = learner.lm.encode([observations[k] for k in keep], learner.vocab)
    subset = full.subset(keep)
    a = learner.lm.log_likelihood(learner.globals, subset)
    b = learner.lm.log_likelihood(learner.globals, alone)
    # Padding widths differ; on real interpretations the numbers must agree.
    J = alone.mask.shape[1]
    assert torch.allclose(a[:, :J][alone.mask], b[alone.mask], atol=1e-4)
    assert not subset.mask[:, J:].any()


def test_warm_start_from_other_globals_reaches_the_same_bag_of_words_optimum(example):
    _, learner, observations = example
    batch = learner.lm.encode(observations, learner.vocab)
    lm = BagOfWords()
    cold = fit_globals(batch, lm, learner.vocab, steps=500, tol=1e-9)
    phi = cold.globals["phi"]
    noisy = torch.softmax(phi.log() + 0.3 * torch.randn(phi.shape, generator=torch.Generator().manual_seed(1)), -1)
    warm = fit_globals(batch, lm, learner.vocab, steps=500, tol=1e-9, init={"phi": noisy})
    assert warm.losses[-1] == pytest.approx(cold.losses[-1], rel=1e-4)


def test_lbfgs_and_em_agree_on_the_bag_of_words_map(example):
    _, learner, observations = example
    batch = learner.lm.encode(observations, learner.vocab)
    em = fit_globals(batch, BagOfWords(), learner.vocab, steps=500, tol=1e-9, optimizer="em")
    lbfgs = fit_globals(batch, BagOfWords(), learner.vocab, steps=400, optimizer="lbfgs")
    assert em.losses[-1] == pytest.approx(lbfgs.losses[-1], rel=1e-3)


def test_unknown_language_model_and_optimizer_are_clear_errors(example):
    _, learner, observations = example
    with pytest.raises(ValueError, match="unknown language model 'lstm'"):
        get_language_model("lstm")
    with pytest.raises(ValueError, match="unknown optimizer"):
        fit_globals(learner.lm.encode(observations[:2], learner.vocab), learner.lm, learner.vocab, optimizer="sgd")


def _brute_force(batch, lm, g, use_behaviour):
    """P(z = j), P(reading = s) per instance by listing every (j, s) of the model's terms."""
    table, reading_logits = lm.words_by_reading(g, batch)
    z_out, s_out = torch.zeros(batch.mask.shape), torch.zeros(reading_logits.shape)
    for i in range(batch.num_instances):
        readings = torch.log_softmax(reading_logits[i], -1)
        weights = {}
        for j in range(int(batch.mask[i].sum())):
            for s in range(reading_logits.shape[1]):
                term = batch.log_prior[i, j] + readings[s] + table[i, j, s]
                weights[j, s] = float(term + (batch.behaviour[i, j] if use_behaviour else 0.0))
        top = max(weights.values())
        total = sum(math.exp(w - top) for w in weights.values())
        for (j, s), w in weights.items():
            z_out[i, j] += math.exp(w - top) / total
            s_out[i, s] += math.exp(w - top) / total
    return z_out, s_out


@pytest.mark.parametrize("use_behaviour", [True, False])
def test_the_reading_site_posterior_equals_brute_force_and_pyro(example, use_behaviour):
    _, learner, observations = example
    batch = learner.lm.encode(observations, learner.vocab)
    assert batch.reading_logp.shape[1] >= 2  # two structures at least, or there is no reading to infer
    z, readings = local_posteriors(batch, learner.lm, learner.globals, use_behaviour)
    z_brute, readings_brute = _brute_force(batch, learner.lm, learner.globals, use_behaviour)
    z_pyro, readings_pyro = posteriors_by_enumeration(batch, learner.lm, learner.vocab, learner.globals, use_behaviour)
    assert torch.allclose(z, z_brute, atol=1e-5) and torch.allclose(readings, readings_brute, atol=1e-5)
    assert torch.allclose(z_pyro, z_brute, atol=1e-4) and torch.allclose(readings_pyro, readings_brute, atol=1e-4)
    several = (readings_brute > 0.01).sum(-1) > 1
    assert several.any()  # the test reads commands whose reading the words leave open


def test_the_reading_site_leaves_the_training_objective_as_the_summed_readings(example):
    # With the reading a site, the log joint is the one with readings summed inside the words term, up to
    # the constant that normalises the parser's probabilities of each command's merged structures.
    _, learner, observations = example
    batch = learner.lm.encode(observations, learner.vocab)
    sizes = global_sizes(learner.vocab)
    g = {k: v.clone().requires_grad_(True) for k, v in learner.globals.items()}
    with_site = _log_joint(lambda: instance_model(batch, learner.lm, sizes), g).item()

    class Summed(type(learner.lm)):
        def words_by_reading(self, g, batch):
            return None

    summed = Summed(**learner.lm.settings())
    by_hand = _log_joint(lambda: instance_model(batch, summed, sizes), g).item()
    constant = float(torch.logsumexp(batch.reading_logp, -1).sum())
    assert with_site == pytest.approx(by_hand - constant, rel=1e-5)


def test_squarem_reaches_em_s_optimum_in_fewer_steps_and_never_loses_ground(example):
    """SQUAREM extrapolates along two EM steps; where EM crawls (the bag of words' ridge between
    synonyms) it must find the same MAP, take fewer forward/backward passes, and never accept an
    iterate worse than the last."""
    _, learner, observations = example
    batch = learner.lm.encode(observations, learner.vocab)
    plain = fit_globals(batch, BagOfWords(), learner.vocab, steps=1000, tol=1e-8, optimizer="em")
    fast = fit_globals(batch, BagOfWords(), learner.vocab, steps=1000, tol=1e-8, optimizer="em",
                       acceleration="squarem")
    assert plain.converged and fast.converged
    assert fast.steps < plain.steps
    assert fast.losses[-1] <= plain.losses[-1] + 1e-4 * abs(plain.losses[-1])
    assert all(b <= a + 1e-5 * abs(a) for a, b in zip(fast.losses, fast.losses[1:]))
    for name in plain.globals:
        assert torch.allclose(fast.globals[name], plain.globals[name], atol=2e-2), name


def test_unknown_em_acceleration_is_a_clear_error(example):
    _, learner, observations = example
    with pytest.raises(ValueError, match="unknown EM acceleration"):
        fit_globals(learner.lm.encode(observations[:2], learner.vocab), learner.lm, learner.vocab, acceleration="aitken")


@pytest.mark.parametrize("tol", [-1.0, float("nan"), float("inf")])
def test_a_tolerance_that_could_never_stop_early_is_refused(example, tol):
    _, learner, observations = example
    with pytest.raises(ValueError, match="tol must be a finite number >= 0"):
        fit_globals(learner.lm.encode(observations[:2], learner.vocab), learner.lm, learner.vocab, tol=tol)


def test_one_em_step_and_one_instance_still_fit(example):
    """SQUAREM's cycle takes two EM steps; a budget of one, or a batch of one command, is still a fit."""
    _, learner, observations = example
    one = fit_globals(learner.lm.encode(observations[:1], learner.vocab), learner.lm, learner.vocab, steps=1)
    assert one.steps == 1 and len(one.losses) >= 1 and all(torch.isfinite(v).all() for v in one.globals.values())
    zero_tol = fit_globals(learner.lm.encode(observations[:1], learner.vocab), learner.lm, learner.vocab, tol=0.0,
                           steps=12)
    assert zero_tol.steps <= 12 and all(b <= a + 1e-5 * abs(a) for a, b in zip(zero_tol.losses, zero_tol.losses[1:]))


def test_a_batch_of_another_language_model_is_refused(example):
    """The bag of words reads any batch (every batch holds its fields); IBM Model 2 needs its machine strings."""
    _, learner, observations = example
    parse_batch = learner.lm.encode(observations[:2], learner.vocab)
    fit_globals(parse_batch, BagOfWords(), learner.vocab, steps=2)
    with pytest.raises(TypeError, match="language model ibm2 reads a MachineBatch"):
        fit_globals(parse_batch, get_language_model("ibm2"), learner.vocab, steps=2)


def _row_sum_error(x: torch.Tensor) -> float:
    return float((x.double().sum(-1) - 1).abs().max())


@pytest.mark.parametrize("acceleration", ["none", "squarem"])
def test_em_keeps_a_large_vocabulary_s_word_distributions_on_the_simplex(example, acceleration):
    """644 commands with a word of their own each (660 words): the M step normalised a row of phi in
    float32 to a sum 5e-7 off 1, and Pyro's float32 Simplex check (|sum - 1| < 1e-6) of the next
    step's Dirichlet log_prob failed ("Error while computing log_prob at site 'phi'") at some corpus
    sizes and not others (500 .bdm commands failed, 300 and 700 trained). Normalised in float64 and
    rounded once, a row sums to 1 within float32's 2**-24."""
    corpus, learner, observations = example
    extended = [dataclasses.replace(o, words=o.words + (f"w{n}",))
                for n, o in ((n, observations[n % len(observations)]) for n in range(644))]
    palettes = sorted({i.initial_state.layout.palette for i in corpus.instances}, key=lambda p: p.name)
    vocab = learner._build_vocabulary(extended, palettes)
    assert len(vocab.words) > 644
    result = fit_globals(BagOfWords().encode(extended, vocab), BagOfWords(), vocab, optimizer="em",
                         acceleration=acceleration)
    for name, value in result.globals.items():
        assert constraints.simplex.check(value).all(), name
        assert _row_sum_error(value) <= 1e-7, name


def test_a_squarem_jump_is_put_back_on_the_simplex_to_float32_precision():
    """Two words counted 284 times and 500 never (the prior's 0.05 each): clipped and normalised in
    float32, the row summed to 1 + 9.5e-7 and failed Pyro's Simplex check."""
    row = torch.tensor([284.05, 284.05] + [0.05] * 500)
    for x in (em._on_simplex(row), em._on_simplex(torch.cat([row[:-1], torch.tensor([-0.3])]))):
        assert x.dtype == torch.float32 and bool((x > 0).all())
        assert constraints.simplex.check(x)
        assert _row_sum_error(x) <= 1e-7

