"""Behaviour likelihood tables: the gold task wins on the corpus; the disk cache is reused and self-healing."""

from __future__ import annotations

import csv
import logging
from dataclasses import dataclass

import numpy as np
import pytest

from groundlang.inference import layout_rows
from groundlang.inference.likelihoods import behaviour_likelihood_table, cache_directory, entry_key, pad_table
from groundlang.inference.planning import TaskSettings
from groundlang.logic.atoms import Atom, parse_goal
from groundlang.model.world import Action, Agent, Door, Layout, Room, State, get_palette, replay


@dataclass(frozen=True)
class _Instance:
    initial_state: State
    states: tuple
    actions: tuple


def _demo(state: State, words: str) -> _Instance:
    actions = tuple(Action.parse(w) for w in words.split(","))
    return _Instance(state, replay(state, actions), actions)


def _corpus_like_state(x: int, y: int) -> State:
    rooms = (Room("green", 0, 10, 6, 4), Room("red", 6, 10, 10, 4), Room("blue", 0, 4, 10, 0))
    doors = (Door(3, 4, 3, 3), Door(8, 4, 8, 3), Door(5, 6, 6, 6))
    return State(Layout(rooms, doors, (), get_palette("sokoban")), Agent(x, y), ())


def _agent_goals(layout) -> list[tuple[Atom, ...]]:
    return [(Atom("agentInRoom", ("agent0", r)),) for r in layout.room_names]


@pytest.fixture
def small_instances():
    # Two demonstrations from one initial state (one solve per goal serves both) and one from another.
    start = _corpus_like_state(4, 2)
    return [
        _demo(start, "east,east,east,east,north,north,north"),  # to room1 (red)
        _demo(start, "west,north,north,north"),  # to room0 (green)
        _demo(_corpus_like_state(8, 6), "west,west,west"),  # to room0
    ]


