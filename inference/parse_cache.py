"""A disk cache of the parser's readings of training commands.

Parsing a corpus's distinct texts (Earley over the grammar, k-best readings from the forest) is most of
what training does before EM on a warm cache of behaviour terms: 748 texts of the Williams corpus take
about 5 s. The readings are kept in the cache folder of the behaviour likelihoods
(``inference.likelihoods``: ``cache_dir``, else ``$GROUNDLANG_CACHE``, else ``.groundlang-cache``), one
JSON file per text in ``parses/ab/abcdef....json``, with the evidence cache's guarantees
(``inference.evidence_cache``):

- the name is the sha256 of everything the readings depend on: the text, the number of readings kept,
  the rule weights, the words of the lexicon by category, the text of every file of the grammar package
  (its code, grammar and word lists: any change to the parser gives new names) and
  :data:`PARSE_CACHE_VERSION`;
- an entry records its key and a checksum over the key and the canonical text of its readings, and every
  field is read back with its type checked, so a changed character, a truncated file or an entry copied
  under another name is detected, reparsed and rewritten, with one warning per run giving how many;
- entries are written atomically, not fsynced (a lost entry is reparsed), read with a size limit; a folder
  that cannot be written gives one warning, and training goes on without writing.
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import os
import unicodedata
from collections.abc import Mapping
from functools import cache
from importlib.resources import files
from pathlib import Path

import lark

from groundlang.grammar.chunker import UNSAID_PREPOSITION
from groundlang.grammar.lexicon import Lexicon
from groundlang.grammar.logical_form import Clause, Entity, LogicalForm, Reading, Relation
from groundlang.grammar.parser import parse, tokenise
from groundlang.inference.cache_entries import EntryFolder
from groundlang.inference.likelihoods import PARSES_FOLDER

__all__ = ["PARSE_CACHE_VERSION", "ParseCache", "parse_key", "parser_digest"]

logger = logging.getLogger(__name__)

PARSE_CACHE_VERSION = 1  # bump when what an entry holds changes meaning
MAX_ENTRY_BYTES = 1024 * 1024  # at most 8 readings of one command; far more is not an entry
MAX_READINGS = 8  # the parser's default, which training uses

# Each dataclass's fields as the cache writes them: (name, type); a list type is a tuple of that type,
# None in a type allows None.
_STR, _OPT = (str,), (str, type(None))
_FIELDS = {
    Entity: (("var", _STR), ("head", _OPT), ("modifiers", [_STR]), ("determiner", _OPT), ("clause", (int,)),
             ("role", _STR), ("prep", _OPT), ("parent", _OPT), ("pronoun", _OPT)),
    Relation: (("name", _STR), ("args", [_STR]), ("word", _OPT), ("kind", _STR), ("negated", (bool,)),
               ("probability", (float,))),
    Clause: (("verb", _OPT), ("args", [_STR]), ("preps", [[_STR]]), ("negated", (bool,)), ("subject", _OPT),
             ("connective", _OPT), ("adverbs", [_STR])),
    LogicalForm: (("clauses", [Clause]), ("entities", [Entity]), ("relations", [Relation]),
                  ("attachments", [[_STR]]), ("words", [_STR]), ("tags", [_STR]), ("fallback", (bool,))),
    Reading: (("logical_form", LogicalForm), ("probability", (float,))),
}


@cache
def parser_digest() -> str:
    """sha256 of the names and texts of every file of the grammar package, read once per process."""
    root = files("groundlang.grammar")
    digest = hashlib.sha256()
    for entry in sorted(Path(str(root)).rglob("*")):
        if entry.is_file() and "__pycache__" not in entry.parts:
            digest.update(entry.relative_to(Path(str(root))).as_posix().encode() + b"\0" + entry.read_bytes() + b"\0")
    return digest.hexdigest()


def parse_key(command: str, weights: Mapping[str, float] | None, lexicon: Lexicon) -> str:
    """sha256 (hex) of what a command's readings depend on: besides the parser's own files, lark (whose
    Earley parser the grammar package patches and whose forests it reads) and the Unicode tables the
    tokeniser lowercases and splits words by."""
    description = {
        "version": PARSE_CACHE_VERSION,
        "command": command,
        "readings": MAX_READINGS,
        "weights": sorted((weights or {}).items()),
        "lexicon": sorted(lexicon.entries.items()),
        "parser": parser_digest(),
        "lark": lark.__version__,
        "unicode": unicodedata.unidata_version,
    }
    return hashlib.sha256(json.dumps(description, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def _plain(value):
    """A reading (or a part of one) as JSON values, field by field in :data:`_FIELDS` order."""
    if type(value) in _FIELDS:
        return [_plain(getattr(value, name)) for name, _ in _FIELDS[type(value)]]
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def _restore(value, kind):
    """The inverse of :func:`_plain` for ``kind`` (a dataclass, a list type or a tuple of types), checked:
    ValueError for anything of another shape or type."""
    if isinstance(kind, list):
        if not isinstance(value, list):
            raise ValueError(f"{value!r:.40} is not a list")
        return tuple(_restore(v, kind[0]) for v in value)
    if kind in _FIELDS:
        spec = _FIELDS[kind]
        if not isinstance(value, list) or len(value) != len(spec):
            raise ValueError(f"a {kind.__name__} needs {len(spec)} fields")
        return kind(**{name: _restore(v, t) for (name, t), v in zip(spec, value)})
    if float in kind and type(value) is int:  # JSON writes no ".0" for some numbers' reprs elsewhere
        return float(value)
    if type(value) not in kind:  # type, not isinstance: a bool is not an int here
        raise ValueError(f"{value!r:.40} is not a {' or '.join(t.__name__ for t in kind)}")
    return value


def _checksum(key: str, readings: list) -> str:
    text = json.dumps(readings, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(f"{key} {text}".encode()).hexdigest()


class ParseCache:
    """Readings of commands, read from the cache folder or parsed and written there. ``cache_dir``: the
    folder (see the module docstring), None for the default, False for no cache. Counts ``hits``,
    ``computed`` (parsed) and ``damaged`` entries; :meth:`report` logs them once."""

    def __init__(self, cache_dir: str | os.PathLike | None | bool = None):
        self.entries = EntryFolder(cache_dir, PARSES_FOLDER, "reparsed", logger)

    hits = property(lambda self: self.entries.hits)
    computed = property(lambda self: self.entries.computed)
    damaged = property(lambda self: self.entries.damaged)

    def readings(self, command: str, weights: Mapping[str, float] | None, lexicon: Lexicon) -> tuple[Reading, ...]:
        """``parse(command, weights=weights, word_lexicon=lexicon)``'s readings; the parser's errors as it
        raises them."""
        key = parse_key(command, weights, lexicon) if self.entries.root is not None else None
        if key is not None:
            found = self.entries.read(key, MAX_ENTRY_BYTES, "a parse cache entry",
                                      lambda data: _restore_entry(data, key, tokenise(command, lexicon)))
            if found is not None:
                return found
        readings = tuple(parse(command, max_readings=MAX_READINGS, weights=weights, word_lexicon=lexicon))
        self.entries.computed += 1
        if key is not None:
            plain = _plain(readings)
            self.entries.write(key, {"readings": plain, "checksum": _checksum(key, plain)})
        return readings

    def report(self) -> None:
        """One warning for damaged entries (how many, the first and why), one info line of counts."""
        self.entries.report("commands' readings", "from the parse cache")


def _restore_entry(data: dict, key: str, tokens: list[str]) -> tuple[Reading, ...]:
    """The readings of an entry, checked for what the parser guarantees and the encoding relies on: at
    most MAX_READINGS readings with probabilities in (0, 1] summing to one, relations' probabilities in
    [0, 1], and in every reading the command's own words (``tokens``), at most one noun phrase per word,
    each noun phrase's words and preposition among them, and every variable a clause, relation or
    attachment names a noun phrase's. An entry the checksum passes is still one the parser could have
    written, or it is reparsed: a forged or buggy one must not train a model on words it does not hold,
    nor size the batch's tables by thousands of noun phrases."""
    if data.get("checksum") != _checksum(key, data["readings"]):
        raise ValueError("checksum does not match the readings")
    readings = _restore(data["readings"], [Reading])
    if not 0 < len(readings) <= MAX_READINGS:
        raise ValueError(f"holds {len(readings)} readings, not 1 to {MAX_READINGS}")
    if (not all(0 < r.probability <= 1 for r in readings)
            or not math.isclose(sum(r.probability for r in readings), 1.0, abs_tol=1e-6)):
        raise ValueError("its readings' probabilities are not a distribution")
    tokens = tuple(tokens)
    for reading in readings:
        _check_form(reading.logical_form, tokens)
    return readings


