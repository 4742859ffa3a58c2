"""The parse cache: a warm read gives the readings the parser gave and parses nothing, keys follow what
the readings depend on, damaged entries are reparsed with one warning, and no cache writes nothing."""

from __future__ import annotations

import json
import logging

import pytest

from groundlang.grammar.lexicon import Lexicon
from groundlang.grammar.parser import ParseError, parse
from groundlang.inference import parse_cache
from groundlang.inference.parse_cache import ParseCache, parse_key

COMMANDS = [
    "take the red chair to the green room",
    "go to the room with the chair, then stand to the left of it",
    "walk to the largest room",
    "move the small box next to the door and do not enter the blue room",
]
WORDS = Lexicon.english().extend({"NOUN": ["chair", "box"], "COLOR": ["red", "green", "blue"]})


def _entries(root):
    return sorted((root / "parses").rglob("*.json"))


def test_a_warm_cache_gives_the_parsers_readings_and_parses_nothing(tmp_path, monkeypatch):
    cold = ParseCache(tmp_path)
    readings = [cold.readings(c, None, WORDS) for c in COMMANDS]
    assert cold.computed == len(COMMANDS) and len(_entries(tmp_path)) == len(COMMANDS)
    assert readings == [tuple(parse(c, word_lexicon=WORDS)) for c in COMMANDS]

    def refuse(*args, **kwargs):
        raise AssertionError("parsed, not read from the cache")

    monkeypatch.setattr(parse_cache, "parse", refuse)
    warm = ParseCache(tmp_path)
    assert [warm.readings(c, None, WORDS) for c in COMMANDS] == readings  # every field, floats exactly
    assert warm.hits == len(COMMANDS) and warm.computed == 0


def test_the_key_follows_what_the_readings_depend_on():
    key = parse_key(COMMANDS[0], None, WORDS)
    assert key == parse_key(COMMANDS[0], {}, Lexicon.english().extend({"NOUN": ["box", "chair"],
                                                                       "COLOR": ["blue", "green", "red"]}))
    changed = [
        parse_key(COMMANDS[1], None, WORDS),
        parse_key(COMMANDS[0], {"nmods_coord": 1.0}, WORDS),
        parse_key(COMMANDS[0], None, WORDS.extend({"NOUN": ["mug"]})),
        parse_key(COMMANDS[0], None, Lexicon.english()),
    ]
    assert len({key, *changed}) == 1 + len(changed)


def test_a_change_to_the_parser_gives_new_keys(monkeypatch):
    key = parse_key(COMMANDS[0], None, WORDS)
    monkeypatch.setattr(parse_cache, "parser_digest", lambda: "another grammar")
    assert parse_key(COMMANDS[0], None, WORDS) != key