def _count_solves(monkeypatch) -> list:
    calls = []
    original = layout_rows.solve_task  # the goals of one layout are solved there

    def counting(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(layout_rows, "solve_task", counting)
    return calls


def test_table_shares_solves_and_the_second_run_reads_the_cache(small_instances, tmp_path, monkeypatch):
    goals = [_agent_goals(i.initial_state.layout) for i in small_instances]
    calls = _count_solves(monkeypatch)
    first = behaviour_likelihood_table(small_instances, goals, cache_dir=tmp_path)
    # 2 initial states x 3 goals, not 3 instances x 3 goals.
    assert len(calls) == 6
    assert [int(np.argmax(r)) for r in first] == [1, 0, 0]
    assert all(r.shape == (3,) and np.isfinite(r).all() for r in first)
    second = behaviour_likelihood_table(small_instances, goals, cache_dir=tmp_path)
    assert len(calls) == 6
    for a, b in zip(first, second):
        np.testing.assert_array_equal(a, b)
    entries = list((tmp_path / "behaviour").rglob("*.json"))
    assert len(entries) == 9
    assert not list(tmp_path.rglob(".tmp-*"))
    # Different settings are different entries.
    behaviour_likelihood_table(small_instances, goals, TaskSettings(temperature=0.3), cache_dir=tmp_path)
    assert len(calls) == 12


def test_corrupt_entries_are_recomputed_with_a_warning(small_instances, tmp_path, caplog):
    goals = [_agent_goals(i.initial_state.layout) for i in small_instances]
    good = behaviour_likelihood_table(small_instances, goals, cache_dir=tmp_path)
    entries = sorted((tmp_path / "behaviour").rglob("*.json"))
    entries[0].write_text('{"key": "trunc')
    entries[1].write_text('{"key": "0000", "log_likelihood": 3.0}')
    entries[2].write_bytes(b"\xff\xfe\x00garbage")  # not UTF-8: what a power cut may leave of an unsynced entry
    with caplog.at_level(logging.WARNING, logger="groundlang.inference.likelihoods"):
        again = behaviour_likelihood_table(small_instances, goals, cache_dir=tmp_path)
    corrupt = [r for r in caplog.records if "corrupt" in r.getMessage()]
    assert len(corrupt) == 1 and "3 corrupt entries recomputed" in corrupt[0].getMessage()  # one line per run
    for a, b in zip(good, again):
        np.testing.assert_allclose(a, b)
    assert '"log_likelihood"' in entries[0].read_text()  # rewritten whole


def test_an_entry_of_an_unreadable_number_or_a_folder_costs_only_that_entry(small_instances, tmp_path, caplog):
    """An integer of 5,000 digits is a ValueError json does not call a decode error: it had stopped every
    run ("Exceeds the limit (4300 digits)"); a folder at one entry's path had stopped every later write."""
    goals = [_agent_goals(i.initial_state.layout) for i in small_instances]
    good = behaviour_likelihood_table(small_instances, goals, cache_dir=tmp_path)
    entries = sorted((tmp_path / "behaviour").rglob("*.json"))
    entries[0].write_text('{"key": ' + "1" * 5000 + "}")
    for entry in entries[1:3]:
        entry.unlink()
    entries[1].mkdir()
    with caplog.at_level(logging.WARNING, logger="groundlang.inference.likelihoods"):
        again = behaviour_likelihood_table(small_instances, goals, cache_dir=tmp_path)
    for a, b in zip(good, again):
        np.testing.assert_allclose(a, b)
    assert '"log_likelihood"' in entries[0].read_text()  # recomputed and rewritten
    assert entries[2].is_file()  # written after the folder's entry failed: the cache was still written
    assert not any("cannot be written" in r.getMessage() for r in caplog.records)


def test_cache_location_and_no_cache(tmp_path, monkeypatch, small_instances):
    monkeypatch.setenv("GROUNDLANG_CACHE", str(tmp_path / "env"))
    assert cache_directory() == tmp_path / "env"
    assert cache_directory(tmp_path / "given") == tmp_path / "given"
    monkeypatch.delenv("GROUNDLANG_CACHE")
    monkeypatch.chdir(tmp_path)
    assert cache_directory() == tmp_path / ".groundlang-cache"
    for blank in ("", " ", "\t"):  # as if unset, as an empty value always was: " " had made a folder " " here
        monkeypatch.setenv("GROUNDLANG_CACHE", blank)
        assert cache_directory() == tmp_path / ".groundlang-cache"
    monkeypatch.delenv("GROUNDLANG_CACHE")
    with pytest.raises(ValueError, match="cache_dir is empty or blank; name a folder"):
        cache_directory(" ")  # the working folder's " ", or with "" the working folder itself
    behaviour_likelihood_table(small_instances[:1], [_agent_goals(small_instances[0].initial_state.layout)],
                               cache_dir=False)
    assert not (tmp_path / ".groundlang-cache").exists()


def test_entry_key_depends_on_goal_demo_and_settings(small_instances):
    inst = small_instances[0]
    goal = (Atom("agentInRoom", ("agent0", "room1")),)
    key = entry_key(inst.initial_state, goal, inst.actions, TaskSettings())
    assert len(key) == 64 and key == entry_key(inst.initial_state, goal, inst.actions, TaskSettings())
    assert key != entry_key(inst.initial_state, (Atom("agentInRoom", ("agent0", "room0")),), inst.actions, TaskSettings())
    assert key != entry_key(inst.initial_state, goal, inst.actions[:-1], TaskSettings())
    assert key != entry_key(inst.initial_state, goal, inst.actions, TaskSettings(goal_reward=50.0))


def test_pad_table_and_argument_checks(small_instances):
    table, mask = pad_table([np.array([1.0, 2.0]), np.array([3.0])])
    assert table.shape == (2, 2) and table[1, 1] == -np.inf and mask.tolist() == [[True, True], [True, False]]
    with pytest.raises(ValueError, match="3 instances but 2 candidate lists"):
        behaviour_likelihood_table(small_instances, [[], []], cache_dir=False)


def test_gold_task_has_the_highest_likelihood_for_every_corpus_demonstration(shared_corpus, tmp_path):
    from groundlang.corpus import read_corpus

    corpus = read_corpus(shared_corpus / "allTurkTrain", "sokoban")
    with open(shared_corpus / "labels.csv") as f:
        gold = {row["prefix"]: parse_goal(row["goal"]) for row in csv.DictReader(f)}
    groups = corpus.distinct_demonstrations()
    assert len(groups) == 6
    demos = [members[0] for members in groups.values()]

    def groundings(layout):
        return _agent_goals(layout) + [
            (Atom("toyInRoom", (t, r)),) for t in layout.toy_names for r in layout.room_names
        ]

    candidates = [groundings(d.initial_state.layout) for d in demos]
    table = behaviour_likelihood_table(demos, candidates, cache_dir=tmp_path)
    for demo, row, goals in zip(demos, table, candidates):
        best = int(np.argmax(row))
        assert goals[best] == gold[demo.prefix], f"{demo.prefix}: {goals[best]} beats the gold goal"
        runner_up = np.sort(row)[-2]
        assert row[best] - runner_up > 5.0, f"{demo.prefix}: margin {row[best] - runner_up:.2f}"
