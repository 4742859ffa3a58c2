"""The words the parser knows and their lexical categories, read from word files; the semantic model.

The parser knows no meanings, only syntax. Which category a word may play (determiner, preposition,
verb, noun, ...) is data: closed-class English ships in ``grammar/english.words``, a domain's nouns and
adjectives sit in a word file beside its ``.lp`` files, and a caller may add words of its own
(:meth:`Lexicon.extend`, :meth:`Lexicon.with_files`). A word no file lists is still parsed: its
categories are guessed from its suffix and position. A word may carry several categories ("left" is
an adverb, an adjective and a noun); the grammar decides which one a reading uses.

The word file format is read and checked in ``grammar/word_files.py`` (documented at the top of
``english.words``).

``SemanticLexicon`` is the paper's semantic model (LWFG's Phi_i constraints): words mapped to domain
propositional functions with probabilities, learned later by the joint model and handed to ``parse``.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from importlib.resources import files
from pathlib import Path

from .word_files import CATEGORIES, FILE_CATEGORIES, TAGGING, LexiconError, SynonymForms, check_words, read_word_file

__all__ = ["CATEGORIES", "CLOSED_CLASS", "FILE_CATEGORIES", "Lexicon", "LexiconError", "SemanticLexicon", "read_word_file"]

# A multiword entry's first word that may head or modify a noun phrase ("left" of "left of") does,
# rather than open the preposition, after a word of these categories: "the left of the room",
# "to left of star", "bottom left of orange room".
_NOUN_PHRASE_OPENERS = frozenset({"DET", "PREP", "TO", "ADJ", "NUM"})
# Marks, in the trie of multiword entries, a node where an entry ends: not a string, so no word collides.
_END = None
# Categories of words a language does not add to: a serial verb or a degree word is none of them.
CLOSED_CLASS = frozenset({"DET", "PREP", "TO", "CONJ", "SUB", "REL", "PRON", "AUX", "NEG"})


def _one_each(entries: dict, category: str, conflict: str) -> dict[str, str]:
    """A paired category's ``form=value`` entries as ``{form: value}``; LexiconError where a form has two values
    (``conflict`` formatted with the first and the second)."""
    out: dict[str, str] = {}
    for pair in entries.get(category, ()):
        form, value = pair.split("=", 1)
        if out.setdefault(form, value) != value:
            raise LexiconError(f"{category} {form!r} {conflict.format(out[form], value)}")
    return out


def _inflections(lemma: str) -> dict[str, str]:
    """Regular forms of a verb lemma: -s, -ed, -ing, with the usual spelling changes."""
    forms = {lemma: lemma}
    stem = lemma[:-1] if lemma.endswith("e") and not lemma.endswith("ee") else lemma
    forms[stem + "ing"] = lemma
    consonant_y = len(lemma) >= 2 and lemma[-1] == "y" and lemma[-2] not in "aeiou"
    if lemma.endswith("e"):
        forms[lemma + "d"] = lemma  # move -> moved
    elif consonant_y:
        forms[lemma[:-1] + "ied"] = lemma  # carry -> carried
    else:
        forms[lemma + "ed"] = lemma  # push -> pushed
    if consonant_y:
        forms[lemma[:-1] + "ies"] = lemma
    else:
        forms[lemma + ("es" if lemma.endswith(("s", "sh", "ch", "x")) else "s")] = lemma
    if len(lemma) >= 3 and lemma[-1] in "pgtbm" and lemma[-2] in "aeiou" and lemma[-3] not in "aeiou":
        forms[lemma + lemma[-1] + "ing"] = lemma  # stop -> stopping
        forms[lemma + lemma[-1] + "ed"] = lemma
    return forms


class Lexicon:
    """The words the parser knows, by category; immutable (extending gives a new lexicon).

    ``entries``: words by word-file category (:data:`FILE_CATEGORIES`), as read from word files or
    given as data. Raises LexiconError for an unknown category or a malformed entry.
    """

    def __init__(self, entries: Mapping[str, Iterable[str]] | None = None, *, _checked: bool = False):
        merged: dict[str, dict[str, None]] = {}  # in the order given, once each: a conflict cites the first
        for category, words in (entries or {}).items():
            # words :meth:`extend` has checked and normalised are not checked again: checking is most of the
            # cost of loading a model whose word file is large, and each extension would repeat it
            merged.setdefault(category, {}).update(dict.fromkeys(
                tuple(words) if _checked else check_words(category, words, "word list")))
        said = SynonymForms()
        for pair in merged.get("SYNONYM", ()):
            said.add(pair, None, "in the words before")
        self.entries: dict[str, tuple[str, ...]] = {
            c: tuple(sorted(merged[c])) for c in FILE_CATEGORIES if merged.get(c)}
        words = {c: frozenset(self.entries.get(c, ())) for c in FILE_CATEGORIES}
        # Verb forms: regular inflections of every lemma, in a fixed order, then the irregular ones.
        self.verb_forms: dict[str, str] = {}
        # a serial verb or a verb of having is a verb, listed so or not (else its clauses would go unread)
        for lemma in sorted(words["VERB"] | words["VERB_SERIAL"] | words["VERB_HAVING"]):
            self.verb_forms.update(_inflections(lemma))
        # a form is of one verb (entries are sorted: no order decides)
        self.verb_forms.update(_one_each(self.entries, "IRREGULAR",
                                         "is a form of {0!r} and of {1!r}: a form is of one verb"))
        table: dict[str, set[str]] = {}
        for category in FILE_CATEGORIES:
            tag = TAGGING.get(category, category)
            if tag in CATEGORIES and category != "VERB":
                for word in words[category]:
                    table.setdefault(word, set()).add(tag)
        for form in self.verb_forms:
            cats = table.setdefault(form, set())
            cats.add("GER" if form.endswith("ing") else "VERB")
            if form.endswith("ed"):
                cats.add("ADJ")  # past participles modify nouns: "orange-floored room", "colored room"
        for word in words["ADV_DEGREE"]:  # a degree word is an adverb too, listed so or not ("mighty quickly")
            table.setdefault(word, set()).add("ADV")
        # A closed-class word read as a serial verb or a degree word changes every command that uses it ("not" as a
        # degree word had dropped the negation of "the not red room"; "to" as a serial verb read "go to" as "to").
        for category in ("VERB_SERIAL", "ADV_DEGREE"):
            for word in sorted(words[category]):
                if closed := sorted(table.get(word, set()) & CLOSED_CLASS):
                    raise LexiconError(f"{category} word {word!r} is also {', '.join(closed)}, a closed class: a "
                                       f"{'serial verb' if category == 'VERB_SERIAL' else 'degree word'} is an open "
                                       "word")
        self._listed = {word: frozenset(cats) for word, cats in table.items()}
        self.hues = words["HUE"]
        # A compound's first hue is one of these lengths: cutting only there keeps the split linear in the
        # word's length (every cut of a word as long as the longest hue, each a slice of that length, was
        # quadratic: a word file's 80,000-letter hue took seconds a word).
        self._hue_lengths = tuple(sorted({len(h) for h in self.hues if len(h) >= 3}))
        # Each form the word it is read as, in tokens (a multiword word's parts, joined afterwards).
        self.synonyms: dict[str, tuple[str, ...]] = {}
        for pair in self.entries.get("SYNONYM", ()):
            form, word = pair.split("=", 1)
            self.synonyms[form] = tuple(word.split("_"))
        self.negating_prepositions = words["PREP_NEGATING"]
        self.source_and_comitative_prepositions = words["PREP_SOURCE"]
        self.having_verbs = words["VERB_HAVING"]
        # Words that take or decline what a question offers (clarify's answers, never a command's words).
        self.yes_words, self.no_words = words["YES"], words["NO"]
        self.polite_words = words["POLITE"]  # saying nothing of what is meant, in a command or an answer
        # An answer's number of a choice in words ("the third one", "option two"): read in answers only.
        self.ordinals = _one_each(self.entries, "ORDINAL", "is the number {0} and {1}: a word names one number")
        self.choice_nouns = words["CHOICE_NOUN"]
        self.definite_determiners = words["DET_DEFINITE"]
        # The preposition a clause of having reads as ("with"); None when no word file names one.
        if len(words["PREP_HAVING"]) > 1:  # one preposition a clause of having reads as; which would be a guess
            raise LexiconError(f"PREP_HAVING lists {len(words['PREP_HAVING'])} words "
                               f"({', '.join(sorted(words['PREP_HAVING']))}); expected one, the preposition a clause "
                               "of having reads as (e.g. with)")
        self.having_preposition = min(words["PREP_HAVING"], default=None)
        # Multiword entries as a trie of their words: the tokeniser joins the longest that fits, and a walk
        # down the trie finds it in as many steps as the entry has words, however many entries share a first
        # word (a list per first word took minutes for a large word file and a long command).
        multiword: dict[str, dict] = {}
        for word in table:
            if "_" in word.strip("_"):
                node = multiword
                for part in word.split("_"):
                    node = node.setdefault(part, {})
                node[_END] = True
        self._multiword = multiword

    # ------------------------------------------------------------------ building
    @classmethod
    @functools.cache
    def english(cls) -> "Lexicon":
        """Closed-class English, from the shipped ``grammar/english.words`` (read once)."""
        return cls(read_word_file(Path(str(files("groundlang.grammar").joinpath("english.words")))))

    @classmethod
    def from_files(cls, *paths: str | Path) -> "Lexicon":
        """English extended with the words of each word file, in order (see :meth:`with_files`)."""
        return cls.english().with_files(*paths)

    def with_files(self, *paths: str | Path) -> "Lexicon":
        """This lexicon extended with the words of each word file. Raises LexiconError naming file and
        line for a malformed file, OSError for one that cannot be read."""
        lexicon = self
        for path in paths:
            words = read_word_file(path)
            try:
                lexicon = lexicon.extend(words)
            except LexiconError as exc:  # what this file says against the words before it
                raise LexiconError(f"{path}: {exc}") from None
        return lexicon

    def extend(self, words_by_category: Mapping[str, Iterable[str]]) -> "Lexicon":
        """This lexicon with more words: ``{"NOUN": ["mug", "shelf"], "PREP": ["left of"], "HUE": ["teal"]}``.

        Categories are those of a word file (:data:`FILE_CATEGORIES`); words are lowercased and a
        multiword entry may be written with spaces or ``_``. Raises LexiconError for anything else.
        """
        if not words_by_category:
            return self
        if not isinstance(words_by_category, Mapping):
            raise LexiconError(f"words to add must map a category to its words, not {type(words_by_category).__name__}")
        merged = {c: list(ws) for c, ws in self.entries.items()}
        for category, words in words_by_category.items():
            merged.setdefault(category, []).extend(check_words(category, words, "word list"))
        return Lexicon(merged, _checked=True)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Lexicon) and self.entries == other.entries

    def __hash__(self) -> int:
        return hash(tuple((c, ws) for c, ws in self.entries.items()))

    def __repr__(self) -> str:
        return f"Lexicon({sum(map(len, self.entries.values()))} entries)"

    # ------------------------------------------------------------------ reading words
    def listed(self, word: str) -> frozenset[str]:
        """Categories the lexicon lists for ``word``; empty for a word it does not know (no guessing)."""
        return self._listed.get(word, frozenset())

    def categories(self, word: str, first: bool = False) -> frozenset[str]:
        """Categories of a word: listed ones if known, else an open-class guess by suffix and position.

        ``first``: the word opens a clause, where an unknown word may be an imperative verb.
        Never empty: anything not recognisable is a noun or an adjective (open class).
        """
        known = self._listed.get(word)
        if known:
            return known
        if not any(ch.isalpha() for ch in word):
            return frozenset({"NUM"}) if any(ch.isdigit() for ch in word) else frozenset({"ADJ", "NOUN"})
        if word.endswith("ly") and len(word) > 4:
            return frozenset({"ADV"})
        if word.endswith("ing") and len(word) > 5:
            return frozenset({"GER", "ADJ", "NOUN"})
        # Whatever its ending, an unknown word that opens a clause may be the imperative verb: a typo
        # such as "tranfser to blue room" ends like an adjective or noun ("-er") yet commands a motion.
        return frozenset({"ADJ", "NOUN", "VERB"}) if first else frozenset({"ADJ", "NOUN"})

    def lemma(self, word: str) -> str:
        """Lemma of a verb form ("pushing" -> "push"); other words are returned unchanged."""
        return self.verb_forms.get(word, word)

    def is_colour(self, word: str) -> bool:
        """Whether the word is listed as a colour word (a hue or a colour modifier)."""
        return "COLOR" in self._listed.get(word, ())

    def split_compound_colour(self, word: str) -> tuple[str, ...]:
        """A colour compound written solid split into its hues ("bluegreen" -> ("blue", "green")), as the
        tokeniser splits a hyphenated one; any other word is itself. Both parts must be hues, so words
        that merely start with one ("tangerine", "redo") are left whole."""
        if not self.is_colour(word):
            for cut in self._hue_lengths:
                if cut > len(word) - 3:
                    break
                if word[:cut] in self.hues and word[cut:] in self.hues:
                    return word[:cut], word[cut:]
        return (word,)

    def read_as(self, token: str) -> tuple[str, ...]:
        """The words a token is read as: a ``SYNONYM`` form's word (``east`` -> ``right``; a multiword word as
        its words, which :meth:`join_multiword` joins), once (a word read as another is not read again);
        any other token itself."""
        return self.synonyms.get(token, (token,))

    def join_multiword(self, tokens: list[str]) -> list[str]:
        """Tokens with each multiword entry ("in front of") joined into one (``in_front_of``), longest
        first, except where its first word heads a noun phrase after a determiner, preposition,
        adjective or number ("to left of star", "bottom left of orange room" keep "left" apart)."""
        if not self._multiword:
            return tokens
        out: list[str] = []
        i = 0
        while i < len(tokens):
            end = i + 1
            # The exception depends on the first word alone, so it holds for every entry that starts here.
            if not (out and self.listed(tokens[i]) & {"ADJ", "NOUN"} and self.listed(out[-1]) & _NOUN_PHRASE_OPENERS):
                node = self._multiword
                for j in range(i, len(tokens)):
                    node = node.get(tokens[j])
                    if node is None:
                        break
                    if _END in node:
                        end = j + 1
            out.append("_".join(tokens[i:end]))
            i = end
        return out


@dataclass(frozen=True)
class SemanticLexicon:
    """Words mapped to domain propositional functions with probabilities (the semantic model).

    ``meanings[word][pf]`` is P(pf | word). Probabilities of a word need not sum to one: the remainder
    is the probability that the word keeps its uninstantiated reading (``P1(room1, green)``).
    Raises ValueError for negative probabilities or a word whose probabilities sum above one.
    """

    meanings: Mapping[str, Mapping[str, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        normalised: dict[str, dict[str, float]] = {}
        for word, pfs in self.meanings.items():
            total = 0.0
            for pf, prob in pfs.items():
                if not (prob >= 0.0) or math.isinf(prob):
                    raise ValueError(f"semantic lexicon: word {word!r}, PF {pf!r}: probability {prob} is not >= 0")
                total += prob
            if total > 1.0 + 1e-6:
                raise ValueError(f"semantic lexicon: word {word!r}: probabilities sum to {total:.4f} > 1")
            normalised[word.lower()] = {pf: float(p) for pf, p in pfs.items() if p > 0.0}
        object.__setattr__(self, "meanings", normalised)

    def choices(self, word: str) -> list[tuple[str | None, float]]:
        """(pf, probability) alternatives for a word; ``None`` is the uninstantiated reading.

        Unknown words give ``[(None, 1.0)]``.
        """
        pfs = self.meanings.get(word.lower())
        if not pfs:
            return [(None, 1.0)]
        out: list[tuple[str | None, float]] = sorted(pfs.items(), key=lambda kv: -kv[1])
        rest = 1.0 - sum(pfs.values())
        if rest > 1e-9:
            out.append((None, rest))
        return out
