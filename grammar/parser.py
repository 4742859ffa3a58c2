"""Parse commands into logical forms with probabilities (the paper's SP component).

Pipeline: tokenise (lowercase, punctuation split off, hyphenated words split, multiword entries of the
lexicon such as "in front of" joined, every word kept), tag each word with its possible categories
(grammar.lexicon: English from ``english.words`` unless the caller hands a lexicon with a domain's
words), split into sentences, parse each sentence with
Earley over the grammar in ``commands.lark``, keep the best readings of each sentence from the parse
forest (grammar.kbest), fall back to chunks where the grammar fails (grammar.chunker), compose logical
forms for the whole command (grammar.composition) and normalise.

Speed: Earley returns the shared packed forest (``ambiguity="forest"``), scored once per node, instead
of explicit trees that unpack every ambiguity; the forest depends only on the sentence's word classes,
so it is cached by class sequence ("push star into orange room" and "move chair into green room"
share one). lark's unordered sets are used (faster); the scoring visits derivations in a fixed order,
so readings do not depend on the hash seed.
"""

from __future__ import annotations

import functools
import itertools
import logging
import math
import re
import unicodedata
from collections.abc import Mapping
from importlib.resources import files

from lark import Lark, Token
from lark.exceptions import LarkError
from lark.lexer import Lexer

from .chunker import chunk
from .composition import compose, instantiate
from .lexicon import Lexicon, SemanticLexicon
from .logical_form import LogicalForm, Reading
from .earley import install as install_fast_earley
from .kbest import MAX_FOREST_NODES, ForestKBest, ForestTooLarge, RuleSymbolNode, log_weights
from .phrases import DEFAULT_WEIGHTS, top_k

logger = logging.getLogger(__name__)

__all__ = ["DEFAULT_WEIGHTS", "ParseError", "Word", "checked_weights", "parse", "tokenise", "tag", "typed_words"]

# Longer sentences are split at commas first, then chunked: Earley is cubic and the number of PP
# attachments grows exponentially, and no corpus sentence needs more.
MAX_SENTENCE_TOKENS = 40
# Sentences (or comma-separated parts of long ones) whose readings are combined jointly; each later part
# adds its most probable reading only. Joint combination copies and compares whole reading tuples, so
# without a cap a command of thousands of sentences took minutes (quadratic); real commands have a few.
MAX_JOINT_PARTS = 16
SENTENCE_END = frozenset({".", "!", "?", ";", ":"})
CLAUSE_BREAK = frozenset({",", "(", ")", "-", "[", "]", "{", "}"})

# Grammar terminal -> the lexical categories that can play it (the parser's term matcher reads this).
CATEGORY_RULES: dict[str, frozenset[str]] = {
    "DET": frozenset({"DET"}), "PREP": frozenset({"PREP"}), "TO": frozenset({"TO"}), "CONJ": frozenset({"CONJ"}),
    "SUB": frozenset({"SUB"}), "REL": frozenset({"REL"}), "PRON": frozenset({"PRON"}), "AUX": frozenset({"AUX"}),
    "NEG": frozenset({"NEG"}), "ADV": frozenset({"ADV"}), "NOUN": frozenset({"NOUN", "MEASURE"}),
    "NMOD": frozenset({"ADJ", "COLOR", "NOUN", "NUM"}), "HMOD": frozenset({"ADJ", "COLOR", "NUM"}),
    "MEASURE": frozenset({"MEASURE"}), "VERB": frozenset({"VERB", "GER"}), "GER": frozenset({"GER"}),
    "COMMA": frozenset({"COMMA"}), "SERIAL": frozenset({"SERIAL"}),
    "DEGREE": frozenset({"DEGREE"}),
}

_TOKEN = re.compile(r"\w+(?:'\w+)*|\.{2,}|[^\w\s]")
_CLITIC = re.compile(r"^(\w+)('(?:re|s|m|ll|ve|d))$")
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f]")  # Unicode's category Cc


class ParseError(ValueError):
    """A command that cannot be parsed at all (empty, whitespace or punctuation only)."""


def utf8_fault(text: str) -> str | None:
    """``"is not UTF-8 text (byte 0xe9 at character 12)"`` where ``text`` holds a byte that was not UTF-8 (Python
    hands it over as a lone surrogate), else None: such text has no words to read."""
    bad = next((i for i, c in enumerate(text) if "\ud800" <= c <= "\udfff"), None)
    if bad is None:
        return None
    code = ord(text[bad])
    what = f"byte 0x{code - 0xdc00:02x}" if code >= 0xdc80 else f"U+{code:04X}"
    return f"is not UTF-8 text ({what} at character {bad + 1})"


