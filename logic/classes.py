"""The object classes of ``domain.lp``: their order, which move, which one commands speak to."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from functools import lru_cache

from .program import Program, Source, package_source

__all__ = ["DomainClasses", "domain_classes", "ranked"]


def ranked(classes: Iterable[str], rank: Mapping[str, int]) -> tuple[str, ...]:
    """``classes`` by ``class_rank/2`` (unranked ones last, by name): the order of a lifted task's variables."""
    return tuple(sorted(classes, key=lambda c: (rank.get(c, len(rank) + 1), c)))


@dataclass(frozen=True)
class DomainClasses:
    """The classes of ``domain.lp`` alone: by rank, which move, which is spoken to."""

    classes: tuple[str, ...]
    movable: frozenset[str]
    addressee: frozenset[str]
    kinds: frozenset[str] = frozenset()  # attributes whose values name kinds of things (``kind/1``)

    @property
    def mentioned(self) -> frozenset[str]:
        """Classes whose objects a command names whenever their task moves them (movers but "you")."""
        return self.movable - self.addressee


@lru_cache(maxsize=1)
def domain_classes() -> DomainClasses:
    """``class/1``, ``class_rank/2``, ``movable/1``, ``addressee/1`` and ``kind/1`` of ``domain.lp``, solved once."""
    show = Source("groundlang.logic.classes",
                  "#show class/1. #show class_rank/2. #show movable/1. #show addressee/1. #show kind/1.")
    found: dict[str, dict[str, int]] = {"class": {}, "class_rank": {}, "movable": {}, "addressee": {}, "kind": {}}
    for sym in Program((package_source("domain.lp"), show)).solve(models=1)[0]:
        found[sym.name][str(sym.arguments[0])] = sym.arguments[1].number if sym.name == "class_rank" else 0
    return DomainClasses(ranked(found["class"], found["class_rank"]), frozenset(found["movable"]),
                         frozenset(found["addressee"]), frozenset(found["kind"]))
