"""Joint inference: MAP fit of the language model's globals with exact enumeration.

Training maximises ``log p(globals) + sum_i log sum_z p(z) p(B_i | z) p(E_i | z)``
with ``TraceEnum_ELBO`` over the enumerated interpretation and an
``AutoDelta`` guide over the globals; this replaces the hand-coded EM of the
paper's Model 0 (kept in :mod:`groundlang.inference.model0` as a baseline).
Posteriors over interpretations come from ``TraceEnum_ELBO.compute_marginals``
or, equivalently and faster, from normalising the enumerated log-joint.
"""

from __future__ import annotations

import logging
import math
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import pyro
import pyro.distributions as dist
import torch
from pyro.infer import SVI, TraceEnum_ELBO
from pyro.infer.autoguide import AutoDelta
from pyro.infer.autoguide.initialization import init_to_mean, init_to_value
from pyro import poutine
from pyro.poutine.util import site_is_subsample

from groundlang.inference.em import EM_ACCELERATIONS, normalise_rows, run_em
from groundlang.model.encoding import Batch
from groundlang.model.generative import LOCAL_SITES, global_sizes, instance_model
from groundlang.model.language_models import LanguageModel
from groundlang.model.vocabulary import Vocabulary

__all__ = ["FitResult", "fit_globals", "log_joint", "posterior", "local_posteriors", "posterior_by_enumeration",
           "posteriors_by_enumeration", "per_parser_reading", "prior_concentrations", "single_threaded"]

log = logging.getLogger(__name__)


@contextmanager
def single_threaded():
    """Run torch on one thread: these tensors are small, and with two busy cores
    intra-op threading made each evaluation ~10x slower (measured: 0.37 s vs 0.035 s
    for the 240-instance parse model's word table)."""
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(before)


@dataclass
class FitResult:
    globals: dict[str, torch.Tensor]
    losses: list[float]
    steps: int  # EM steps (a forward and a backward pass each), or optimiser rounds
    converged: bool


def fit_globals(
    batch: Batch,
    lm: LanguageModel,
    vocab: Vocabulary,
    steps: int = 300,
    lr: float = 0.1,
    seed: int = 0,
    init: dict[str, torch.Tensor] | None = None,
    tol: float = 1e-7,
    optimizer: str = "auto",
    progress: bool = False,
    acceleration: str = "none",
) -> FitResult:
    """MAP estimate of the language model's globals.

    Optimisers (all maximise the same Pyro joint density, with the
    interpretation enumerated by ``TraceEnum_ELBO``):

    - ``"em"``: expectation-maximisation driven by autograd. For Dirichlet
      globals, ``phi * d log p(data, phi) / d phi`` is exactly the expected
      counts plus ``alpha - 1``, so one backward pass through the enumerated
      model gives the E step and normalising gives the M step; every step
      increases the objective, with no step size. Stops when the relative
      change of the objective is below ``tol`` or after ``steps`` iterations.
    - ``"lbfgs"``: L-BFGS (strong-Wolfe) on the unconstrained ``AutoDelta``
      parameters, ``steps // 20`` rounds of 20 iterations.
    - ``"adam"``: ``steps`` SVI steps with learning rate ``lr``.
    - ``"auto"``: EM when every global is Dirichlet, else L-BFGS.

    ``acceleration`` (EM only): ``"none"``, one EM step after another, or ``"squarem"``, which
    extrapolates along two EM steps (:mod:`groundlang.inference.em`) and never decreases the objective
    from one accepted iterate to the next.

    ``init`` warm-starts from earlier globals (e.g. the full model's, for a
    leave-one-out fold); the fit still runs to convergence on its own data.
    """
    if optimizer not in ("auto", "em", "lbfgs", "adam"):
        raise ValueError(f"unknown optimizer {optimizer!r}; expected auto, em, lbfgs or adam")
    if acceleration not in EM_ACCELERATIONS:
        raise ValueError(f"unknown EM acceleration {acceleration!r}; expected one of {', '.join(EM_ACCELERATIONS)}")
    if not isinstance(batch, lm.batch_type):
        raise TypeError(f"fit_globals: language model {lm.name} reads a {lm.batch_type.__name__} (lm.encode), "
                        f"not a {type(batch).__name__}")
    if not (isinstance(tol, (int, float)) and 0 <= tol < math.inf):  # a NaN or negative tol would never stop early
        raise ValueError(f"fit_globals: tol must be a finite number >= 0, not {tol!r}")
    with single_threaded():
        pyro.set_rng_seed(seed)
        pyro.clear_param_store()
        sizes = global_sizes(vocab)

        def model():
            return instance_model(batch, lm, sizes)

        sites = _global_sites(model)
        if optimizer == "auto":
            optimizer = "em" if all(isinstance(d, dist.Dirichlet) for d in sites.values()) else "lbfgs"
        if optimizer == "em":
            return _fit_em(model, sites, lm, steps, init, tol, progress, acceleration)
        return _fit_svi(model, lm, steps, lr, init, tol, optimizer, progress)