def command_fault(command: str) -> str | None:
    """Why ``command`` cannot be read as a command, or None: text without a word says nothing to read."""
    if fault := utf8_fault(command):
        return fault
    text = _normalised(command)  # as the tokeniser reads it: NFKC makes some signs combining marks ("\u037a")
    if not text.strip():
        return "is empty or only whitespace"
    if not re.search(r"[^\W_]", text):  # a letter or a digit: "____" is no more a word than "----"
        return f"has no word, only punctuation ({text.strip()[:40]!r})"
    return None


def _without_control(text: str) -> str:
    """Control characters (a NUL from a binary file, a terminal's escape, a stray carriage return) as spaces:
    no part of what a person wrote, and read as punctuation one would become a word of the vocabulary."""
    return _CONTROL.sub(" ", text)


def _without_format(text: str) -> str:
    """Without Unicode's invisible format characters (category Cf: a zero-width joiner, a soft hyphen, a
    right-to-left mark, a byte order mark): inside a word they are no part of it ("re\u200dd" is red)."""
    return text if text.isascii() else "".join(c for c in text if unicodedata.category(c) != "Cf")


def _normalised(command: str) -> str:
    """A command as the tokeniser reads it, before any word file: control characters as spaces, invisible
    format characters dropped, Unicode NFKC (a letter typed as a base and a combining accent, "te\u0301le\u0301",
    is the word its precomposed spelling is; split at the accent, it would be two words and a sign; a full-width
    "\uff52\uff45\uff44", as an East Asian keyboard types it, is "red"), lower case, typographic apostrophes as "'"."""
    text = unicodedata.normalize("NFKC", _without_format(_without_control(command))).lower()
    return text.replace("\u2019", "'").replace("\u2018", "'")


def typed_words(command: str) -> list[str]:
    """The command's words and signs as typed (normalised as :func:`tokenise` reads it): what its tokens are
    unless a word file's multiword entries or synonyms, or the tokeniser's splits (clitics, hyphens, colour
    compounds), read them otherwise (``groundlang parse`` says how they were read where they differ)."""
    return _TOKEN.findall(_normalised(command))


Word = tuple[str, frozenset[str]]


def tokenise(command: str, word_lexicon: Lexicon | None = None) -> list[str]:
    """Lowercase tokens: words (hyphenated words and solid colour compounds like "bluegreen" split,
    clitics like 're split off, a word file's synonyms read as the word they stand for, multiword
    entries such as "left of" joined into ``left_of``) and punctuation. ``word_lexicon``: the words known
    (default: English, :meth:`Lexicon.english`)."""
    words = word_lexicon or Lexicon.english()
    text = re.sub(r"(?<=\w)-(?=\w)", " ", _normalised(command))
    out: list[str] = []
    for tok in _TOKEN.findall(text):
        m = _CLITIC.match(tok)
        if m and not tok.endswith("n't"):
            out.extend(piece for part in m.groups() for piece in words.read_as(part))
        elif re.fullmatch(r"\.{2,}", tok):
            out.append(".")
        else:  # a synonym's form is read before a colour compound is split: "bluegreen=teal" is read
            out.extend(piece for part in words.read_as(tok) for piece in words.split_compound_colour(part))
    return words.join_multiword(out)


def tag(tokens: list[str], word_lexicon: Lexicon | None = None) -> list[frozenset[str]]:
    """Possible categories of each token (empty set for punctuation the grammar skips)."""
    words = word_lexicon or Lexicon.english()
    cats: list[frozenset[str]] = []
    first = True
    for tok in tokens:
        if tok in SENTENCE_END:
            cats.append(frozenset())
            first = True
        elif tok in CLAUSE_BREAK:
            cats.append(frozenset({"COMMA"}))
            first = True
        elif not any(ch.isalnum() for ch in tok) and not words.listed(tok):
            cats.append(frozenset())  # quotes and the like: kept in words, not parsed ("&" is listed)
        else:
            c = words.categories(tok, first=first)
            cats.append(c)
            first = bool(c & {"CONJ", "COMMA", "SUB"})
    return cats


def _class_name(cats: frozenset[str]) -> str:
    return "_".join(sorted(cats))


# Token type (a lexical class such as "ADJ_NOUN") -> the grammar terminals it matches.
_TERMINALS_OF: dict[str, frozenset[str]] = {}


def _terminals_of(cls: str) -> frozenset[str]:
    found = _TERMINALS_OF.get(cls)
    if found is None:
        cats = frozenset(cls.split("_"))
        found = frozenset(t for t, wanted in CATEGORY_RULES.items() if cats & wanted)
        _TERMINALS_OF[cls] = found
    return found