def _check_form(form: LogicalForm, tokens: tuple[str, ...]) -> None:
    if form.words != tokens:
        raise ValueError("its words are not the command's")
    if len(form.entities) > len(tokens):
        raise ValueError(f"{len(form.entities)} noun phrases in {len(tokens)} words")
    if len(form.clauses) > len(tokens):  # a clause, even a verbless fragment, holds one word at least
        raise ValueError(f"{len(form.clauses)} clauses in {len(tokens)} words")
    names = {e.var for e in form.entities}
    words = set(tokens) | {UNSAID_PREPOSITION}
    if len(names) != len(form.entities):
        raise ValueError("two noun phrases share a variable")
    if not all(0 <= r.probability <= 1 for r in form.relations):
        raise ValueError("a relation's probability is not one")
    if not all((set(e.modifiers) | {e.head, e.prep}) - {None} <= words for e in form.entities):
        raise ValueError("a noun phrase has words the command does not")
    if any(len(p) != 2 for c in form.clauses for p in c.preps) or any(len(a) != 3 for a in form.attachments):
        raise ValueError("a preposition or attachment of the wrong shape")
    if not all(0 <= e.clause < len(form.clauses) for e in form.entities):
        raise ValueError("a noun phrase belongs to a clause the reading does not have")
    named = ([e.parent for e in form.entities] + [c.subject for c in form.clauses]
             + [v for c in form.clauses for v in (*c.args, *(p[1] for p in c.preps))]
             + [a for a in form.attachments for a in a[1:]] + [r.args[0] for r in form.relations if r.args])
    if not set(named) - {None} <= names:
        raise ValueError("a variable names no noun phrase")