def test_damaged_entries_are_reparsed_with_one_warning(tmp_path, caplog):
    cold = ParseCache(tmp_path)
    readings = {c: cold.readings(c, None, WORDS) for c in COMMANDS}
    entries = {c: tmp_path / "parses" / k[:2] / f"{k}.json" for c in COMMANDS for k in [parse_key(c, None, WORDS)]}
    first, second, third, fourth = (entries[c] for c in COMMANDS)
    text = first.read_text()
    first.write_text(text[: len(text) // 2])  # truncated
    data = json.loads(second.read_text())
    data["readings"][0][1] = 0.5  # a probability changed, its checksum not
    second.write_text(json.dumps(data))
    third.write_text(fourth.read_text())  # another command's entry under this name
    data = json.loads(fourth.read_text())
    data["readings"][0][0][4] = [1, 2]  # words that are not strings, the checksum made to match
    data["checksum"] = parse_cache._checksum(data["key"], data["readings"])
    fourth.write_text(json.dumps(data))
    warm = ParseCache(tmp_path)
    with caplog.at_level(logging.WARNING, logger="groundlang.inference.parse_cache"):
        assert {c: warm.readings(c, None, WORDS) for c in COMMANDS} == readings
        warm.report()
    corrupt = [r.getMessage() for r in caplog.records if "corrupt" in r.getMessage()]
    assert len(corrupt) == 1 and "4 corrupt entries reparsed" in corrupt[0]
    again = ParseCache(tmp_path)
    assert {c: again.readings(c, None, WORDS) for c in COMMANDS} == readings
    assert again.hits == len(COMMANDS)  # rewritten whole


def test_no_cache_writes_nothing_and_the_parsers_errors_pass_through(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("GROUNDLANG_CACHE", raising=False)
    assert ParseCache(False).readings(COMMANDS[0], None, WORDS) == tuple(parse(COMMANDS[0], word_lexicon=WORDS))
    assert not any(tmp_path.iterdir())
    with pytest.raises(ParseError):
        ParseCache(tmp_path / "cache").readings("   ", None, WORDS)


def test_training_reads_its_commands_from_the_cache(williams_commands, williams_library, tmp_path, monkeypatch):
    from groundlang.learner import Learner
    from groundlang.pair_corpus import training_instances

    instances = training_instances(williams_commands, williams_library, cache_dir=tmp_path).instances
    cold = Learner(library=williams_library, cache_dir=tmp_path).observe(instances)
    assert len(_entries(tmp_path)) == len({i.command for i in instances})
    monkeypatch.setattr(parse_cache, "parse", lambda *a, **k: pytest.fail("parsed, not read from the cache"))
    warm = Learner(library=williams_library, cache_dir=tmp_path).observe(instances)
    assert warm == cold


def test_a_folder_that_cannot_be_written_is_a_warning_and_still_read(tmp_path, monkeypatch, caplog):
    from groundlang.inference import cache_entries

    ParseCache(tmp_path).readings(COMMANDS[0], None, WORDS)
    writes = []

    def full(path, data, **options):
        writes.append(path)
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(cache_entries, "write_atomically", full)
    cache = ParseCache(tmp_path)
    with caplog.at_level(logging.WARNING, logger="groundlang.inference.parse_cache"):
        readings = [cache.readings(c, None, WORDS) for c in COMMANDS]
    assert readings == [tuple(parse(c, word_lexicon=WORDS)) for c in COMMANDS]
    assert len(writes) == 1 and (cache.hits, cache.computed) == (1, 3)  # tried once, then read only
    assert len(caplog.records) == 1 and "cannot be written" in caplog.records[0].getMessage()


def test_an_entry_whose_path_is_a_folder_loses_only_that_entry(tmp_path, caplog):
    """One entry's path taken by a folder stopped the cache being written for the rest of the run."""
    key = parse_key(COMMANDS[0], None, WORDS)
    (tmp_path / "parses" / key[:2] / f"{key}.json").mkdir(parents=True)
    cache = ParseCache(tmp_path)
    with caplog.at_level(logging.WARNING, logger="groundlang.inference.parse_cache"):
        readings = [cache.readings(c, None, WORDS) for c in COMMANDS]
        cache.report()
    assert readings == [tuple(parse(c, word_lexicon=WORDS)) for c in COMMANDS]
    assert cache.damaged == 1 and sum(p.is_file() for p in _entries(tmp_path)) == len(COMMANDS) - 1  # the others
    assert not any("cannot be written" in r.getMessage() for r in caplog.records)


def test_the_cache_writes_every_field_of_a_reading():
    from dataclasses import fields

    for kind, spec in parse_cache._FIELDS.items():
        assert [name for name, _ in spec] == [f.name for f in fields(kind)], kind.__name__


def _probabilities(readings):
    for r in readings:
        r[1] = float("nan")


def _huge(readings):
    readings[0][1] = -(10 ** 400)


def _foreign_word(readings):
    readings[0][0][1][0][2] = ["unicorn"]  # the first noun phrase's modifiers: a word the command lacks


def _nine(readings):
    readings.extend([readings[0]] * (9 - len(readings)))


# A reading is [logical form, probability]; a logical form [clauses, entities, relations, attachments, words,
# tags, fallback]; an entity [var, head, modifiers, determiner, clause, role, prep, parent, pronoun].
def _no_words(readings):
    for r in readings:
        r[0][4] = []  # trained as a command without words


def _clause_out_of_range(readings):
    readings[0][0][1][0][4] = 99


def _unknown_variable(readings):
    readings[0][0][0][0][1] = ["ghost1"]  # the first clause's arguments


def _thousands_of_noun_phrases(readings):
    entity = readings[0][0][1][0]
    readings[0][0][1] = [[f"x{i}", *entity[1:6], "to", None, None] for i in range(3000)]


def _thousands_of_clauses(readings):
    readings[0][0][0] = readings[0][0][0] * 3000


def _a_vocabulary_token_as_preposition(readings):
    readings[0][0][1][0][6] = "<dobj>"


@pytest.mark.parametrize("spoil", [_probabilities, _huge, _foreign_word, _nine, _no_words, _clause_out_of_range,
                                   _unknown_variable, _thousands_of_noun_phrases, _thousands_of_clauses,
                                   _a_vocabulary_token_as_preposition])
def test_an_entry_made_to_match_its_checksum_is_still_checked(tmp_path, spoil, caplog):
    """The checksum catches damage, not an entry written on purpose: what the encoding relies on is checked
    too, and such an entry is reparsed, not read (nor a traceback)."""
    command = COMMANDS[0]
    ParseCache(tmp_path).readings(command, None, WORDS)
    key = parse_key(command, None, WORDS)
    path = tmp_path / "parses" / key[:2] / f"{key}.json"
    data = json.loads(path.read_text())
    spoil(data["readings"])
    data["checksum"] = parse_cache._checksum(key, data["readings"])
    path.write_text(json.dumps(data))
    cache = ParseCache(tmp_path)
    with caplog.at_level(logging.WARNING, logger="groundlang.inference.parse_cache"):
        assert cache.readings(command, None, WORDS) == tuple(parse(command, word_lexicon=WORDS))
        cache.report()
    assert cache.damaged == 1 and "1 corrupt entry reparsed" in caplog.records[0].getMessage()