def _match(term, token) -> bool:
    """Earley's term matcher: a word matches every grammar terminal its lexical tags allow."""
    return term.name in _terminals_of(token.type)


class _TaggedLexer(Lexer):
    """Feeds lark pre-tagged words: one token per word, typed by its lexical class."""

    def __init__(self, lexer_conf):  # lark's signature
        pass

    def lex(self, data):
        # the token value is the class too: the forest must not depend on the words (it is shared)
        for i, cls in enumerate(data):
            yield Token(cls, cls, start_pos=i, end_pos=i + 1, line=1, column=i + 1)


@functools.lru_cache(maxsize=1)
def _earley() -> tuple[Lark, dict]:
    """The Earley parser (returns forests) and a fixed index per grammar rule (the visiting order)."""
    grammar = files("groundlang.grammar").joinpath("commands.lark").read_text(encoding="utf-8")
    parser = Lark(grammar, parser="earley", lexer=_TaggedLexer, ambiguity="forest", start="start",
                  ordered_sets=False)
    # lark's basic Earley matches a terminal by token type; ours accepts a word for each of its categories
    earley = parser.parser.parser
    earley.term_matcher = _match
    earley.SymbolNode = RuleSymbolNode  # keeps NOUN and HMOD derivations of one word apart (grammar.kbest)
    install_fast_earley(earley)
    return parser, {rule: i for i, rule in enumerate(parser.rules)}


@functools.lru_cache(maxsize=512)  # ~60 kB per forest; the corpus has 355 distinct class sequences
def _parse_forest(classes: tuple[str, ...]):
    """Earley's parse forest (root symbol node) of a sentence's class sequence, None if rejected.

    Cached (independent of words and weights): crowd commands repeat sentence shapes a lot.
    """
    try:
        return _earley()[0].parse(list(classes))
    except (LarkError, RecursionError) as exc:
        logger.debug("grammar failed on %r: %s", " ".join(classes), type(exc).__name__)
        return None


def _sentences(tokens: list[str], cats: list[frozenset[str]]) -> list[list[Word]]:
    out: list[list[Word]] = [[]]
    for tok, c in zip(tokens, cats):
        if tok in SENTENCE_END:
            out.append([])
        elif c:
            out[-1].append((tok, c))
    return [s for s in out if s]


def _split_long(sentence: list[Word]) -> list[list[Word]]:
    if len(sentence) <= MAX_SENTENCE_TOKENS:
        return [sentence]
    parts: list[list[Word]] = [[]]
    for w in sentence:
        if "COMMA" in w[1] and parts[-1]:
            parts.append([])
        elif "COMMA" not in w[1]:
            parts[-1].append(w)
    return [p for p in parts if p]


def _parse_sentence(sentence: list[Word], logw: Mapping[str, float],
                    beam: int) -> tuple[list[tuple[float, tuple]], bool]:
    """Best (log weight, clause values) readings of one sentence, and whether it fell back to chunks."""
    if len(sentence) <= MAX_SENTENCE_TOKENS:
        classes = tuple(_class_name(c) for _, c in sentence)
        root = _parse_forest(classes)
        if root is not None:
            words = [Token(cls, w, start_pos=i) for i, ((w, _), cls) in enumerate(zip(sentence, classes))]
            try:
                cands = ForestKBest(logw, beam, words, _earley()[1]).best(root)
            except RecursionError:
                logger.debug("forest too deep for %r", " ".join(w for w, _ in sentence))
                cands = []
            except ForestTooLarge:  # read in chunks, as a sentence over MAX_SENTENCE_TOKENS is
                logger.debug("forest of more than %d nodes for %r", MAX_FOREST_NODES, " ".join(w for w, _ in sentence))
                cands = []
            cands = [(w, v) for w, v in cands if v]
            if cands:
                return cands, False
    return [(0.0, chunk([w for w, _ in sentence], [c for _, c in sentence]))], True


def _normalise(scored: list[tuple[float, LogicalForm]]) -> list[tuple[float, LogicalForm]]:
    """Sum equal logical forms; probabilities from log weights, summing to one, most probable first."""
    top = max(w for w, _ in scored)
    total: dict[LogicalForm, float] = {}
    for w, lf in scored:
        total[lf] = total.get(lf, 0.0) + math.exp(w - top)
    z = sum(total.values())
    return sorted(((p / z, lf) for lf, p in total.items()), key=lambda pl: (-round(pl[0], 12), repr(pl[1])))


