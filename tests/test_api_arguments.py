"""The Python API refuses arguments a notebook user gets wrong with one clear error naming the argument,
before any work, instead of an AttributeError from deep inside or a silently wrong answer."""

from __future__ import annotations

import re
from importlib.resources import files
from pathlib import Path

import pytest

from groundlang.corpus import example_corpus_path, read_corpus, read_instance, read_state_file
from groundlang.labels import read_labels
from groundlang.learner import Learner, NotFittedError
from groundlang.logic.tasks import TaskLibrary
from groundlang.pair_corpus import read_pair_corpus

EXAMPLES = example_corpus_path()


@pytest.fixture(scope="module")
def trained():
    return Learner(steps=30, cache_dir=False).fit(read_corpus(EXAMPLES, "sokoban").instances[:8])


@pytest.fixture(scope="module")
def novel():
    return read_state_file(EXAMPLES / "novel_b.state", "sokoban")


@pytest.mark.parametrize("options, error, message", [
    ({"language_model": None}, TypeError, "Learner: language_model must be a name"),
    ({"library": "tasks"}, TypeError, r"Learner: library must be a TaskLibrary \(TaskLibrary.load\(path\)\)"),
    ({"seed": -1}, ValueError, r"Learner: seed must be an integer from 0 to 2\*\*32 - 1, got -1"),
    ({"seed": 2**70}, ValueError, "Learner: seed must be an integer from 0 to 2"),  # failed inside fit before
    # "" had put the cache in the working folder; 5 had failed inside fit with pathlib's message
    ({"cache_dir": ""}, ValueError, r"Learner: cache_dir is empty or blank; name a folder \(or None for \$GROUNDLANG_CACHE"),
    ({"cache_dir": " "}, ValueError, "Learner: cache_dir is empty or blank"),
    ({"cache_dir": 5}, TypeError, r"Learner: cache_dir must be a folder's path \(a str or os.PathLike\), False for "
                                  "no cache or None for .* got int"),
])
def test_constructor_arguments_are_checked_at_construction(options, error, message):
    with pytest.raises(error, match=message):
        Learner(**options)


@pytest.mark.parametrize("threshold", [-1, 2, float("nan"), "0.5", True])
def test_follow_checks_min_confidence(trained, novel, threshold):
    """nan acted however unsure (every comparison with it is false); -1 and 2 were taken as given."""
    with pytest.raises(ValueError, match="follow: min_confidence must be a number from 0 to 1"):
        trained.follow("go to the red room", novel, min_confidence=threshold)


def test_clarify_takes_a_choice_by_number_and_checks_the_rest(trained, novel):
    asked = trained.follow("go to the purple room", novel, min_confidence=0.999)
    assert asked.abstained
    by_int, by_text = trained.clarify(asked, 1), trained.clarify(asked, "1")
    assert by_int.goal == by_text.goal and by_int.states == by_text.states
    with pytest.raises(TypeError, match="clarify: answer must be a str"):
        trained.clarify(asked, 2.0)
    with pytest.raises(TypeError, match="clarify: result must be the FollowResult"):
        trained.clarify(None, "1")
    with pytest.raises(ValueError, match="clarify: max_steps must be a positive integer"):
        trained.clarify(asked, "1", max_steps=0)
    with pytest.raises(NotFittedError):
        Learner().clarify(asked, "1")  # a number reads no words, but acting is a trained model's
    too_long = trained.clarify  # an answer of 5000 digits is one short line, not int()'s own error
    with pytest.raises(ValueError, match=r"answer 99999999999999999999\.\.\. \(5000 characters\): expected a number"):
        too_long(asked, "9" * 5000)


