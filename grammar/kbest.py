"""The k best phrase values of a sentence, read off Earley's shared packed parse forest (SPPF).

lark's Earley with ``ambiguity="forest"`` returns the SPPF: a symbol node per (symbol, start, end)
whose packed nodes are its derivations, binarised through intermediate nodes (a rule's prefix). Each
node gets a short list of candidates ``(log weight, values)``: ``values`` is what the node adds to its
parent's children, shaped the way lark shapes parse trees (rules named ``_x`` are spliced into the
parent, an un-aliased ``?rule`` with one child is replaced by it, every other rule is built by
grammar.phrases.build and adds its log weight). Alternatives are summed when they give the same value
(the paper sums parses per logical form) and pruned to the beam. Nodes are shared, so every node is
scored once (memoised): linear in the forest, where explicit trees unpack every ambiguity.

The forest depends on the word classes only (the parser caches it by class sequence); the words are
read from the sentence by token position. Packed nodes are visited in a fixed order (rule, split
point), so the result does not depend on the hash seed or on lark's set order.

lark's packed nodes compare equal when their children do, whatever the rule: a word that is both NOUN
and HMOD ("bottom") gives ``np_base -> NOUN`` and ``np_base -> HMOD`` with the same single token child,
and lark keeps whichever came first (hash-seed dependent with unordered sets, and one reading lost
either way). ``RuleSymbolNode`` is installed as the parser's symbol node class: its packed nodes also
compare the rule, so both derivations stay.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from typing import Any

from lark import Token
from lark.parsers.earley_forest import PackedNode, SymbolNode, TokenNode

from .phrases import build, merge, top_k

Candidates = list[tuple[float, tuple]]

_EMPTY: Candidates = [(0.0, ())]

# The symbol nodes a sentence's forest may have scored. Every sentence of both shared corpora needs at most
# about 200; 40 words each in several classes ("then" forty times) give thousands, and minutes of merging.
MAX_FOREST_NODES = 2_000


class ForestTooLarge(Exception):
    """The forest has more symbol nodes than :data:`MAX_FOREST_NODES`: the sentence is read in chunks."""


def log_weights(weights: Mapping[str, float]) -> dict[str, float]:
    """Log of each rule weight. Raises ValueError for a weight that is not positive and finite."""
    out = {}
    for name, w in weights.items():
        if not (w > 0.0) or math.isinf(w):
            raise ValueError(f"grammar weight {name!r} must be a positive finite number, got {w}")
        out[name] = math.log(w)
    return out


class RulePackedNode(PackedNode):
    """A packed node equal to another only for the same rule and the same children."""

    __slots__ = ()

    def __init__(self, parent, s, rule, start, left, right):
        super().__init__(parent, s, rule, start, left, right)
        self._hash = hash((id(rule), self._hash))

    def __eq__(self, other):
        return self is other or (isinstance(other, PackedNode) and self.rule is other.rule
                                 and self.left == other.left and self.right == other.right)

    def __hash__(self):
        return self._hash


class RuleSymbolNode(SymbolNode):
    """lark's symbol node with rule-aware packed nodes (set ``earley.SymbolNode`` to this class)."""

    __slots__ = ()

    def add_family(self, lr0, rule, start, left, right):
        self._children.add(RulePackedNode(self, lr0, rule, start, left, right))


class ForestKBest:
    """Scores one sentence's forest: ``best(root)`` gives the ``beam`` best values of the start rule.

    ``words``: the sentence's tokens as lark Tokens (type: lexical class, value: the word), indexed by
    the position the tagged lexer gave them. ``rule_index``: a fixed number per grammar rule.
    """

    def __init__(self, logw: Mapping[str, float], beam: int, words: Sequence[Token],
                 rule_index: Mapping[Any, int]):
        self.logw = logw
        self.beam = beam
        self.words = words
        self.rule_index = rule_index
        self.memo: dict[int, Candidates] = {}

    def best(self, root: SymbolNode) -> list[tuple[float, Any]]:
        """(log weight, value) of the root's start rule, best first."""
        return [(w, vals[0]) for w, vals in self._node(root) if len(vals) == 1]

    def _node(self, node) -> Candidates:
        if node is None:
            return _EMPTY
        if isinstance(node, TokenNode):
            return [(0.0, (self.words[node.token.start_pos],))]
        key = id(node)
        found = self.memo.get(key)
        if found is None:
            if len(self.memo) >= MAX_FOREST_NODES:
                raise ForestTooLarge(len(self.memo))
            found = self._symbol(node)
            self.memo[key] = found
        return found

    def _symbol(self, node: SymbolNode) -> Candidates:
        index = self.rule_index
        packed = sorted(node.children, key=lambda pn: (index[pn.rule], pn.start))
        out: Candidates = []
        for pn in packed:
            seqs = self._product(self._node(pn.left), self._node(pn.right))
            if node.is_intermediate:
                out += seqs
                continue
            rule = pn.rule
            if rule.origin.name.startswith("_"):  # lark splices "_x" rules into their parent
                out += seqs
                continue
            name = rule.alias or rule.origin.name
            own = self.logw.get(name, 0.0)
            expand1 = rule.options.expand1 and not rule.alias
            for w, vals in seqs:
                if expand1 and len(vals) == 1:
                    out.append((w, vals))
                    continue
                value = build(name, vals)
                if value is not None:
                    out.append((w + own, (value,)))
        return merge(out, self.beam) if len(out) > 1 else out

    def _product(self, left: Candidates, right: Candidates) -> Candidates:
        if len(left) == 1 and len(right) == 1:
            (w1, a), (w2, b) = left[0], right[0]
            return [(w1 + w2, a + b)]
        return top_k([(w1 + w2, a + b) for (w1, a), (w2, b) in itertools.product(left, right)], self.beam)
