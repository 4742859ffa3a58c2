"""The words the parser knows and their lexical categories, read from word files; the semantic model.

The parser knows no meanings, only syntax. Which category a word may play (determiner, preposition,
verb, noun, ...) is data: closed-class English ships in ``grammar/english.words``, a domain's nouns and
adjectives sit in a word file beside its ``.lp`` files, and a caller may add words of its own
(:meth:`Lexicon.extend`, :meth:`Lexicon.with_files`). A word no file lists is still parsed: its
categories are guessed from its suffix and position. A word may carry several categories ("left" is
an adverb, an adjective and a noun); the grammar decides which one a reading uses.

Word file format (documented at the top of ``english.words``): ``CATEGORY: word word ...`` lines,
``#`` comments, blank lines skipped, ``_`` joining the words of a multiword entry (``in_front_of``),
``form=lemma`` pairs under ``IRREGULAR``, ``form=word`` pairs under ``SYNONYM``.

``SemanticLexicon`` is the paper's semantic model (LWFG's Phi_i constraints): words mapped to domain
propositional functions with probabilities, learned later by the joint model and handed to ``parse``.
"""

from __future__ import annotations

import functools
import math
import os
import re
import stat
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from importlib.resources import files
from pathlib import Path

__all__ = ["CATEGORIES", "FILE_CATEGORIES", "Lexicon", "LexiconError", "SemanticLexicon", "read_word_file"]

# Lexical categories (the grammar's terminals are sets of these).
CATEGORIES = (
    "ADJ", "ADV", "AUX", "COLOR", "COMMA", "CONJ", "DET", "GER", "MEASURE",
    "NEG", "NOUN", "NUM", "PREP", "PRON", "REL", "SUB", "TO", "VERB",
)
# Categories of a word file that tag their words with a lexical category and give them a role the
# parser or the model reads (see english.words); VERB lists lemmas, IRREGULAR form=lemma pairs.
_TAGGING = {"HUE": "COLOR", "PARTICLE": "ADV", "PREP_NEGATING": "PREP", "PREP_SOURCE": "PREP", "PREP_HAVING": "PREP"}
# VERB_HAVING marks verb lemmas (listed under VERB) whose relative clause about a noun phrase reads as
# "with" ("the room that has the chair"); it tags nothing itself.
FILE_CATEGORIES = tuple(c for c in CATEGORIES if c not in ("GER", "VERB")) + (
    "VERB", "IRREGULAR", "SYNONYM", *_TAGGING, "VERB_HAVING",
)
# Categories whose entries pair two words, ``form=word``, and what the pair means (for error messages).
_PAIRED = {"IRREGULAR": "form=lemma (e.g. went=go)", "SYNONYM": "form=word (e.g. east=right)"}
# A multiword entry's first word that may head or modify a noun phrase ("left" of "left of") does,
# rather than open the preposition, after a word of these categories: "the left of the room",
# "to left of star", "bottom left of orange room".
_NOUN_PHRASE_OPENERS = frozenset({"DET", "PREP", "TO", "ADJ", "NUM"})
# Marks, in the trie of multiword entries, a node where an entry ends: not a string, so no word collides.
_END = None
_CATEGORY_LINE = re.compile(r"^([A-Za-z_]+)\s*:(.*)$")
_HYPHEN = re.compile(r"(?<=\w)-(?=\w)")
# A synonym's word replaces one word of a command: a multiword entry's few words, not a text.
MAX_SYNONYM_PARTS = 8
_LETTER = re.compile(r"[^\W_]")
# A word a synonym's form may be: what the tokeniser leaves whole (no clitic split off, no sign alone).
_SYNONYM_FORM = re.compile(r"[^\W_]+(?:n't)?")


class LexiconError(ValueError):
    """A word file or word list that does not follow the format; the message names file and line."""


# one token as grammar.parser's tokeniser reads it: a word (a clitic such as 're too), or one sign ("&")
_WORD = re.compile(r"'?[^\W_]+(?:'[^\W_]+)*|[^\w\s]")


