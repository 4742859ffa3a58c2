"""Word files: the format a domain's words are written in, read and checked (see ``english.words``).

``CATEGORY: word word ...`` lines, ``#`` comments, blank lines skipped, ``_`` joining the words of a
multiword entry (``in_front_of``), ``form=lemma`` pairs under ``IRREGULAR``, ``form=word`` pairs under
``SYNONYM``. :func:`read_word_file` reads one file, naming file and line of the first malformed line;
:func:`check_words` checks and normalises one category's words however they came (a file, a mapping);
``grammar.lexicon.Lexicon`` builds the parser's lexicon from them.
"""

from __future__ import annotations

import os
import re
import unicodedata
import stat
from collections.abc import Iterable, Mapping
from pathlib import Path

__all__ = [
    "CATEGORIES", "FILE_CATEGORIES", "LexiconError", "MAX_SYNONYM_PARTS", "MAX_WORD_FILE_BYTES", "SynonymForms",
    "TAGGING", "check_words", "entry", "read_word_file",
]

# Lexical categories (the grammar's terminals are sets of these).
CATEGORIES = (
    "ADJ", "ADV", "AUX", "COLOR", "COMMA", "CONJ", "DET", "GER", "MEASURE",
    "NEG", "NOUN", "NUM", "PREP", "PRON", "REL", "SUB", "TO", "VERB", "SERIAL", "DEGREE",
)
# Categories of a word file that tag their words with a lexical category and give them a role the
# parser or the model reads (see english.words); VERB lists lemmas, IRREGULAR form=lemma pairs.
TAGGING = {"HUE": "COLOR", "PARTICLE": "ADV", "PREP_NEGATING": "PREP", "PREP_SOURCE": "PREP", "PREP_HAVING": "PREP",
           "POLITE": "ADV", "VERB_SERIAL": "SERIAL", "ADV_DEGREE": "DEGREE", "DET_DEFINITE": "DET"}
# VERB_HAVING marks verb lemmas (listed under VERB) whose relative clause about a noun phrase reads as
# "with" ("the room that has the chair"); it tags nothing itself.
# YES and NO list the words that answer a question of one choice ("Do you mean the red room?") by taking it
# or declining it; they tag nothing either (commands are not answers).
# VERB_SERIAL tags SERIAL: motion verbs that, before a bare verb, head nothing ("go stand next to the chair");
# ADV_DEGREE tags DEGREE: adverbs that, before a modifier, grade it ("the very small room").
# ORDINAL pairs the words an answer names a choice's number by with the number ("third=3"), CHOICE_NOUN lists
# the nouns such an answer may say it with ("option two", "number 2"); they tag nothing either. DET_DEFINITE
# tags DET: the determiners such an answer may have ("the third one"; "all three", "no two" name no number).
FILE_CATEGORIES = tuple(c for c in CATEGORIES if c not in ("GER", "VERB", "SERIAL", "DEGREE")) + (
    "VERB", "IRREGULAR", "SYNONYM", *TAGGING, "VERB_HAVING", "YES", "NO", "ORDINAL", "CHOICE_NOUN",
)
# Categories whose entries pair two words, ``form=word``, and what the pair means (for error messages).
_PAIRED = {"IRREGULAR": "form=lemma (e.g. went=go)", "SYNONYM": "form=word (e.g. east=right)",
           "ORDINAL": "word=number (e.g. third=3)"}
# A choice's number: the questions offer a few choices.
_ORDINAL_NUMBER = re.compile(r"[1-9][0-9]?")
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


def entry(word: str) -> str:
    """A word as the tokeniser produces it: lowercase, and the words of a multiword entry (written
    with ``_``, spaces or hyphens, which the tokeniser splits at) joined with ``_``."""
    return "_".join(_HYPHEN.sub(" ", unicodedata.normalize("NFKC", word).strip().lower()).replace("_", " ").split())


