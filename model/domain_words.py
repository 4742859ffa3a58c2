"""The words a domain's commands are parsed with: closed-class English, the domain's word file, a user's.

The grammar knows English only (``grammar/english.words``); the nouns and colour words of the
Cleanup World sit in ``logic/cleanup.words``, beside its ``.lp`` files. A user adds word files
(``Learner(lexicon=...)``, ``--lexicon FILE``) or words as data (``{"NOUN": ["mug"]}``), e.g. the
class names and palette values of a domain schema.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Iterable, Mapping, Sized
from importlib.resources import files
from pathlib import Path

from groundlang.grammar.lexicon import CLOSED_CLASS, Lexicon, LexiconError, read_word_file
from groundlang.grammar.word_files import TAGGING, SynonymForms, entry

__all__ = ["DOMAIN_WORD_FILE", "MAX_WORDS", "WordSource", "domain_lexicon", "extra_words"]

# The Cleanup World's word file, a resource of the logic package beside domain.lp.
DOMAIN_WORD_FILE = "cleanup.words"

# Words of every word file a lexicon reads, together, a verb lemma counted as the VERB_FORMS forms it is kept
# in: a file's size is bounded, but not how many files there are (three files of 400,000 verbs took 3.5 GB;
# 500,000 nouns take about half a GB). English and a domain's words are a few hundred.
MAX_WORDS = 500_000
VERB_FORMS = 4
_LEMMAS = ("VERB", "VERB_SERIAL", "VERB_HAVING")

# A word file's path, or words by category given as data.
WordSource = str | Path | Mapping[str, Iterable[str]]


@functools.cache
def _cleanup_lexicon() -> Lexicon:
    return Lexicon.english().with_files(Path(str(files("groundlang.logic").joinpath(DOMAIN_WORD_FILE))))


def extra_words(sources: WordSource | Iterable[WordSource] | None) -> dict[str, list[str]]:
    """Words by category from word files and word mappings, merged in order (what a model saves to
    parse the same way without the files). Raises LexiconError for a malformed file (naming file and
    line) or mapping, OSError for a file that cannot be read."""
    if sources is None:
        return {}
    if isinstance(sources, (str, Path, Mapping)):
        sources = [sources]
    merged: dict[str, dict[str, None]] = {}
    said = SynonymForms()  # merged below, a form's second word would name no source
    for read, source in enumerate(sources, 1):
        if isinstance(source, (str, Path)):
            words = read_word_file(source)
        elif isinstance(source, Mapping):
            # weighed before any lexicon is built of them: a saved model's words are read this way
            sized = {c: w for c, w in source.items() if isinstance(w, Sized) and not isinstance(w, str)}
            if (weight := _weight(sized)) > MAX_WORDS:
                raise LexiconError(f"words given as data: {weight:,} words, a verb counted as its {VERB_FORMS} "
                                   f"forms; at most {MAX_WORDS:,}")
            try:
                words = Lexicon().extend(source).entries  # checked and normalised as a file's would be
            except LexiconError as exc:  # a form given two words within the mapping: named as such
                raise LexiconError(f"words given as data: {exc}") from None
        else:
            raise LexiconError(f"a lexicon is a word file's path or a mapping of categories to words, "
                               f"not {type(source).__name__}")
        where = str(source) if isinstance(source, (str, Path)) else "words given as data (a trained model's own)"
        for pair in words.get("SYNONYM", ()):
            said.add(pair, where, f"in {where}")
        _check_word_roles(words, source, merged)
        for category, entries in words.items():
            merged.setdefault(category, {}).update(dict.fromkeys(entries))  # in order, once each
        if (total := _weight(merged)) > MAX_WORDS:
            files_said = "word files of" if read > 1 else "a word file of"
            raise LexiconError(f"{where}: {files_said} {total:,} words{' together' * (read > 1)}, a verb counted as "
                               f"its {VERB_FORMS} forms; at most {MAX_WORDS:,}")
    return {category: list(entries) for category, entries in merged.items()}


def _weight(words: Mapping[str, Mapping]) -> int:
    """What ``words`` will take in a lexicon: an entry each, a verb lemma its forms."""
    return sum(len(entries) * (VERB_FORMS if category in _LEMMAS else 1) for category, entries in words.items())


# Paired categories whose form has one value (``third=3``, ``went=go``): how two values read, and the rule.
_ONE_EACH = {"ORDINAL": ("is the number {here} here and {there}", "a word names one number"),
             "IRREGULAR": ("is a form of {here!r} here and of {there!r}", "a form is of one verb")}


def _check_word_roles(words: Mapping[str, Iterable[str]], source: WordSource, merged: Mapping) -> None:
    """A word file's word in a role English or an earlier file gives another: a closed-class word that is a serial
    verb or a degree word there ("NEG: go"), or the other way round, or a second preposition a clause of having
    reads as ("PREP_HAVING: near"). Refused here, naming the file and line, as the merged lexicon would refuse
    it without either (and blaming the category of grammar/english.words)."""
    open_roles = {"VERB_SERIAL": "a serial verb", "ADV_DEGREE": "a degree word"}
    english = Lexicon.english().entries
    for category, (says, rule) in _ONE_EACH.items():  # a word names one number, a form is of one verb
        given = dict(pair.split("=", 1) for pair in [*english.get(category, ()), *merged.get(category, {})])
        for pair in words.get(category, ()):
            form, value = pair.split("=", 1)
            if given.setdefault(form, value) != value:
                raise LexiconError(f"{_line_of(source, category, pair)}: {category} {form!r} "
                                   f"{says.format(here=value, there=given[form])} in English or an earlier word file "
                                   f"(or this one): {rule}")
    for word in words.get("PREP_HAVING", ()):  # one preposition a clause of having reads as
        if other := sorted({*english.get("PREP_HAVING", ()), *merged.get("PREP_HAVING", {})} - {word}):
            raise LexiconError(f"{_line_of(source, 'PREP_HAVING', word)}: PREP_HAVING word {word!r}: a clause of having "
                               f"reads as one preposition, and English or an earlier word file says {other[0]!r}")
    for role, said in open_roles.items():  # the other way round: a closed-class word of English or an earlier file
        for word in words.get(role, ()):
            closed = sorted(Lexicon.english().listed(word) & CLOSED_CLASS) or [
                c for c, e in merged.items() if TAGGING.get(c, c) in CLOSED_CLASS and word in e]
            if closed:
                raise LexiconError(f"{_line_of(source, role, word)}: {role} word {word!r} is {', '.join(closed)} in "
                                   f"English or an earlier word file, a closed class: {said} is an open word")
    for category, entries in words.items():
        if TAGGING.get(category, category) not in CLOSED_CLASS:
            continue
        for word in entries:
            for role, said in open_roles.items():
                if word in english.get(role, ()) or word in merged.get(role, {}):
                    where = _line_of(source, category, word)
                    raise LexiconError(f"{where}: {category} word {word!r} is {said} ({role}) of English or an "
                                       f"earlier word file, an open word: a closed class cannot take it")


def _line_of(source: WordSource, category: str, word: str) -> str:
    """``path:N`` of the first ``category`` line listing ``word``, lines numbered and words read as
    :func:`~groundlang.grammar.word_files.read_word_file` numbers and reads them (the file as a whole where
    none does)."""
    if not isinstance(source, (str, Path)):
        return "words given as data"
    with open(source, encoding="utf-8-sig", errors="replace", newline="") as handle:
        for number, line in enumerate(re.split(r"\r\n|\r|\n", handle.read()), 1):
            head, colon, rest = line.split("#", 1)[0].partition(":")
            if colon and head.strip() == category and word in (entry(w) for w in rest.split()):
                return f"{source}:{number}"
    return str(source)


def domain_lexicon(extra: Mapping[str, Iterable[str]] | None = None) -> Lexicon:
    """English and the Cleanup World's words, extended with ``extra`` (words by category, see
    :func:`extra_words`); the lexicon without extras is built once."""
    lexicon = _cleanup_lexicon()
    return lexicon.extend(extra) if extra else lexicon