def _entry(word: str) -> str:
    """A word as the tokeniser produces it: lowercase, and the words of a multiword entry (written
    with ``_``, spaces or hyphens, which the tokeniser splits at) joined with ``_``."""
    return "_".join(_HYPHEN.sub(" ", word.strip().lower()).replace("_", " ").split())


def _check(category: str, words: Iterable[str], where: str) -> tuple[str, ...]:
    if category not in FILE_CATEGORIES:
        raise LexiconError(f"{where}: unknown category {category!r}; a word file knows "
                           f"{', '.join(FILE_CATEGORIES)}")
    if isinstance(words, str):
        raise LexiconError(f"{where}: the words of {category} must be a list of words, not one string")
    out = []
    for word in words:
        if not isinstance(word, str) or not _entry(word):
            raise LexiconError(f"{where}: {category} has an empty or non-text word {word!r}")
        if category in _PAIRED:
            form, sep, lemma = word.partition("=")
            if not sep or not _entry(form) or not _entry(lemma) or "=" in lemma:
                raise LexiconError(f"{where}: {category} entry {word!r} is not {_PAIRED[category]}")
            if category == "SYNONYM" and not (_WORD.fullmatch(_entry(form)) and _SYNONYM_FORM.fullmatch(_entry(form))):
                # Read where the tokeniser has split clitics ("it's": it 's) and signs off, a form is one word of
                # letters and digits, or one ending in n't, which stays whole.
                raise LexiconError(f"{where}: SYNONYM entry {word!r}: the form {form!r} must be one word "
                                   "(letters and digits, or a negation such as don't)")
            parts = _entry(lemma).split("_")
            if category == "SYNONYM" and (len(parts) > MAX_SYNONYM_PARTS or not any(_LETTER.search(p) for p in parts)):
                # a word read in place of one: a few words, one of them a word (not only signs, which
                # would leave a command nothing to read)
                raise LexiconError(f"{where}: SYNONYM entry {word!r}: the word must be at most "
                                   f"{MAX_SYNONYM_PARTS} words, with a letter or digit")
            if category == "SYNONYM" and not all(_WORD.fullmatch(part) for part in parts):
                raise LexiconError(f"{where}: SYNONYM entry {word!r}: {lemma!r} is not letters, digits or apostrophes "
                                   "(the tokeniser splits at other characters)")
            out.append(f"{_entry(form)}={_entry(lemma)}")
        elif "=" in word:
            raise LexiconError(f"{where}: {category} entry {word!r} has '=' (only IRREGULAR and SYNONYM pair words)")
        elif not all(_WORD.fullmatch(part) for part in _entry(word).split("_")):
            # the tokeniser splits at any other character, so such an entry would never be read
            raise LexiconError(f"{where}: {category} word {word!r} is not a word the tokeniser reads (letters, "
                               "digits and apostrophes, or one sign such as &; '_', '-' or a space join the words of "
                               "a multiword entry)")
        else:
            out.append(_entry(word))
    return tuple(out)


# A word file lists a domain's words: a few KB. A wrong path (a log, /dev/zero) must not be read whole.
MAX_WORD_FILE_BYTES = 4 * 2**20


