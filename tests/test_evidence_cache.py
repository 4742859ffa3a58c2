"""The end-state evidence cache: a warm read gives the numbers a cold one computed, keys follow what the
numbers depend on, damaged entries are recomputed with one warning, and a folder that cannot be written
is only a warning."""

from __future__ import annotations

import json
import logging

import pytest

from groundlang.inference import cache_entries, evidence_cache
from groundlang.inference.end_states import EndStateNoise
from groundlang.inference.evidence_cache import EvidenceCache, evidence_key, library_digest
from groundlang.inference.shared_meaning import LayoutEvidence, end_state_behaviour, evidence_space
from groundlang.logic.program import Source
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.interpretations import interpretations
from groundlang.pair_corpus import training_instances


def _pairs(commands):
    return [(p.start, p.end) for c in commands for p in c.pairs]


def _same(a: LayoutEvidence, b: LayoutEvidence) -> None:
    assert a.goals == b.goals and a.values == b.values and a.floor == b.floor  # exactly: floats round-trip
    assert a.by_task == b.by_task and a.by_goal == b.by_goal
    assert a.new_relations == b.new_relations and a.new_relations is not None


def test_a_warm_cache_gives_what_was_computed_and_computes_nothing(williams_commands, williams_library, tmp_path,
                                                                    monkeypatch):
    cold = training_instances(williams_commands, williams_library, cache_dir=tmp_path)
    assert len(list((tmp_path / "evidence").rglob("*.json"))) == 6  # one entry per pair

    def refuse(*args, **kwargs):
        raise AssertionError("computed, not read from the cache")

    monkeypatch.setattr(LayoutEvidence, "__init__", refuse)
    warm = training_instances(williams_commands, williams_library, cache_dir=tmp_path)
    for a, b in zip(cold.instances, warm.instances):
        for x, y in zip(a.evidence, b.evidence):
            _same(x, y)
    # and the behaviour terms the learner reads from them are the same numbers
    interps = [interpretations(i.initial_state, williams_library) for i in cold.instances]
    assert (end_state_behaviour(cold.instances, interps, williams_library)
            == end_state_behaviour(warm.instances, interps, williams_library))