def check_words(category: str, words: Iterable[str], where: str) -> tuple[str, ...]:
    if category not in FILE_CATEGORIES:
        raise LexiconError(f"{where}: unknown category {category!r}; a word file knows "
                           f"{', '.join(FILE_CATEGORIES)}")
    if isinstance(words, str):
        raise LexiconError(f"{where}: the words of {category} must be a list of words, not one string")
    if isinstance(words, (bytes, bytearray, Mapping)) or not isinstance(words, Iterable):
        raise LexiconError(f"{where}: the words of {category} must be a list of words, not {type(words).__name__}")
    out = []
    for word in words:
        said = entry(word) if isinstance(word, str) else ""
        if not said:
            raise LexiconError(f"{where}: {category} has an empty or non-text word {word!r}")
        if any(0xD800 <= ord(ch) <= 0xDFFF for ch in word):  # no text: a byte that was not UTF-8, or half a pair
            raise LexiconError(f"{where}: {category} word {word!r} is not text (a lone surrogate)")
        if hidden := next((ch for ch in word if unicodedata.category(ch) in ("Cc", "Cf") and not ch.isspace()), None):
            # the tokeniser reads a command without them (a space, or nothing), so such an entry is never read
            raise LexiconError(f"{where}: {category} word {word!r} has an invisible or control character "
                               f"(U+{ord(hidden):04X}), which commands are read without")
        if category in _PAIRED:
            form, sep, lemma = word.partition("=")
            if not sep or not entry(form) or not entry(lemma) or "=" in lemma:
                raise LexiconError(f"{where}: {category} entry {word!r} is not {_PAIRED[category]}")
            if category == "SYNONYM" and not (_WORD.fullmatch(entry(form)) and _SYNONYM_FORM.fullmatch(entry(form))):
                # Read where the tokeniser has split clitics ("it's": it 's) and signs off, a form is one word of
                # letters and digits, or one ending in n't, which stays whole.
                raise LexiconError(f"{where}: SYNONYM entry {word!r}: the form {form!r} must be one word "
                                   "(letters and digits, or a negation such as don't)")
            if category == "ORDINAL" and not (_WORD.fullmatch(entry(form)) and _ORDINAL_NUMBER.fullmatch(entry(lemma))):
                raise LexiconError(f"{where}: ORDINAL entry {word!r}: expected one word and a number from 1 to 99 "
                                   "(e.g. third=3)")
            parts = entry(lemma).split("_")
            if category == "SYNONYM" and (len(parts) > MAX_SYNONYM_PARTS or not any(_LETTER.search(p) for p in parts)):
                # a word read in place of one: a few words, one of them a word (not only signs, which
                # would leave a command nothing to read)
                raise LexiconError(f"{where}: SYNONYM entry {word!r}: the word must be at most "
                                   f"{MAX_SYNONYM_PARTS} words, with a letter or digit")
            if category == "SYNONYM" and not all(_WORD.fullmatch(part) for part in parts):
                raise LexiconError(f"{where}: SYNONYM entry {word!r}: {lemma!r} is not letters, digits or apostrophes "
                                   "(the tokeniser splits at other characters)")
            out.append(f"{entry(form)}={entry(lemma)}")
        elif category in ("YES", "NO", "CHOICE_NOUN") and "_" in said:  # answers are read a word at a time
            raise LexiconError(f"{where}: {category} word {word!r} is more than one word (an answer's words are read "
                               "one at a time)")
        elif category in ("VERB_SERIAL", "ADV_DEGREE") and "_" in said:  # the grammar reads one word there
            raise LexiconError(f"{where}: {category} word {word!r} is more than one word (a serial verb or a degree "
                               "word is one)")
        elif "=" in word:
            raise LexiconError(f"{where}: {category} entry {word!r} has '=' (only IRREGULAR, SYNONYM and ORDINAL pair "
                               "words)")
        elif not all(_WORD.fullmatch(part) for part in said.split("_")):
            # the tokeniser splits at any other character, so such an entry would never be read
            raise LexiconError(f"{where}: {category} word {word!r} is not a word the tokeniser reads (letters, "
                               "digits and apostrophes, or one sign such as &; '_', '-' or a space join the words of "
                               "a multiword entry)")
        else:
            out.append(said)
    return tuple(out)


class SynonymForms:
    """The word each ``SYNONYM`` form is read as, and where that was said: a form given a second word is
    refused, naming both places (one check for a file's lines, a model's word files and words given as
    data, each naming what it can)."""

    def __init__(self) -> None:
        self._said: dict[str, tuple[str, str]] = {}

    def add(self, pair: str, where: str | None, cited: str) -> None:
        """Record ``form=word``, said at ``where`` (the error's prefix; None for none), cited later as
        ``cited`` ("on line 3", "in words.txt"). Raises LexiconError if the form was given another word."""
        form, word = pair.split("=", 1)
        first, first_cited = self._said.setdefault(form, (word, cited))
        if first != word:
            prefix = f"{where}: " if where else ""
            raise LexiconError(f"{prefix}SYNONYM {form!r} is read as {word} here and as {first} {first_cited}")


# A word file lists a domain's words: a few KB. A wrong path (a log, /dev/zero) must not be read whole.
MAX_WORD_FILE_BYTES = 4 * 2**20


def read_word_file(path: str | Path) -> dict[str, tuple[str, ...]]:
    """Words by category from a word file (format: see the module docstring).

    Raises LexiconError naming the file and line of the first malformed line, OSError if unreadable.
    """
    if not str(path) or "\0" in str(path):  # "" would open the working folder, a NUL no file at all
        raise LexiconError(f"word file {str(path)!r}: not a file name")
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
    synonyms = SynonymForms()
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
        checked = check_words(category, words, where)
        for pair in checked if category == "SYNONYM" else ():
            synonyms.add(pair, where, f"on line {number}")
        entries.setdefault(category, []).extend(checked)
    return {category: tuple(words) for category, words in entries.items()}