def test_update_names_what_is_wrong_in_a_short_line(trained, novel):
    with pytest.raises(TypeError, match="update: demonstration: each action must be an Action or its word"):
        trained.update("go north", novel, demonstration=[1, 2])
    # None among the actions had slipped past the check (it was the check's own "none found")
    with pytest.raises(TypeError, match="each action must be an Action or its word \\('north'\\), got NoneType"):
        trained.update("go north", novel, demonstration=[None])
    for iterated in (b"north", {"north": 1}):  # read by their byte values, by their keys
        with pytest.raises(TypeError, match="update: demonstration must be a sequence of actions"):
            trained.update("go north", novel, demonstration=iterated)
    from groundlang.confidence import GoalGroup

    with pytest.raises(ValueError, match="update: goal is a GoalGroup of no goals"):  # a bare StopIteration
        trained.update("go north", novel, goal=GoalGroup((), 1.0))
    with pytest.raises(ValueError, match="update: goal") as caught:
        trained.update("go", novel, goal="agentInRoom(agent0" + ", room1" * 100000)
    assert len(str(caught.value)) < 400


def test_lexicon_top_is_a_positive_count(trained):
    assert all(len(m) <= 2 for m in trained.lexicon(top=2).values())
    for top in (-1, 0):
        with pytest.raises(ValueError, match="lexicon: top must be a positive integer"):
            trained.lexicon(top=top)
    for top in (1.5, "3", True):  # of the wrong type: TypeError, as Python's own
        with pytest.raises(TypeError, match="lexicon: top must be a positive integer, got (float|str|bool)"):
            trained.lexicon(top=top)


def test_alignments_take_an_index_and_read_corpus_a_flag(trained, novel):
    for index in (1.5, "0", True, -1):
        with pytest.raises(ValueError, match="alignments: interpretation must be an index below"):
            trained.alignments("go to the red room", novel, interpretation=index)
    assert trained.alignments("go to the red room", novel, interpretation=0)
    with pytest.raises(TypeError, match="read_corpus: skip_inconsistent must be True or False, got 'no'"):
        read_corpus(EXAMPLES, "sokoban", skip_inconsistent="no")


def test_a_warm_start_must_be_globals_of_this_vocabulary(trained):
    instances = read_corpus(EXAMPLES, "sokoban").instances[:8]
    with pytest.raises(TypeError, match="fit: init must map global names to tensors"):
        trained.fit(instances, init=5)
    with pytest.raises(TypeError, match="fit: init must map global names to tensors"):
        trained.fit(instances, init={"phi": "x"})
    import copy

    import torch

    again = copy.deepcopy(trained)
    with pytest.raises(ValueError, match=r"fit: init\['phi'\] has shape \(2, 2\); this vocabulary's is"):
        again.fit(instances, init={"phi": torch.zeros(2, 2)})


def test_a_folder_given_as_a_state_file_is_named():
    from groundlang.corpus import CorpusError

    with pytest.raises(CorpusError, match=f"^{EXAMPLES}: a folder, not a regular file; expected a state file$"):
        read_state_file(EXAMPLES, "sokoban")
    # read_instance agrees: it had raised IsADirectoryError "[Errno 21] Is a directory"
    with pytest.raises(CorpusError, match=f"^{EXAMPLES}: a folder, not a regular file; expected a corpus file$"):
        read_instance(EXAMPLES, "sokoban")


@pytest.mark.parametrize("call, message", [
    (lambda: read_state_file(3, "sokoban"), "read_state_file: path must be a path"),
    (lambda: read_corpus(None, "sokoban"), "read_corpus: directory must be a path"),
    (lambda: read_instance(b"corpus/a.txt", "sokoban"), "read_instance: path must be a path"),
    (lambda: read_pair_corpus(7), "read_pair_corpus: path must be a path"),
    (lambda: read_labels(None), "read_labels: csv_path must be a path"),
    (lambda: Learner.load(None), "Learner.load: directory must be a path"),
    (lambda: Learner().save(0), "Learner.save: directory must be a path"),  # before "not trained"
    (lambda: TaskLibrary.load([3]), "TaskLibrary.load: each path must be a path"),
    (lambda: TaskLibrary.load(3), "TaskLibrary.load: paths must be a path or paths"),
    # bytes iterate as ints: it had said "each path must be a path ..., got int"
    (lambda: TaskLibrary.load(b"/x.lp"), "^TaskLibrary.load: paths must be a path or paths, got bytes$"),
])
def test_a_path_argument_of_another_type_is_named(call, message):
    """pathlib's own message ("expected str, bytes or os.PathLike object, not int") names no argument."""
    with pytest.raises(TypeError, match=message):
        call()


