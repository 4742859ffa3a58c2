"""The words a domain's commands are parsed with: closed-class English, the domain's word file, a user's.

The grammar knows English only (``grammar/english.words``); the nouns and colour words of the
Cleanup World sit in ``logic/cleanup.words``, beside its ``.lp`` files. A user adds word files
(``Learner(lexicon=...)``, ``--lexicon FILE``) or words as data (``{"NOUN": ["mug"]}``), e.g. the
class names and palette values of a domain schema.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Mapping
from importlib.resources import files
from pathlib import Path

from groundlang.grammar.lexicon import Lexicon, LexiconError, read_word_file
from groundlang.grammar.word_files import SynonymForms

__all__ = ["DOMAIN_WORD_FILE", "WordSource", "domain_lexicon", "extra_words"]

# The Cleanup World's word file, a resource of the logic package beside domain.lp.
DOMAIN_WORD_FILE = "cleanup.words"

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
    for source in sources:
        if isinstance(source, (str, Path)):
            words = read_word_file(source)
        elif isinstance(source, Mapping):
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
        if words.get("VERB_SERIAL") or words.get("ADV_DEGREE"):  # read against English: "to" is no serial verb
            try:
                Lexicon.english().extend({c: words[c] for c in ("VERB_SERIAL", "ADV_DEGREE") if c in words})
            except LexiconError as exc:
                raise LexiconError(f"{where}: {exc}") from None
        for category, entries in words.items():
            merged.setdefault(category, {}).update(dict.fromkeys(entries))  # in order, once each
    return {category: list(entries) for category, entries in merged.items()}


def domain_lexicon(extra: Mapping[str, Iterable[str]] | None = None) -> Lexicon:
    """English and the Cleanup World's words, extended with ``extra`` (words by category, see
    :func:`extra_words`); the lexicon without extras is built once."""
    lexicon = _cleanup_lexicon()
    return lexicon.extend(extra) if extra else lexicon