def test_no_cache_writes_nothing(williams_commands, williams_library, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("GROUNDLANG_CACHE", raising=False)
    training_instances(williams_commands[:1], williams_library, cache_dir=False)
    assert not any(tmp_path.iterdir())


def test_the_key_follows_what_the_numbers_depend_on(williams_commands, williams_library):
    (start, end), (other_start, other_end) = _pairs(williams_commands)[:2]
    digest = library_digest(williams_library)
    noise = EndStateNoise()
    space = evidence_space(start, end)
    key = evidence_key(start, end, digest, noise, space)
    assert key == evidence_key(start, end, digest, EndStateNoise(), space)  # same inputs, same entry
    changed = [
        evidence_key(other_start, end, digest, noise, space),  # another start (and layout)
        evidence_key(start, start, digest, noise, space),  # another end
        evidence_key(start, end, digest, EndStateNoise(beta=1.0), space),
        evidence_key(start, end, digest, EndStateNoise(anywhere=0.1), space),
        evidence_key(start, end, "another library", noise, space),
        evidence_key(start, end, digest, noise, evidence_space(start, end, max_states=10)),  # the abstraction
    ]
    assert len({key, *changed}) == 1 + len(changed)
    # a library differing in one rule has another digest, package sources included
    edited = TaskLibrary([*williams_library.sources, Source("extra.lp", "% a comment")])
    assert library_digest(edited) != digest
    assert library_digest(williams_library) == digest  # once per library, the same each time


def test_damaged_entries_are_recomputed_with_one_warning(williams_commands, williams_library, tmp_path, caplog):
    cold = training_instances(williams_commands, williams_library, cache_dir=tmp_path)
    entries = sorted((tmp_path / "evidence").rglob("*.json"))
    text = entries[0].read_text()
    entries[0].write_text(text[: len(text) // 2])  # truncated
    data = json.loads(entries[1].read_text())
    data["values"][0] -= 1.0  # one number changed, its checksum not
    entries[1].write_text(json.dumps(data))
    entries[2].write_text(entries[3].read_text())  # another pair's entry under this name
    entries[4].write_bytes(b"\xff\xfe\x00garbage")  # not UTF-8
    data = json.loads(entries[5].read_text())
    data["new"] = [7]  # not names, its checksum made to match
    data["checksum"] = evidence_cache._checksum(data["key"], {k: data[k] for k in ("goals", "values", "groundings",
                                                                                  "floor", "new")})
    entries[5].write_text(json.dumps(data))
    with caplog.at_level(logging.WARNING, logger="groundlang.inference.evidence_cache"):
        warm = training_instances(williams_commands, williams_library, cache_dir=tmp_path)
    corrupt = [r for r in caplog.records if "corrupt" in r.getMessage()]
    assert len(corrupt) == 1 and "5 corrupt entries recomputed" in corrupt[0].getMessage()
    for a, b in zip(cold.instances, warm.instances):
        for x, y in zip(a.evidence, b.evidence):
            _same(x, y)
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="groundlang.inference.evidence_cache"):
        training_instances(williams_commands, williams_library, cache_dir=tmp_path)
    assert not caplog.records  # rewritten whole


def test_a_folder_that_cannot_be_written_is_a_warning(williams_commands, williams_library, tmp_path, monkeypatch,
                                                      caplog):
    writes = []

    def full(path, data, **options):
        writes.append(path)
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(cache_entries, "write_atomically", full)
    cache = EvidenceCache(williams_library, EndStateNoise(), tmp_path)
    with caplog.at_level(logging.WARNING, logger="groundlang.inference.evidence_cache"):
        for start, end in _pairs(williams_commands):
            cache.evidence(start, end)
    assert len(writes) == 1 and cache.computed == 6  # tried once, then went on without writing
    assert len(caplog.records) == 1 and "cannot be written" in caplog.records[0].getMessage()


def test_a_cache_that_cannot_be_written_is_still_read(williams_commands, williams_library, tmp_path, monkeypatch):
    # a warm cache on a full disk (or a read-only share): the entries there are read after a write fails
    pairs = _pairs(williams_commands)
    EvidenceCache(williams_library, EndStateNoise(), tmp_path).evidence(*pairs[0])

    def full(path, data, **options):
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(cache_entries, "write_atomically", full)
    cache = EvidenceCache(williams_library, EndStateNoise(), tmp_path)
    cache.evidence(*pairs[1])  # not cached: computed, its write fails
    cache.evidence(*pairs[0])
    assert (cache.computed, cache.hits) == (1, 1)


def test_a_cache_folder_that_is_a_file_is_refused(williams_library, tmp_path):
    (tmp_path / "cache").write_text("")
    with pytest.raises(ValueError, match="is a file, not a folder"):
        EvidenceCache(williams_library, EndStateNoise(), tmp_path / "cache")


def test_repeated_pairs_are_computed_once_and_memory_is_bounded(williams_commands, williams_library, monkeypatch):
    monkeypatch.setattr(evidence_cache, "REMEMBERED", 2)
    cache = EvidenceCache(williams_library, EndStateNoise(), cache_dir=False)
    pairs = _pairs(williams_commands)
    first = cache.evidence(*pairs[0])
    assert cache.evidence(*pairs[0]) is first and (cache.hits, cache.computed) == (1, 1)  # shared, not recomputed
    for pair in pairs:
        cache.evidence(*pair)
    assert len(cache._memory) == 2 and cache.computed == 6  # the oldest forgotten: pairs[0] computed again


def test_commands_that_share_their_pairs_are_scored_once(williams_commands, williams_library, monkeypatch):
    """Workers shown the same pairs give commands with the same evidence objects: their behaviour terms are
    computed once and are what each command's own computation gives."""
    from groundlang.inference import shared_meaning

    instances = training_instances(williams_commands, williams_library, cache_dir=False).instances
    interps = [interpretations(i.initial_state, williams_library) for i in instances]
    alone = [end_state_behaviour([i], [g], williams_library)[0] for i, g in zip(instances, interps)]
    computed = []
    real = shared_meaning._behaviour
    monkeypatch.setattr(shared_meaning, "_behaviour", lambda *args: computed.append(1) or real(*args))
    repeated = end_state_behaviour(instances * 3, interps * 3, williams_library)
    assert repeated == alone * 3 and len(computed) == len(instances)


def _forge_grounding(data: dict) -> None:
    task, props, g = data["groundings"][0]
    data["groundings"][0] = [task, {**props, "NOSUCH": ["x"]}, g]


@pytest.mark.parametrize("forge", [
    # passes "at most 0", then overflows a float
    lambda data: data.update(floor=-(10 ** 400)),
    # a grounding of a variable its task lacks: it had stopped training with a KeyError traceback
    _forge_grounding,
    # every goal impossible: torch's nan error had stopped training
    lambda data: data.update(values=["-Infinity"] * len(data["values"])),
    # a goal of an object the layout lacks
    lambda data: data["goals"][0][0].__setitem__(1, ["agent0", "block99"]),
], ids=["float overflow", "foreign variable", "all -inf", "absent object"])
def test_an_entry_whole_but_unusable_is_a_damaged_entry(williams_commands, williams_library, tmp_path, caplog,
                                                         forge):
    """Its checksum matching (a writer's bug, a hand edit), the entry is still checked and recomputed."""
    start, end = _pairs(williams_commands)[0]
    EvidenceCache(williams_library, EndStateNoise(), tmp_path).evidence(start, end)
    (path,) = (tmp_path / "evidence").rglob("*.json")
    data = json.loads(path.read_text())
    forge(data)
    data["checksum"] = evidence_cache._checksum(data["key"], {k: data[k] for k in ("goals", "values", "groundings",
                                                                                  "floor", "new")})
    path.write_text(json.dumps(data))
    cache = EvidenceCache(williams_library, EndStateNoise(), tmp_path)
    with caplog.at_level(logging.WARNING, logger="groundlang.inference.evidence_cache"):
        cache.evidence(start, end)
        cache.report()
    assert (cache.damaged, cache.computed) == (1, 1) and "1 corrupt entry recomputed" in caplog.records[0].getMessage()
