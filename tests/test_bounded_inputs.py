"""Inputs whose size a user controls cost time and memory bounded by what they mean, not by their size:
an overlong word in a command, a word file that is not a file of words, many words in one, and a
conjunction size beyond what any demonstration offers; and more worker processes than folds or cores."""

from __future__ import annotations

import os
import time
import tracemalloc
from collections import Counter

import pytest

from groundlang.corpus import example_corpus_path, read_corpus
from groundlang.grammar.lexicon import Lexicon, LexiconError, read_word_file
from groundlang.inference.discovery import DiscoverySettings, _Demo, _fit_top_features
from groundlang.model.domain_words import extra_words
from groundlang.model.vocabulary import MAX_SPELLING_LENGTH, Vocabulary, _neighbours


def test_an_overlong_word_is_not_searched_for_a_typo():
    known = {"x" * MAX_SPELLING_LENGTH}.__contains__
    # At the limit a typo is still read as the word meant (one letter inserted) ...
    assert _neighbours("x" * (MAX_SPELLING_LENGTH - 1), known, Lexicon.english()) == "x" * MAX_SPELLING_LENGTH
    # ... beyond it the word is not searched: its neighbours would take memory in the square of its length.
    tracemalloc.start()
    assert _neighbours("x" * 100_000, known, Lexicon.english()) is None
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert peak < 10 * 2**20


def test_training_reads_an_overlong_word_in_bounded_memory():
    vocab = Vocabulary()
    tracemalloc.start()
    vocab.read_misspellings(Counter({"white": 40, "whlite": 1, "w" * 100_000: 1}))
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert vocab.aliases == {"whlite": "white"} and peak < 10 * 2**20


def test_a_word_file_that_is_a_fifo_or_too_large_is_refused_in_one_line(tmp_path):
    fifo = tmp_path / "words.fifo"
    os.mkfifo(fifo)
    with pytest.raises(LexiconError, match="not a regular file"):
        read_word_file(fifo)  # returns at once: no writer is waited for
    with pytest.raises(LexiconError, match="not a regular file"):
        read_word_file("/dev/zero")
    big = tmp_path / "big.words"
    big.write_text("NOUN: mug\n" * 500_000)
    with pytest.raises(LexiconError, match="a word file of more than 4,194,304 bytes"):
        read_word_file(big)


def test_a_word_file_behind_a_byte_order_mark_is_read(tmp_path):
    path = tmp_path / "bom.words"
    path.write_bytes(b"\xef\xbb\xbfNOUN: mug\n")
    assert read_word_file(path) == {"NOUN": ("mug",)}


def test_many_words_merge_in_linear_time_in_order_once_each(tmp_path):
    words = [f"w{i}" for i in range(60_000)]
    first, second = tmp_path / "a.words", tmp_path / "b.words"
    first.write_text("NOUN: " + " ".join(words) + "\n")
    second.write_text("NOUN: w5 extra w0\nADJ: w1\n")
    started = time.perf_counter()
    merged = extra_words([first, second])
    assert time.perf_counter() - started < 5  # quadratic merging took minutes at this size
    assert merged["NOUN"] == words + ["extra"] and merged["ADJ"] == ["w1"]


@pytest.mark.slow
def test_a_conjunction_size_beyond_the_top_features_gives_the_same_candidates():
    inst = read_corpus(example_corpus_path(), "sokoban").instances[0]
    found = []
    for max_conjuncts in (3, 10**14):  # the second took hours before: every size up to it was tried
        demo = _Demo(inst, (inst.name,))
        started = time.perf_counter()
        _fit_top_features(demo, DiscoverySettings(max_conjuncts=max_conjuncts))
        found.append((demo.top, demo.goals, time.perf_counter() - started))
    assert len(found[0][0]) <= 3 and found[0][1]  # 3 covers every subset of the top features here
    assert found[0][:2] == found[1][:2]


def test_workers_beyond_the_folds_or_cores_fork_no_more_processes(monkeypatch, capsys):
    """--workers 100000 forked 100000 copies of the process for 4 folds (a load average of 350 here)."""
    import multiprocessing

    from groundlang.cli import main

    pools = []

    class Refused(Exception):
        pass

    class Context:
        def Pool(self, processes, *args):  # noqa: N802 (multiprocessing's name)
            pools.append(processes)
            raise Refused  # a test must not fork: the size asked for is all it checks

    monkeypatch.setattr(multiprocessing, "get_context", lambda method: Context())
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1, 2, 3, 4, 5, 6, 7}, raising=False)
    corpus = os.path.join(os.path.dirname(__file__), "fixtures", "sokoban")  # 4 instances: 4 folds
    with pytest.raises(Refused):
        main(["--quiet", "evaluate", "--corpus", corpus, "--palette", "sokoban", "--labels",
              os.path.join(corpus, "labels.csv"), "--workers", "100000"])
    assert pools == [4]
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1})
    with pytest.raises(Refused):
        main(["--quiet", "evaluate", "--corpus", corpus, "--palette", "sokoban", "--labels",
              os.path.join(corpus, "labels.csv"), "--workers", "100000"])
    assert pools == [4, 2]


