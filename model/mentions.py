"""The parse model's mention factor: whether each mentionable object is named by some phrase.

Each mentionable object g of an interpretation (every toy, every object the task binds but the agent)
is named by some phrase ("covered") with probability ``mention[role_g, 0]`` and not with
``mention[role_g, 1]``. The factor sums over the phrases' alignments in closed form (inclusion-exclusion
over the objects left unnamed); ``tests/test_language_models.py`` checks it against summing over every
alignment.
"""

from __future__ import annotations

import itertools

import torch

from groundlang.model.parse_encoding import ParseBatch

__all__ = ["MENTION_SUBSETS_PER_BLOCK", "MAX_MENTIONABLE", "MentionLimitError", "mention_factor"]

MENTION_SUBSETS_PER_BLOCK = 64  # subsets of mentionable objects summed at once by the mention factor
# The factor sums over the subsets of the objects a command could name (every block, and the task's other
# objects): 2^16 subsets take seconds; each object more doubles time and memory (26 blocks: gigabytes).
MAX_MENTIONABLE = 16


class MentionLimitError(ValueError):
    """A layout with more objects a command could name than the mention factor sums over."""


def mention_factor(g: dict, batch: ParseBatch, joint: torch.Tensor, entities: torch.Tensor,
                   referring_only: bool = True) -> torch.Tensor:
    """``log`` of the mention model's factor per ``[I, J, R]``.

    With ``referring_only``, only a referring phrase (``batch.type_refers``) aligned with g names it;
    the others align as freely but name nothing. The alignments in which exactly the objects W go
    unnamed carry the mass ``E(W)``; with ``P(U)`` the mass of alignments avoiding the objects U
    (phrases choose roles independently, so it is a product over phrases), inclusion-exclusion gives
    ``sum_W E(W) prod_{W} m1 prod_{not W} m0 = sum_U P(U) prod_{U} (m1 - m0) prod_{not U} m0``, a
    polynomial in the mention parameters with non-negative coefficients in the E(W) form: ``phi * grad``
    still gives EM's expected counts. Returned relative to ``P({})`` (= ``entities``), to which it is
    added.
    """
    # Only the real interpretations, flattened to [N] = the True entries of ``batch.mask``: padding
    # fills [I, J] wherever an instance offers fewer interpretations than the most, and its factor
    # is 1 (log 0: no slot to name), so it is left at 0 rather than computed.
    real_i, real_j = batch.mask.nonzero(as_tuple=True)
    cover_mask = batch.cover_mask[real_i, real_j]  # [N, G]
    # Covered slots first in each row: a subset holding an uncovered slot weighs exactly 0, so rows
    # with c covered slots need only the 2^c subsets of their first c.
    order = torch.argsort((~cover_mask).to(torch.int8), dim=1, stable=True)
    cover_mask = torch.gather(cover_mask, 1, order)
    cover_slot = torch.gather(batch.cover_slot[real_i, real_j], 1, order)  # [N, G]
    covered = cover_mask.sum(1)  # [N]
    most = int(covered.max()) if len(covered) else 0
    if most > MAX_MENTIONABLE:
        raise MentionLimitError(f"{most} objects a command could name in one layout (its blocks and the task's "
                                f"room); the mention model sums over their subsets and reads at most "
                                f"{MAX_MENTIONABLE} (2^{MAX_MENTIONABLE} subsets)")
    total = torch.ones((len(real_i), entities.shape[-1]), dtype=torch.float64)
    for c in covered.unique().tolist():
        if c == 0:
            continue  # nothing to name: the factor is 1
        rows = (covered == c).nonzero(as_tuple=True)[0]
        part = _factor_of_rows(g, batch, joint, real_i[rows], real_j[rows], cover_slot[rows, :c], referring_only)
        total = total.index_put((rows,), part)
    out = torch.zeros(entities.shape, dtype=torch.float64).index_put((real_i, real_j), total.clamp_min(1e-30).log())
    return out.to(entities.dtype)


def _factor_of_rows(g: dict, batch: ParseBatch, joint: torch.Tensor, real_i: torch.Tensor, real_j: torch.Tensor,
                    cover_slot: torch.Tensor, referring_only: bool) -> torch.Tensor:
    """The factor ``[N, R]`` of rows whose slots ``cover_slot [N, G]`` are all covered."""
    G = cover_slot.shape[-1]
    role_of_slot = torch.gather(batch.role[real_i, real_j], 1, cover_slot)  # [N, G]
    # In double precision: the terms alternate in sign and nearly cancel when a task's object
    # is almost surely named, so float32 would leave errors of 1e-3 nats that depend on padding.
    mention = g["mention"].double()[role_of_slot]  # [N, G, 2]
    joint = joint[real_i, real_j].double()  # [N, V, K]
    named = mention[..., 0]
    unnamed_minus_named = mention[..., 1] - mention[..., 0]
    # Each slot is its own role binding, so the roles avoiding U carry the mass of all roles
    # less the slots' own: one subtraction per subset instead of a masked logsumexp.
    K = joint.shape[2]
    top = joint.max(dim=1, keepdim=True).values  # [N, 1, K]
    mass = (joint - top).exp()  # [N, V, K]
    all_roles = mass.sum(1)  # [N, K]
    slot_mass = torch.gather(mass, 1, cover_slot[..., None].expand(-1, -1, K))  # [N, G, K]
    # Subsets U of the slots, a block at a time: chosen[u, g] says whether slot g is in subset u.
    # Blocks bound the memory of [N, subsets, K] when a layout has many toys.
    subsets = torch.tensor(list(itertools.product((False, True), repeat=G)), dtype=torch.bool)  # [2^G, G]
    naming = batch.type_mask & batch.type_refers if referring_only else batch.type_mask
    types = naming[real_i][:, None, :]  # [N, 1, K]
    readings = batch.reading_types.double()[real_i]  # [N, R, K]
    total = torch.zeros((len(real_i), readings.shape[1]), dtype=torch.float64)
    for chosen in subsets.split(MENTION_SUBSETS_PER_BLOCK):
        weight = torch.where(chosen, unnamed_minus_named[:, None, :], named[:, None, :]).prod(-1)  # [N, U]
        avoided = torch.einsum("ngk,ug->nuk", slot_mass, chosen.to(slot_mass.dtype))  # [N, U, K]
        share = ((all_roles[:, None, :] - avoided) / all_roles[:, None, :]).clamp_min(1e-30).log()
        share = torch.einsum("nuk,nrk->nur", share * types, readings)
        total = total + (weight[..., None] * share.exp()).sum(1)  # [N, R]
    return total
