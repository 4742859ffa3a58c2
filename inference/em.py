"""EM for Dirichlet globals, plain or accelerated by SQUAREM.

The E and M steps come from one backward pass of the enumerated model (see
:func:`groundlang.inference.joint.fit_globals`); this module only decides
where to take the next step from. SQUAREM (Varadhan & Roland, *Scand. J.
Statist.* 2008, scheme S3) treats two EM steps ``t0 -> t1 -> t2`` as a
fixed-point iteration and extrapolates along them:

    r = t1 - t0,  v = t2 - 2 t1 + t0,  a = -|r| / |v| (at most -1),
    t' = t0 - 2 a r + a^2 v,

then takes one EM step from ``t'``. ``a = -1`` gives back ``t2``, so the
scheme never does less than two EM steps per cycle; where EM crawls along a
ridge (a word shared by two symbols, a slowly emptying reading) it jumps
ahead by ``a^2`` steps. Both ``r`` and ``v`` sum to zero over a simplex, so
``t'`` keeps every row's total; entries the jump makes negative are clipped
and the row renormalised. The jump is kept only if ``t'`` scores at least as
well as ``t1``; otherwise the cycle ends at ``t2`` as plain EM would, so the
objective never decreases from one cycle to the next.
"""

from __future__ import annotations

from typing import Callable

import torch

__all__ = ["EM_ACCELERATIONS", "run_em", "normalise_rows"]

EM_ACCELERATIONS = ("none", "squarem")

Values = dict[str, torch.Tensor]
# One EM step: the globals after it and the loss (-log p(data, globals)) at the globals before it.
Step = Callable[[Values], tuple[Values, float]]
_FLOOR = 1e-12


def run_em(step: Step, values: Values, steps: int, tol: float, acceleration: str = "none",
           tick: Callable[[float], None] | None = None) -> tuple[Values, list[float], int, bool]:
    """Iterate ``step`` from ``values`` until one EM step changes the loss by at most ``tol`` (relative)
    or ``steps`` EM steps have been taken.

    Returns the final globals, the loss of every accepted iterate (non-increasing up to rounding),
    the number of EM steps taken and whether it converged.
    """
    if acceleration not in EM_ACCELERATIONS:
        raise ValueError(f"unknown EM acceleration {acceleration!r}; expected one of {', '.join(EM_ACCELERATIONS)}")
    losses: list[float] = []

    def accept(loss: float) -> bool:
        losses.append(loss)
        if tick is not None:
            tick(loss)
        return len(losses) >= 2 and abs(losses[-2] - losses[-1]) <= tol * abs(losses[-1])

    taken = 0
    if acceleration == "none":
        while taken < steps:
            values, loss = step(values)
            taken += 1
            if accept(loss):
                return values, losses, taken, True
        return values, losses, taken, False

    # Stopping means the same as for plain EM: one EM step (t0 -> t1) changes the loss by at most tol.
    t0 = values
    while taken < steps:
        t1, loss0 = step(t0)
        taken += 1
        accept(loss0)
        if taken >= steps:
            return t1, losses, taken, False
        t2, loss1 = step(t1)
        taken += 1
        if abs(loss0 - loss1) <= tol * abs(loss1):
            accept(loss1)
            return t2, losses, taken, True
        r = {k: t1[k] - t0[k] for k in t0}
        v = {k: t2[k] - 2 * t1[k] + t0[k] for k in t0}
        r_norm = torch.sqrt(sum((x.double() ** 2).sum() for x in r.values()))
        v_norm = torch.sqrt(sum((x.double() ** 2).sum() for x in v.values()))
        a = -float(r_norm / v_norm) if float(v_norm) > 0.0 else -1.0
        if a >= -1.0 or taken >= steps:
            t0 = t2  # no jump beyond two plain steps
            continue
        jumped = {k: _on_simplex(t0[k] - 2 * a * r[k] + a * a * v[k]) for k in t0}
        t3, loss_jumped = step(jumped)
        taken += 1
        # An EM step from the jump scores at least as well as the jump itself.
        t0 = t3 if loss_jumped <= loss1 else t2
    return t0, losses, taken, False


def normalise_rows(x: torch.Tensor) -> torch.Tensor:
    """``x`` (non-negative, a positive total per row) with each row divided by its total, in ``x``'s dtype.

    The total and the division are taken in float64 and rounded to ``x``'s dtype once, per entry, so a
    float32 row sums to 1 within 2**-24 however many entries it has: summed in float32, a row of hundreds
    of words with counts from 0.05 to hundreds is off by ~1e-6, the tolerance of Pyro's ``Simplex``
    check, which adds rounding of its own."""
    x64 = x.double()
    return (x64 / x64.sum(-1, keepdim=True)).to(x.dtype)


def _on_simplex(x: torch.Tensor) -> torch.Tensor:
    return normalise_rows(x.clamp_min(_FLOOR))