def read_word_file(path: str | Path) -> dict[str, tuple[str, ...]]:
    """Words by category from a word file (format: see the module docstring).

    Raises LexiconError naming the file and line of the first malformed line, OSError if unreadable.
    """
    path = Path(path)
    # logic.storage.read_limited's twin (grammar imports no other layer): opened non-blocking, so that a
    # FIFO cannot hang the open; its kind is read from the open file; no more than the limit is read.
    with open(path, "rb", opener=lambda p, flags: os.open(p, flags | getattr(os, "O_NONBLOCK", 0))) as handle:
        if not stat.S_ISREG(os.fstat(handle.fileno()).st_mode):
            raise LexiconError(f"{path}: not a regular file (a FIFO or device); expected a word file")
        data = handle.read(MAX_WORD_FILE_BYTES + 1)
    if len(data) > MAX_WORD_FILE_BYTES:
        raise LexiconError(f"{path}: a word file of more than {MAX_WORD_FILE_BYTES:,} bytes, the most allowed")
    try:
        text = data.decode("utf-8").removeprefix("\ufeff")  # a byte order mark some editors write first
    except UnicodeDecodeError as exc:
        raise LexiconError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start}); a word file is "
                           "text with `CATEGORY: word word ...` lines") from None
    entries: dict[str, list[str]] = {}
    read_as: dict[str, tuple[str, int]] = {}  # a synonym's form -> its word and the line giving it
    # Split where an editor ends a line (LF, CRLF, CR), not at the other separators str.splitlines knows
    # (U+2028, form feed, NEL): a comment may hold one, and every line number after it would shift.
    for number, line in enumerate(re.split(r"\r\n|\r|\n", text), 1):
        content = line.split("#", 1)[0].strip()
        if not content:
            continue
        where = f"{path}:{number}"
        match = _CATEGORY_LINE.match(content)
        if match is None:
            raise LexiconError(f"{where}: expected `CATEGORY: word word ...`, got {content[:60]!r}")
        category, words = match.group(1), match.group(2).split()
        if not words:
            raise LexiconError(f"{where}: no words after {category}:")
        checked = _check(category, words, where)
        for form, word in (pair.split("=", 1) for pair in checked if category == "SYNONYM"):
            first = read_as.setdefault(form, (word, number))
            if first[0] != word:
                raise LexiconError(f"{where}: SYNONYM {form!r} is read as {word} here and as {first[0]} on line "
                                   f"{first[1]}")
        entries.setdefault(category, []).extend(checked)
    return {category: tuple(words) for category, words in entries.items()}


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

    def __init__(self, entries: Mapping[str, Iterable[str]] | None = None):
        merged: dict[str, set[str]] = {}
        for category, words in (entries or {}).items():
            merged.setdefault(category, set()).update(_check(category, words, "word list"))
        self.entries: dict[str, tuple[str, ...]] = {
            c: tuple(sorted(merged[c])) for c in FILE_CATEGORIES if merged.get(c)}
        words = {c: frozenset(self.entries.get(c, ())) for c in FILE_CATEGORIES}
        # Verb forms: regular inflections of every lemma, in a fixed order, then the irregular ones.
        self.verb_forms: dict[str, str] = {}
        for lemma in sorted(words["VERB"]):
            self.verb_forms.update(_inflections(lemma))
        self.verb_forms.update(pair.split("=", 1) for pair in self.entries.get("IRREGULAR", ()))
        table: dict[str, set[str]] = {}
        for category in FILE_CATEGORIES:
            tag = _TAGGING.get(category, category)
            if tag in CATEGORIES and category != "VERB":
                for word in words[category]:
                    table.setdefault(word, set()).add(tag)
        for form in self.verb_forms:
            cats = table.setdefault(form, set())
            cats.add("GER" if form.endswith("ing") else "VERB")
            if form.endswith("ed"):
                cats.add("ADJ")  # past participles modify nouns: "orange-floored room", "colored room"
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
            parts = tuple(word.split("_"))
            if self.synonyms.setdefault(form, parts) != parts:
                raise LexiconError(f"SYNONYM {form!r} is given two words: {'_'.join(self.synonyms[form])} and "
                                   f"{word}")
        self.negating_prepositions = words["PREP_NEGATING"]
        self.source_and_comitative_prepositions = words["PREP_SOURCE"]
        self.having_verbs = words["VERB_HAVING"]
        # The preposition a clause of having reads as ("with"); None when no word file names one.
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
            merged.setdefault(category, []).extend(_check(category, words, "word list"))
        return Lexicon(merged)

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