def _global_sites(model) -> dict:
    """The model's global sample sites and their prior distributions."""
    trace = poutine.trace(poutine.block(model, hide=list(LOCAL_SITES))).get_trace()
    return {
        name: site["fn"].base_dist if isinstance(site["fn"], dist.Independent) else site["fn"]
        for name, site in trace.nodes.items()
        if site["type"] == "sample" and not site["is_observed"] and not site_is_subsample(site)
    }


def _progress_bar(progress: bool, total: int, lm: LanguageModel):
    if not progress:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=f"training {lm.name}", unit="iter", leave=False)


def _log_joint(model, values: dict) -> torch.Tensor:
    """``log p(data, globals)`` with the interpretations summed out exactly."""
    conditioned = poutine.condition(model, data=values)
    return -TraceEnum_ELBO(max_plate_nesting=1).differentiable_loss(conditioned, _empty_guide)


def _empty_guide():
    pass


def log_joint(batch: Batch, lm: LanguageModel, vocab: Vocabulary, values: dict[str, torch.Tensor],
              use_behaviour: bool = True) -> torch.Tensor:
    """``log p(data, globals)`` of the Pyro model at ``values``, interpretations summed out exactly
    (differentiable: ``phi * grad`` is EM's expected counts plus the prior's ``alpha - 1``)."""
    sizes = global_sizes(vocab)
    return _log_joint(lambda: instance_model(batch, lm, sizes, use_behaviour), values)


def prior_concentrations(batch: Batch, lm: LanguageModel, vocab: Vocabulary) -> dict[str, torch.Tensor]:
    """Each Dirichlet global's prior concentration, shaped like the global."""
    sizes = global_sizes(vocab)
    sites = _global_sites(lambda: instance_model(batch, lm, sizes))
    return {name: prior.concentration for name, prior in sites.items() if isinstance(prior, dist.Dirichlet)}


def _fit_em(model, sites, lm, steps, init, tol, progress, acceleration) -> FitResult:
    for name, prior in sites.items():
        if init and name in init and tuple(init[name].shape) != tuple(prior.mean.shape):
            raise ValueError(f"fit: init[{name!r}] has shape {tuple(init[name].shape)}; this vocabulary's is "
                             f"{tuple(prior.mean.shape)} (a warm start needs the vocabulary it was fitted with)")
    values = {
        name: (init[name].clone() if init and name in init else prior.mean.detach().clone())
        for name, prior in sites.items()
    }
    bar = _progress_bar(progress, steps, lm)

    def step(current):
        leaves = {k: v.clone().requires_grad_(True) for k, v in current.items()}
        objective = _log_joint(model, leaves)
        objective.backward()
        with torch.no_grad():
            # phi * dlogp/dphi = expected counts + (alpha - 1): the M step.
            counts = {name: (leaf * leaf.grad).clamp_min(1e-12) for name, leaf in leaves.items()}
        if bar is not None:  # one tick per EM step, accepted or not
            bar.update(1)
        # Normalised in float64 (normalise_rows): float32 rows of a large vocabulary drift outside the
        # tolerance of Pyro's Simplex check, which the next step's log_prob of the Dirichlet prior applies.
        return {name: normalise_rows(c) for name, c in counts.items()}, -float(objective.detach())

    def tick(loss: float) -> None:
        if bar is not None:
            bar.set_postfix(loss=f"{loss:.1f}")

    values, losses, taken, converged = run_em(step, values, steps, tol, acceleration, tick)
    if bar is not None:
        bar.close()
    log.debug("EM (%s) fit %s: %d steps, final loss %.3f", acceleration, lm.name, taken, losses[-1])
    return FitResult(values, losses, taken, converged)