def checked_weights(weights) -> dict[str, float]:
    """Overrides of DEFAULT_WEIGHTS by rule name, checked: a mapping of known rule names to positive
    finite numbers. Raises ValueError naming what is wrong (an unknown rule with the list of known ones)."""
    if not isinstance(weights, Mapping):
        raise ValueError(f"grammar weights must be rule names with weights, e.g. {{\"nmods_coord\": 1.0}}; "
                         f"got {weights!r}")
    unknown = sorted(set(weights) - set(DEFAULT_WEIGHTS))
    if unknown:
        raise ValueError(f"unknown grammar rule(s) {', '.join(map(repr, unknown))}; the rules are "
                         f"{', '.join(sorted(DEFAULT_WEIGHTS))}")
    for name, w in weights.items():
        if isinstance(w, bool) or not isinstance(w, (int, float)):
            raise ValueError(f"grammar weight {name!r} must be a positive finite number, got {w!r}")
    log_weights(weights)  # positive and finite
    return {name: float(w) for name, w in weights.items()}


# Readings kept per command at most: each widens the k-best beam every node of the parse forest keeps (1,000
# took 32 s and 100,000 more than 1.5 GB on a 30-word command, against 2 s for the default 8), and the
# thousandth reading of a command carries no probability worth reading.
READING_LIMIT = 256


def parse(command: str, max_readings: int = 8, lexicon: SemanticLexicon | None = None,
          weights: Mapping[str, float] | None = None, word_lexicon: Lexicon | None = None) -> list[Reading]:
    """Readings of a command, most probable first; probabilities sum to one; never empty.

    ``weights`` overrides entries of DEFAULT_WEIGHTS (positive numbers); ``lexicon`` instantiates the
    predicates of the words it knows; ``word_lexicon`` gives the words' categories (default: English
    only, :meth:`Lexicon.english`; a domain's nouns and colour words come with its word file). Raises
    ParseError (a ValueError) for empty or whitespace-only input, ValueError for ``max_readings`` out of 1 to
    READING_LIMIT
    or a non-positive weight, TypeError for a non-string command or lexicons of the wrong type.
    """
    if not isinstance(command, str):
        raise TypeError(f"parse: command must be a str, got {type(command).__name__}")
    if not 1 <= max_readings <= READING_LIMIT:
        raise ValueError(f"parse: max_readings must be 1 to {READING_LIMIT}, got {max_readings!r:.40}")
    if word_lexicon is not None and not isinstance(word_lexicon, Lexicon):  # a word file's text or path included
        raise TypeError(f"parse: word_lexicon must be a Lexicon (Lexicon.english(), or with words of your own "
                        f"groundlang.model.domain_words.domain_lexicon({{'NOUN': [...]}})) or None, got "
                        f"{type(word_lexicon).__name__}")
    if lexicon is not None and not isinstance(lexicon, SemanticLexicon):
        raise TypeError(f"parse: lexicon must be a SemanticLexicon or None, got {type(lexicon).__name__}")
    words = word_lexicon or Lexicon.english()
    fault = command_fault(command)
    if fault:
        raise ParseError(f"cannot parse the command: it {fault}")
    tokens = tokenise(command, words)
    cats = tag(tokens, words)
    tags = tuple(_class_name(c).replace("_", "|") if c else "PUNCT" for c in cats)
    beam = 2 * max_readings + 4
    logw = log_weights({**DEFAULT_WEIGHTS, **(checked_weights(weights) if weights else {})})  # a typo is named
    combined: list[tuple[float, tuple]] = [(0.0, ())]
    fallback = False
    tail: list = []  # best clause values of the parts after MAX_JOINT_PARTS, in order
    tail_weight = 0.0
    parts = (part for sentence in _sentences(tokens, cats) for part in _split_long(sentence))
    for n, part in enumerate(parts):
        cands, fell_back = _parse_sentence(part, logw, beam)
        fallback |= fell_back
        if n >= MAX_JOINT_PARTS:
            tail_weight += cands[0][0]
            tail.extend(cands[0][1])
            continue
        combined = top_k([(w1 + w2, c1 + c2) for (w1, c1), (w2, c2) in itertools.product(combined, cands)], beam)
    if tail:
        combined = [(w + tail_weight, c + tuple(tail)) for w, c in combined]
    token_tuple = tuple(tokens)
    if not any(c for c in cats):
        fallback = True  # punctuation only: one empty logical form that still keeps the tokens
    scored = [(w, compose(c, token_tuple, tags, fallback, words)) for w, c in combined]
    readings = _normalise(scored)
    if lexicon is not None:
        expanded = []
        for p, lf in readings:
            expanded += [(math.log(p * q) if p * q > 0 else -1e300, lf2) for q, lf2 in instantiate(lf, lexicon, beam)]
        readings = _normalise(expanded)
    readings = readings[:max_readings]
    z = sum(p for p, _ in readings)
    return [Reading(lf, p / z) for p, lf in readings]
