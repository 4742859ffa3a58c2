"""Phrase values built from parse-tree nodes, the default rule weights, and k-best list helpers.

``build(rule, children)`` turns a grammar rule's children values (lark Tokens for words, phrase values
for sub-phrases) into the rule's phrase value; grammar.kbest applies it to every derivation in
Earley's parse forest and keeps the best candidates ``(log weight, phrase)``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any, Union

from lark import Token

# Default rule weights (a PCFG-like score; a reading's weight is the product of the weights of its
# choice rules, then readings are normalised). Only rules that compete with each other matter:
# - c_pp / np_pp: a PP after "verb NP" attaches to the verb 0.65, to the noun 0.35. These are the
#   paper's numbers for "Push the star into the green room"; minimal attachment (and the corpus, where
#   the "into/to/through X" after the object names the goal) favours the verb. c_part / np_part are the
#   same choice for participles ("push star pushing it ..." vs "door leading into orange room").
# - frag, frag_np (verbless fragments) 0.2: only a fallback reading when a verb is present.
# - vp_ellipsis 0.2: complements after a comma continue the verb before it, against a verbless clause
#   of their own (frag); chosen by held-out likelihood (ABLATIONS.md).
# - subj_clause 0.5: commands are imperative; a subject reading ("star goes into blue") competes only
#   when an NP-like word opens the clause.
# - np_headless 0.5: an ambiguous word ("ornge") is likelier the head noun than a bare modifier.
# - np_coord, c_measure 0.5 / 0.3: coordination and measure phrases ("all way") are rarer than
#   the alternatives they compete with (clause coordination, a direct object).
# - nmods_coord 0.5: coordinated modifiers of one noun ("a room with white / cream floor") against
#   coordinated noun phrases ("white" and "cream floor"); both readings stay (measured: ABLATIONS.md).
DEFAULT_WEIGHTS: dict[str, float] = {
    "c_pp": 0.65, "np_pp": 0.35, "c_part": 0.65, "np_part": 0.35,
    "frag": 0.2, "frag_np": 0.2, "vp_ellipsis": 0.2, "subj_clause": 0.5, "np_headless": 0.5, "np_coord": 0.5,
    "nmods_coord": 0.5, "c_measure": 0.3, "c_adv": 1.0, "c_inf": 1.0, "c_sub": 1.0, "c_ger": 1.0, "sub_clause": 1.0,
    "np_rel": 1.0, "np_head": 1.0, "np_pron": 1.0, "pp": 1.0, "pp_coord": 1.0, "vp": 1.0, "gvp": 1.0,
    "vhead_serial": 1.0,
}


@dataclass(frozen=True)
class NP:
    """A noun phrase: determiner, modifiers, head (None if headless), pronoun, attached PPs/clauses."""

    det: str | None = None
    mods: tuple[str, ...] = ()
    head: str | None = None
    pron: str | None = None
    attached: tuple["PP | Sub", ...] = ()
    conjuncts: tuple["NP", ...] = ()


@dataclass(frozen=True)
class PP:
    prep: str
    obj: NP


@dataclass(frozen=True)
class Adv:
    word: str


@dataclass(frozen=True)
class Measure:
    np: NP


@dataclass(frozen=True)
class VP:
    """A clause: verb word form (None for fragments), negation, subject, direct object, complements."""

    verb: str | None = None
    negated: bool = False
    subject: NP | None = None
    obj: NP | None = None
    comps: tuple["PP | Adv | Measure | Sub", ...] = ()
    adverbs: tuple[str, ...] = ()


@dataclass(frozen=True)
class Sub:
    """A subordinate, infinitival, gerund or relative clause and the word that introduces it."""

    connective: str
    clause: Union[VP, "Sub"]


ClauseValue = Union[VP, Sub]
Candidates = list[tuple[float, Any]]

_SEP = "<sep>"


def _words(children: list) -> list[str]:
    return [str(c) for c in children if isinstance(c, Token)]


def _np_parts(values: list) -> tuple[str | None, list[str]]:
    det = None
    rest = []
    for v in values:
        if isinstance(v, tuple) and v and v[0] == "det":
            det = v[1]
        elif isinstance(v, tuple) and v and v[0] == "mods":
            rest.extend(v[1])
        elif v is not _DEGREE:  # "the very big one": the degree grades, names nothing
            rest.append(str(v))
    return det, rest


def _verb_phrase(values: list) -> VP:
    pre: list[str] = []
    verb = None
    obj = None
    comps = []
    for v in values:
        if isinstance(v, tuple) and v and v[0] == "pre":
            pre.append(v[1])
        elif isinstance(v, tuple) and v and v[0] == "verb":
            verb = v[1]
        elif isinstance(v, tuple) and v and v[0] == "obj":
            obj = v[1]
        elif isinstance(v, (PP, Adv, Measure, Sub)):
            comps.append(v)
        elif isinstance(v, tuple) and v and v[0] == "comps":
            comps.extend(v[1])
        # conjunction tokens between complements carry no structure; the words keep them
    # a word's token type is its lexical class ("DET_NEG" for "no"): grammar.parser tags it
    negated = any(_is_negation(t) for t in pre)
    adverbs = tuple(str(t) for t in pre if not _is_negation(t))
    return VP(verb=verb, negated=negated, obj=obj, comps=tuple(comps), adverbs=adverbs)


def _is_negation(token: Token) -> bool:
    return "NEG" in token.type.split("_")


def _continued(vp: VP, comps) -> VP | None:
    """A verb phrase whose complements go on after a comma; rejected (None) where a clausal complement
    ends the verb phrase: what follows would belong to that clause, not to this verb (late closure, as in
    ``_complements``), and the grammar reads it as a fragment of its own."""
    if comps is None or (vp.comps and isinstance(vp.comps[-1], Sub)):
        return None
    return replace(vp, comps=vp.comps + comps[1])


def _fragment(values: list) -> VP:
    nps = [v for v in values if isinstance(v, NP)]
    comps = tuple(c for v in values if isinstance(v, tuple) and v and v[0] == "comps" for c in v[1])
    return VP(verb=None, obj=nps[0] if nps else None, comps=comps)


def _attach(np: NP, extra) -> NP:
    return replace(np, attached=np.attached + (extra,))


def _coord(a: NP, b: NP) -> NP:
    parts = (a.conjuncts or (a,)) + (b.conjuncts or (b,))
    return NP(conjuncts=parts)


def _connective(values: list) -> tuple[str, Any]:
    words = [str(v) for v in values if isinstance(v, Token)]
    clause = next(v for v in values if isinstance(v, (VP, Sub)))
    return " ".join(words), clause


# A degree word before a modifier ("the very small room"): it grades the modifier and names nothing.
_DEGREE = ("degree",)


# Builders: rule name -> function of the children's values.
_BUILDERS: dict[str, Callable[[list], Any]] = {
    "start": lambda vs: tuple(v for v in vs if isinstance(v, (VP, Sub))),
    "lead": lambda vs: _SEP,
    "trail": lambda vs: _SEP,
    "sep": lambda vs: _SEP,
    "vpre": lambda vs: ("pre", vs[0]),
    "vhead": lambda vs: ("verb", str(vs[0])),
    "vhead_serial": lambda vs: ("verb", str(vs[1])),
    "obj": lambda vs: ("obj", vs[0]),
    "determiner": lambda vs: ("det", str(vs[0])),
    "degree": lambda vs: _DEGREE,
    "nmods": lambda vs: ("mods", tuple(str(v) for v in vs if v is not _DEGREE)),
    "nmods_coord": lambda vs: ("mods", tuple(str(v) for v in vs if v is not _DEGREE and v.type != "CONJ")),
    "comps": lambda vs: _complements(vs),
    "vp": _verb_phrase,
    "gvp": lambda vs: _verb_phrase([("verb", str(vs[0]))] + list(vs[1:])),
    "subj_clause": lambda vs: replace(vs[1], subject=vs[0]),
    "sub_clause": lambda vs: Sub(*_connective(vs)),
    "vp_ellipsis": lambda vs: _continued(vs[0], vs[-1]),
    "frag_np": _fragment,
    "frag": _fragment,
    "c_pp": lambda vs: vs[0],
    "c_adv": lambda vs: Adv(str(vs[0])),
    "c_inf": lambda vs: Sub("to", vs[1]),
    "c_sub": lambda vs: Sub(*_connective(vs)),
    # "without going into ...": the lexicon's negating prepositions negate the clause (grammar.composition)
    "c_ger": lambda vs: Sub(str(vs[0]), vs[1]),
    "c_part": lambda vs: Sub("ing", vs[0]),
    "c_measure": lambda vs: Measure(_np_head(vs)),
    "np_pp": lambda vs: _attach(vs[0], vs[1]),
    "np_part": lambda vs: _attach(vs[0], Sub("ing", vs[1])),
    "np_rel": lambda vs: _attach(vs[0], Sub(str(vs[1]), vs[2])),
    "np_head": lambda vs: _np_head(vs),
    "np_headless": lambda vs: _np_headless(vs),
    "np_pron": lambda vs: NP(pron=str(vs[0])),
    "np_coord": lambda vs: _coord(vs[0], vs[2]),
    "pp": lambda vs: PP(str(vs[0]), vs[1]),
    "pp_coord": lambda vs: PP(str(vs[2]), vs[3]),
}


def build(rule: str, children) -> Any:
    """The phrase value of a tree node named ``rule`` (alias or rule name); None if the node is rejected.

    Raises ValueError for a rule without a builder (a grammar rule added without one).
    """
    try:
        builder = _BUILDERS[rule]
    except KeyError:
        raise ValueError(f"grammar rule {rule!r} has no phrase builder") from None
    return builder(list(children))


def _complements(values: list):
    comps = tuple(v for v in values if isinstance(v, (PP, Adv, Measure, Sub)))
    # late closure: a clausal complement ("without walking ...", "until ...") takes what follows it
    if any(isinstance(c, Sub) for c in comps[:-1]):
        return None
    return ("comps", comps)


def _np_head(values: list) -> NP:
    det, words = _np_parts(values)
    return NP(det=det, mods=tuple(words[:-1]), head=words[-1])


def _np_headless(values: list) -> NP:
    det, words = _np_parts(values)
    return NP(det=det, mods=tuple(words))


def _logaddexp(a: float, b: float) -> float:
    m = max(a, b)
    return m + math.log1p(math.exp(-abs(a - b)))


def merge(cands: Candidates, beam: int) -> Candidates:
    """Sum the weights of equal phrases, keep the ``beam`` best (highest log weight first)."""
    best: dict[Any, float] = {}
    for logw, value in cands:
        old = best.get(value)
        best[value] = logw if old is None else _logaddexp(old, logw)
    return top_k([(w, v) for v, w in best.items()], beam)


def top_k(items: list[tuple[float, Any]], k: int) -> list[tuple[float, Any]]:
    """The k highest-weight (weight, value) pairs; ties at the cut broken by ``repr`` (deterministic).

    lark's Earley sets are unordered, so alternatives arrive in an order that varies with the hash seed.
    """
    items = sorted(items, key=lambda wv: -wv[0])
    if len(items) > k and abs(items[k][0] - items[k - 1][0]) < 1e-9:
        cut = items[k - 1][0]
        above = [wv for wv in items if wv[0] > cut + 1e-9]
        tied = sorted((wv for wv in items if abs(wv[0] - cut) <= 1e-9), key=lambda wv: repr(wv[1]))
        items = above + tied
    return items[:k]