def _fit_svi(model, lm, steps, lr, init, tol, optimizer, progress) -> FitResult:
    init_fn = init_to_value(values=init, fallback=init_to_mean) if init else init_to_mean
    guide = AutoDelta(poutine.block(model, hide=list(LOCAL_SITES)), init_loc_fn=init_fn)
    elbo = TraceEnum_ELBO(max_plate_nesting=1)
    losses: list[float] = []
    converged = False
    rounds = steps if optimizer == "adam" else max(1, steps // 20)
    bar = _progress_bar(progress, rounds, lm)

    def tick(loss: float) -> None:
        losses.append(loss)
        if bar is not None:
            bar.update(1)
            bar.set_postfix(loss=f"{loss:.1f}")

    if optimizer == "adam":
        svi = SVI(model, guide, pyro.optim.Adam({"lr": lr}), elbo)
        for step in range(steps):
            tick(float(svi.step()))
            if step >= 10 and abs(losses[-11] - losses[-1]) <= tol * abs(losses[-1]):
                converged = True
                break
    else:
        guide()  # creates the parameters
        params = [p.unconstrained() for p in pyro.get_param_store().values()]
        opt = torch.optim.LBFGS(
            params, lr=1.0, max_iter=20, history_size=20, line_search_fn="strong_wolfe",
            tolerance_grad=1e-6, tolerance_change=1e-12,
        )

        def closure():
            opt.zero_grad()
            loss = elbo.differentiable_loss(model, guide)
            loss.backward()
            return loss

        for _ in range(rounds):
            tick(float(opt.step(closure).detach()))
            if len(losses) >= 2 and abs(losses[-2] - losses[-1]) <= tol * abs(losses[-1]):
                converged = True
                break
    if bar is not None:
        bar.close()
    with torch.no_grad():
        values = {k: v.detach().clone() for k, v in guide.median().items()}
    log.debug("%s fit %s: %d rounds, final loss %.3f", optimizer, lm.name, len(losses), losses[-1])
    return FitResult(values, losses, len(losses), converged)


def posterior(
    batch: Batch, lm: LanguageModel, g: dict[str, torch.Tensor], use_behaviour: bool = True
) -> torch.Tensor:
    """``P(z_i = j | words, behaviour)`` as ``[I, J]`` (0 on padding)."""
    return local_posteriors(batch, lm, g, use_behaviour)[0]


def local_posteriors(batch: Batch, lm: LanguageModel, g: dict[str, torch.Tensor], use_behaviour: bool = True
                     ) -> tuple[torch.Tensor, torch.Tensor | None]:
    """The posteriors of the sites :func:`instance_model` enumerates per instance, from its own terms
    summed exactly: ``P(z_i = j | words[, behaviour])`` ``[I, J]`` (0 on padding) and, for a language
    model that reads parses (``words_by_reading``), ``P(reading s | words[, behaviour])`` ``[I, S]`` over
    the merged structures of the parser's readings (else None). Pyro's own enumeration gives the same
    (:func:`posteriors_by_enumeration`, a test)."""
    with torch.no_grad():
        logits = batch.log_prior + (batch.behaviour if use_behaviour else 0.0)  # [I, J]
        by_reading = lm.words_by_reading(g, batch)
        if by_reading is None:
            return torch.softmax(logits + lm.log_likelihood(g, batch), dim=-1) * batch.mask, None
        table, reading_logits = by_reading  # [I, J, S], [I, S]
        joint = logits[:, :, None] + table + reading_logits[:, None, :]
        joint = joint.masked_fill(~batch.mask[:, :, None], float("-inf"))
        norm = torch.logsumexp(joint.flatten(1), dim=-1)[:, None]
        z = (torch.logsumexp(joint, dim=2) - norm).exp() * batch.mask
        return z, (torch.logsumexp(joint, dim=1) - norm).exp()


def _marginals(batch: Batch, lm: LanguageModel, vocab: Vocabulary, g: dict[str, torch.Tensor],
               use_behaviour: bool) -> dict[str, torch.Tensor]:
    """Pyro's ``compute_marginals`` of the enumerated sites of :func:`instance_model`, globals fixed, as
    probabilities ``[I, values]`` per site."""
    I = batch.num_instances
    sizes = global_sizes(vocab)

    def model():
        return instance_model(batch, lm, sizes, use_behaviour)

    # (Not under no_grad: Pyro computes the marginals by differentiating the log normaliser.)
    conditioned = poutine.condition(model, data=g)
    marginals = TraceEnum_ELBO(max_plate_nesting=1).compute_marginals(conditioned, _empty_guide)
    return {name: d.probs.detach().reshape(I, -1) for name, d in marginals.items()}


def posterior_by_enumeration(
    batch: Batch, lm: LanguageModel, vocab: Vocabulary, g: dict[str, torch.Tensor], use_behaviour: bool = True
) -> torch.Tensor:
    """The same posterior as :func:`posterior`, read off Pyro's ``compute_marginals`` (a cross-check)."""
    return _marginals(batch, lm, vocab, g, use_behaviour)["z"] * batch.mask


def posteriors_by_enumeration(batch: Batch, lm: LanguageModel, vocab: Vocabulary, g: dict[str, torch.Tensor],
                              use_behaviour: bool = True) -> tuple[torch.Tensor, torch.Tensor | None]:
    """:func:`local_posteriors` read off Pyro's ``compute_marginals`` of the enumerated sites (a
    cross-check: Pyro's contraction loses a plate or an enumerated site of size 1, so the batch needs
    two instances and two structures)."""
    marginals = _marginals(batch, lm, vocab, g, use_behaviour)
    return marginals["z"] * batch.mask, marginals.get("reading")


def per_parser_reading(structure: torch.Tensor, batch: Batch, prior) -> np.ndarray:
    """Spread ``P(s | words)`` ``[S]`` of one command over its parser readings, whose prior probabilities
    are ``prior``, by each reading's share of its merged structure's prior (``batch.reading_group``)."""
    group = batch.reading_group[0, : len(prior)].numpy()
    prior = np.asarray(prior, dtype=float)
    share = prior / np.bincount(group, weights=prior)[group]
    return structure.numpy()[group] * share