@pytest.mark.parametrize("line, message", [
    ("room,1,0,4,4,0 agent,1,1 " + "blah" * 250_000,
     "unknown object kind 'blahblahblahblahblah... (1000000 characters)' in 'blahblahblahblahblahblahblahblahblah"
     "blahblahblahblahblahblah... (1000000 characters)'; expected room, door, block (or toy) or agent"),
    ("room,1,0,4,4,0 agent,1,1 door" + ",1" * 250_000,
     "'door,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1... (500004 characters)' has 250001 "
     "comma-separated fields; expected 5 (door,LEFT,TOP,RIGHT,BOTTOM)"),
])
def test_an_error_quotes_a_huge_token_of_a_state_line_by_its_start(tmp_path, line, message):
    """A state line without spaces (megabytes in one token) was quoted whole: a 6 MB error line."""
    from groundlang.corpus import CorpusError, read_state_file

    path = tmp_path / "x.state"
    path.write_text(line + "\n")
    with pytest.raises(CorpusError) as error:
        read_state_file(path, "sokoban")
    assert str(error.value) == f"{path}, line 1: {message}"


def test_an_error_quotes_a_huge_action_by_its_start(tmp_path):
    from groundlang.corpus import CorpusError, read_instance

    lines = (example_corpus_path() / "agent2blue_0.txt").read_text().split("\n")
    lines[1] = "north" * 200_000 + "," + lines[1]
    path = tmp_path / "agent2blue_0.txt"
    path.write_text("\n".join(lines))
    with pytest.raises(CorpusError) as error:
        read_instance(path, "sokoban")
    assert str(error.value) == (f"{path}, line 2: action 1 is 'northnorthnorthnorth... (1000000 characters)'; "
                                "expected one of north, south, east, west")


def test_a_layout_of_more_objects_than_are_read_is_refused_before_they_are_checked(tmp_path):
    """100,000 doors in one state line took 25 s to refuse, door by door; a layout's rooms, doors and toys are
    counted first."""
    from groundlang.corpus import read_state_file
    from groundlang.model.world import MAX_LAYOUT_OBJECTS
    from groundlang.state_line import CorpusError

    path = tmp_path / "doors.state"
    path.write_text("room,5,0,4,4,0 room,10,4,4,8,0 " + " ".join(["door,4,2,4,2"] * 5000) + " agent,2,2\n")
    with pytest.raises(CorpusError, match=f"the layout has 5,002 rooms, doors and toys \\(2, 5,000, 0\\); at most "
                                          f"{MAX_LAYOUT_OBJECTS:,} are read"):
        read_state_file(path, "sokoban")
    # as many as are read: six rooms side by side, 1000 cells tall, a door on each cell of their five walls
    # (two doors on one cell are refused: one opening named twice)
    fine = tmp_path / "fine.state"
    rooms = " ".join(f"room,5,{4 * k},1000,{4 * k + 4},0" for k in range(6))
    doors = [f"door,{4 * k},{y},{4 * k},{y}" for k in range(1, 6) for y in range(1, 1000)][: MAX_LAYOUT_OBJECTS - 6]
    fine.write_text(f"{rooms} {' '.join(doors)} agent,2,2\n")
    assert len(read_state_file(fine, "sokoban").layout.doors) == MAX_LAYOUT_OBJECTS - 6


def test_a_layout_of_more_rooms_than_are_read_is_refused_naming_its_file(tmp_path):
    """1,600 rooms of one cell each in a 30 KB state line took 75 s and 2.5 GB to follow one command."""
    from groundlang.corpus import read_state_file
    from groundlang.model.world import MAX_LAYOUT_ROOMS
    from groundlang.state_line import CorpusError

    def grid(n: int) -> str:
        return " ".join(f"room,1,{2 * i},{2 * j + 2},{2 * i + 2},{2 * j}" for i in range(n) for j in range(n)) + \
            " agent,1,1\n"

    path = tmp_path / "rooms.state"
    path.write_text(grid(17))
    with pytest.raises(CorpusError, match=rf"rooms.state.*: the layout has 289 rooms; at most {MAX_LAYOUT_ROOMS} are "
                                          "read"):
        read_state_file(path, "sokoban")
    path.write_text(grid(16))  # as many as are read
    assert len(read_state_file(path, "sokoban").layout.rooms) == MAX_LAYOUT_ROOMS == 256