@pytest.mark.parametrize("call, what", [(lambda: Learner.load("\ud800"), "Learner.load: directory"),
                                        (lambda: Learner().save("m\ud800"), "Learner.save: directory"),
                                        (lambda: read_state_file("\udbff.state", "sokoban"), "read_state_file: path")])
def test_a_path_no_file_system_can_hold_is_named(call, what):
    """A lone surrogate is no file name: the open had raised UnicodeEncodeError (a surrogate escape, a byte
    that was not UTF-8, is a file name and is read)."""
    with pytest.raises(ValueError, match=f"^{what}: '.*' is not a file name on this system"):
        call()


def test_a_library_given_as_one_path_is_read_as_one_file(tmp_path):
    """A str is iterable: it had been read letter by letter ("no such file ... 't'")."""
    shipped = TaskLibrary.load(["williams2018"])
    assert [t.name for t in TaskLibrary.load("williams2018").tasks] == [t.name for t in shipped.tasks]
    own = tmp_path / "mine.lp"
    own.write_text((Path(str(files("groundlang.logic"))) / "tasks.lp").read_text())
    assert [t.name for t in TaskLibrary.load(own).tasks] == [t.name for t in TaskLibrary.load().tasks]


@pytest.mark.parametrize("lexicon", [5, [5], [{"NOUN": ["lamp"]}, 3.0]])
def test_word_sources_of_the_wrong_type_are_named(lexicon, trained):
    # a number had failed as "'int' object is not iterable"
    with pytest.raises(TypeError, match="Learner: lexicon must be a word file's path, words by category"):
        Learner(lexicon=lexicon)
    with pytest.raises(TypeError, match="add_words: lexicon must be"):
        trained.add_words(lexicon)
    assert Learner(lexicon=[{"NOUN": ["lamp"]}]).lexicon_words["NOUN"] == ["lamp"]


def test_add_words_names_what_is_wrong(trained):
    from groundlang.grammar.lexicon import LexiconError

    trained.add_words({"NOUN": {"mug"}})  # any iterable of words but text, bytes or a mapping
    for words, said in (({"NOUN": None}, "the words of NOUN must be a list of words, not NoneType"),
                        ({"NOUN": b"mug"}, "the words of NOUN must be a list of words, not bytes"),
                        ("", "word file '': not a file name"),  # it had opened the working folder
                        ("\x00", "not a file name"),
                        ({"NOUN": ["\ud800"]}, "is not text (a lone surrogate)")):  # had been saved with the model
        with pytest.raises(LexiconError, match=re.escape(said)):
            trained.add_words(words)


@pytest.mark.parametrize("bound, error", [(float("nan"), ValueError), (0, ValueError), (-5, ValueError),
                                          (True, TypeError), ("5000", TypeError)])
def test_a_state_bound_that_is_no_positive_number_is_refused(bound, error):
    """nan compared false with every count: it had read as "no limit" where the exact space was sized and as
    "nothing fits" where the abstraction was."""
    from groundlang.corpus import read_initial_state
    from groundlang.model.relevance import check_abstraction_possible
    from groundlang.model.statespace import enumerate_states
    from groundlang.pair_tasks import reachable

    state = read_initial_state(Path(__file__).parent / "fixtures" / "williams2018" / "one.state", "williams2018")
    for call in (lambda: check_abstraction_possible(state, bound), lambda: enumerate_states(state, bound),
                 lambda: reachable(state, state, max_states=bound)):
        with pytest.raises(error, match="max_states.*positive number of states"):
            call()
    assert reachable(state, state, max_states=1e6) is True  # a float bound is a bound
