"""Asking instead of guessing: abstention, the question's wording, answers, and goals in words."""

from __future__ import annotations

from pathlib import Path

import pytest

from groundlang.clarify import AnswerError, Declined, choose, question
from groundlang.confidence import GoalGroup
from groundlang.corpus import example_corpus_path, read_state_file
from groundlang.labels import goal_holds
from groundlang.learner import DEFAULT_MIN_CONFIDENCE
from groundlang.logic.atoms import parse_goal
from groundlang.logic.tasks import TaskLibrary
from groundlang.wording import goal_phrase, labelled_goal, object_phrase

EXAMPLES = example_corpus_path()
FIXTURES = __import__("pathlib").Path(__file__).parent / "fixtures"


@pytest.fixture(scope="module")
def novel_b():
    return read_state_file(EXAMPLES / "novel_b.state", "sokoban")


@pytest.fixture(scope="module")
def library():
    return TaskLibrary.load()


def _groups(*goals: str) -> list[GoalGroup]:
    return [GoalGroup((parse_goal(g),), 1 / len(goals)) for g in goals]


def test_objects_and_goals_in_words(novel_b, library):
    assert object_phrase("room0", novel_b, library) == "the red room"
    assert object_phrase("block0", novel_b, library) == "the yellow star"
    assert object_phrase("door0", novel_b, library) == "the door south and west of the agent"
    assert goal_phrase(parse_goal("toyInRoom(block0, room0)"), novel_b, library) == "the yellow star in the red room"
    assert (labelled_goal(parse_goal("agentInRoom(agent0, room1) toyInRoom(block0, room2)"), novel_b, library)
            == "the agent in the blue room and the yellow star in the green room \u2014 "
               "agentInRoom(agent0, room1) toyInRoom(block0, room2)")


def test_question_for_rooms_toys_and_conjunctions(novel_b, library):
    rooms = _groups("agentInRoom(agent0, room1)", "agentInRoom(agent0, room2)", "agentInRoom(agent0, room0)")
    assert (question(rooms, ("purple",), novel_b, library)
            == "I don't know the word 'purple'. Which room do you mean: the blue room, the green room or the red room?")
    two_toys = read_state_file(FIXTURES / "two_toys.state", "sokoban")
    toys = _groups("toyInRoom(block0, room1)", "toyInRoom(block1, room1)")
    assert question(toys, (), two_toys, library) == "Which toy do you mean: the dark gray star or the blue smiley?"
    # conjunctions that differ in one room: asked as a room; goals of different shapes: asked whole
    both = [GoalGroup((parse_goal("agentInRoom(agent0, room0) toyInRoom(block0, room1)"),), 0.5),
            GoalGroup((parse_goal("agentInRoom(agent0, room0) toyInRoom(block0, room2)"),), 0.5)]
    assert question(both, (), novel_b, library) == "Which room do you mean: the blue room or the green room?"
    mixed = _groups("agentInRoom(agent0, room1)", "toyInRoom(block0, room1)")
    assert (question(mixed, ("fetch", "blu"), novel_b, library)
            == "I don't know the words 'fetch' and 'blu'. "
               "Do you mean the agent in the blue room or the yellow star in the blue room?")
    # a word file's multiword entry is said as written, not as the tokeniser joins it
    assert question(rooms, ("coffee_table",), novel_b, library).startswith("I don't know the word 'coffee table'.")


def test_answers_by_number_and_by_words(novel_b, library):
    rooms = _groups("agentInRoom(agent0, room0)", "agentInRoom(agent0, room1)", "agentInRoom(agent0, room2)")
    assert choose("2", rooms, novel_b, library) is rooms[1]
    assert choose("the green one", rooms, novel_b, library) is rooms[2]
    assert choose("  I mean the RED room ", rooms, novel_b, library) is rooms[0]
    with pytest.raises(AnswerError, match="expected a number from 1 to 3"):
        choose("4", rooms, novel_b, library)
    assert choose("\u0663", rooms, novel_b, library) is rooms[2]  # an Arabic-Indic three is a number
    # a superscript two, a circled one: read as the digits they are written for (Unicode NFKC, as a command is)
    assert choose("\u00b2", rooms, novel_b, library) is rooms[1] and choose("\u2460", rooms, novel_b, library) is rooms[0]
    # a number in words: ORDINAL and CHOICE_NOUN of grammar/english.words
    for said, k in (("the third one", 2), ("option two", 1), ("number 2", 1), ("2nd please", 1), ("one", 0),
                    ("the first", 0), ("Choice 3.", 2)):
        assert choose(said, rooms, novel_b, library) is rooms[k], said
    with pytest.raises(AnswerError, match="expected a number from 1 to 3"):
        choose("the fourth one", rooms, novel_b, library)
    with pytest.raises(AnswerError, match="names none of the choices"):
        choose("the one", rooms, novel_b, library)  # no number
    # a quantifier or a negation makes it no choice's number ("all three" had taken the third, "no 2" the second)
    for said in ("all three", "no two", "no 2", "any two", "these two", "neither 1"):
        with pytest.raises(AnswerError):
            choose(said, rooms, novel_b, library)
    assert choose("the green one", rooms, novel_b, library) is rooms[2]  # "one", the pronoun, is no number there
    with pytest.raises(AnswerError, match="names none of the choices"):
        choose("the room", rooms, novel_b, library)  # "room" is in every choice: it tells none apart
    assert choose("the mauve one", rooms, novel_b, library, read=lambda text, c: c[1]) is rooms[1]


def test_the_models_reading_of_an_answer_counts_only_where_its_words_moved_it(novel_b, library):
    from groundlang.clarify import clear_choice

    rooms = _groups("agentInRoom(agent0, room0)", "agentInRoom(agent0, room1)")
    sure = {rooms[0].goals[0]: 0.8, rooms[1].goals[0]: 0.2}
    # Without the reading before the answer, a clear reading is taken as the answer
    assert clear_choice(sure, rooms) is rooms[0]
    # The answer's words left it as it was ("abc", never learned): the question's own doubt, no answer
    assert clear_choice(sure, rooms, before=sure) is None
    assert clear_choice(sure, rooms, before={rooms[0].goals[0]: 0.5, rooms[1].goals[0]: 0.5}) is rooms[0]
    # moved, but by less than a Bayes factor of 2 against the other choice: 0.8/0.2 after 0.7/0.3 is 1.7
    assert clear_choice(sure, rooms, before={rooms[0].goals[0]: 0.7, rooms[1].goals[0]: 0.3}) is None
    # a choice the reading before gave nothing is moved by any mass
    assert clear_choice(sure, rooms, before={rooms[1].goals[0]: 1.0}) is rooms[0]
    # a reading that gives the choices nothing, or no number, says nothing of them (it had returned the first)
    for nothing in ({}, {rooms[0].goals[0]: 0.0, rooms[1].goals[0]: 0.0}, {rooms[0].goals[0]: float("nan")},
                    {rooms[0].goals[0]: float("inf")}):
        assert clear_choice(nothing, rooms) is None


def test_a_negated_answer_names_the_choices_it_leaves_out(novel_b, library):
    rooms = _groups("agentInRoom(agent0, room0)", "agentInRoom(agent0, room1)", "agentInRoom(agent0, room2)")
    two = rooms[:2]
    # "not red" had chosen the red room: its word matched, the negation was not read
    assert choose("not the red one", two, novel_b, library) is two[1]
    assert choose("the one that isn't red", two, novel_b, library) is two[1]
    assert choose("not the blue room", two, novel_b, library) is two[0]
    with pytest.raises(AnswerError, match=r"leaves more than one choice \(the blue room or the green room\): answer with the number"):
        choose("not the red one", rooms, novel_b, library)
    with pytest.raises(Declined, match="'no' declines every choice: nothing is done"):
        choose("no", two, novel_b, library)
    with pytest.raises(AnswerError, match="leaves out every choice"):
        choose("not red or blue", two, novel_b, library)
    assert choose("not red or blue", rooms, novel_b, library) is rooms[2]
    # a negation denies what follows it in its clause: "no, the red one" is the red one, not the blue
    for answer in ("no, the red one", "no, red", "the red one, no?", "the red one no doubt", "red isn't it",
                   "red, not blue", "not blue, red"):
        assert choose(answer, two, novel_b, library) is two[0], answer
    assert choose("the red one, not the blue one", rooms, novel_b, library) is rooms[0]  # had been green
    with pytest.raises(AnswerError, match="names more than one of the choices"):
        choose("the red one. no wait, the blue one", rooms, novel_b, library)
    # a question of one choice: words all from its phrase, and some words
    for nothing in ("?", "...", "\u202e"):
        with pytest.raises(AnswerError, match="does not name the choice"):
            choose(nothing, rooms[:1], novel_b, library)


def test_an_answer_of_unknown_words_chooses_nothing(learner, novel_b):
    """"abc" read after the command leaves the reading as it was: asked at confidence 1, the reading's own
    most probable choice had been taken as the answer (and, with follow --ask --learn, saved)."""
    result = learner.follow("go to the room", novel_b, min_confidence=1.0)
    assert result.abstained and len(result.choices) >= 2
    for answer in ("abc", "-1", "1e9"):
        with pytest.raises(AnswerError, match="names none of the choices"):
            learner.clarify(result, answer)
    # one choice ("Do you mean the agent in the red room?"): its number, its words or a yes; a no declines it
    one = learner.follow("go to the red room", novel_b, min_confidence=1.0)
    assert one.abstained and len(one.choices) == 1
    for answer in ("abc", "the blue room", "no, the red one", "yes, the blue room", "that one", "no, the first one",
                   "no 1"):
        with pytest.raises(AnswerError, match="does not name the choice .*: answer 1, yes or its words to act on it, "
                                              "no to decline it") as refused:
            learner.clarify(one, answer)
        assert not isinstance(refused.value, Declined), answer
    for answer in ("no", "Nope.", "not the red room", "no thanks", "don't", "none of them"):
        with pytest.raises(Declined, match="declines the choice: nothing is done"):
            learner.clarify(one, answer)
    for answer in ("the red room", "1", "yes", "Yes please", "ok", "yeah, the red one", "sure, do it"):
        assert learner.clarify(one, answer).goal == one.choices[0].goal, answer
    # of several choices, a no declines them all; a yes chooses none
    with pytest.raises(Declined, match="declines every choice"):
        learner.clarify(result, "none of them")
    with pytest.raises(AnswerError, match="names none of the choices"):
        learner.clarify(result, "yes")


def test_follow_asks_about_an_unknown_colour_and_acts_on_the_answer(learner, novel_b):
    result = learner.follow("go to the purple room", novel_b, min_confidence=DEFAULT_MIN_CONFIDENCE)
    assert result.abstained and result.reason == "abstained" and not result.actions
    assert result.confidence == pytest.approx(1 / 3, abs=0.01)
    assert result.unknown_words == ("purple",)
    assert result.question.startswith("I don't know the word 'purple'. Which room do you mean: ")
    assert len(result.choices) == 3
    assert repr(result).startswith("FollowResult('go to the purple room', abstained, confidence=0.33")
    answered = learner.clarify(result, "the blue one")
    assert answered.goal == parse_goal("agentInRoom(agent0, room1)") and answered.reached
    assert answered.goal_words == "the agent in the blue room"
    with pytest.raises(ValueError, match="acted already"):
        learner.clarify(answered, "1")


def test_an_answer_that_is_not_utf8_is_named_as_the_answer(learner, novel_b):
    """It was read after the command and refused as "cannot parse the command", at a character of both."""
    asked = learner.follow("go to the purple room", novel_b, min_confidence=DEFAULT_MIN_CONFIDENCE)
    with pytest.raises(AnswerError, match=r"^the answer is not UTF-8 text \(byte 0xff at character 5\): expected a "
                                          "number or words naming one of the choices"):
        learner.clarify(asked, "the \udcff one")


@pytest.mark.parametrize("command", ["go to the purple room", "go to a room", "move the star", "go to the blue room",
                                     "take the star to the green room"])
def test_the_goal_said_to_be_reached_holds_where_the_agent_ends(learner, novel_b, command):
    # expected_success may end in any of the states worth the most, not only where the goal it started
    # from holds (three rooms tied at the top, the agent in a door between two): the goal said is where it ends
    result = learner.follow(command, novel_b)
    assert result.reached and goal_holds(result.goal, result.states[-1])
    assert dict(result.posterior.goals())[result.goal] >= max(
        p for g, p in result.posterior.goals() if goal_holds(g, result.states[-1])) - 1e-12


def test_a_known_command_is_acted_on_and_reads_in_short(learner, novel_b):
    result = learner.follow("take the star to the red room", novel_b, min_confidence=DEFAULT_MIN_CONFIDENCE)
    assert not result.abstained and result.reached and result.confidence > 0.95
    assert result.posterior.margin > 0.9
    text = repr(result)
    assert len(text) < 200 and "goal='toyInRoom(block0, room0)'" in text and "reached=True" in text
    post = repr(result.posterior)
    assert len(post) < 200 and "confidence=0.9" in post
    # without a threshold it always acts, as before
    assert not learner.follow("go to the purple room", novel_b).abstained


def test_confidences_are_shown_rounded_down_so_a_threshold_is_never_contradicted():
    """0.6999 shown as 0.70 had read "confidence 0.70 is below --min-confidence 0.7"; a value that is exact in
    hundredths stays itself (0.29 * 100 is 28.999... in floating point)."""
    from groundlang.commands.asking import down as _down

    assert [_down(x) for x in (0.6999, 0.7, 0.29, 0.58, 1.0, 0.0)] == ["0.69", "0.70", "0.29", "0.58", "1.00", "0.00"]
    # as many places as the threshold has: 0.996 is not shown as 0.99 against --min-confidence 0.995
    from groundlang.commands.asking import places_for as _places

    assert [_places(t) for t in (0.7, 0.995, 0.9961, 0.12345678)] == [2, 3, 4, 6]
    assert _down(0.996, _places(0.995)) == "0.996"


def test_no_choices_are_no_question(novel_b, library):
    from groundlang.clarify import competing

    assert competing([]) == []  # an IndexError
    with pytest.raises(ValueError, match="question: no choices to ask about"):  # "Do you mean ?"
        question([], (), novel_b, library)


def test_a_result_whose_choices_another_library_made_is_refused(learner, novel_b):
    """A result of a learner with a library of other relations, answered by this one: planning its choice had
    failed deep in tabulation (TabulationError) naming nothing the caller gave."""
    from dataclasses import replace

    asked = learner.follow("go to the purple room", novel_b, min_confidence=DEFAULT_MIN_CONFIDENCE)
    foreign = replace(asked, choices=[GoalGroup((parse_goal("agentLeftOfToy(agent0, block0)"),), 1.0)])
    with pytest.raises(ValueError, match="clarify: the result's choices are goals of another task library than this "
                                         "learner's"):
        learner.clarify(foreign, "1")
    assert learner.clarify(asked, "1").reached  # its own result is answered as ever


def test_answers_about_sides_are_read_by_their_side_not_as_yes_or_no():
    """"right" had been a yes, and adverbs words that say nothing: "the one on the right" took "left of the
    chair" offered alone, and "no, the right one" declined every choice."""
    library = TaskLibrary.load(["williams2018"])
    state = read_state_file(Path(__file__).parent / "fixtures" / "williams2018" / "one.state", "williams2018")
    left, right, beside = (GoalGroup((parse_goal(f"{pf}(agent0, block0)"),), 0.3)
                           for pf in ("agentLeftOfToy", "agentRightOfToy", "agentNextToToy"))
    for answer in ("right", "the one on the right", "to the right", "the", "the one to the north"):
        with pytest.raises(AnswerError, match="does not name the choice") as refused:
            choose(answer, [left], state, library)
        assert not isinstance(refused.value, Declined), answer
    for answer in ("on the left", "yes, left of it", "ok thanks"):
        assert choose(answer, [left], state, library) is left, answer
    for answer in ("no, the right one", "the right one, not the left one", "right, not left", "nope, to the right"):
        assert choose(answer, [right, left, beside], state, library) is right, answer
    assert choose("not the left one", [left, right], state, library) is right
    for answer in ("yes no", "no, yes"):  # both: asked again, never acted on
        with pytest.raises(AnswerError, match="says both yes .* and no"):
            choose(answer, [left, right], state, library)


def test_a_denial_declines_one_choice_only_where_it_denies_that_choice():
    """"not the green room" to "Do you mean the agent in the red room?" had declined it (its "room" was the
    choice's): for the question of what already holds, that acted on the rest, the green room."""
    library = TaskLibrary.load(["williams2018"])
    state = read_state_file(Path(__file__).parent / "fixtures" / "williams2018" / "one.state", "williams2018")
    red, blue = (GoalGroup((parse_goal(f"agentInRoom(agent0, {room})"),), 0.3) for room in ("room1", "room0"))
    for answer in ("not the green room", "isn't it the green room?", "that's right"):
        with pytest.raises(AnswerError, match="does not name the choice") as refused:
            choose(answer, [red], state, library)
        assert not isinstance(refused.value, Declined), answer
    for answer in ("not the red room", "not that one", "no thank you"):
        with pytest.raises(Declined):
            choose(answer, [red], state, library)
    # whole tokens say nothing ("thank you", "'s"), and so does an auxiliary that is a verb too ("is")
    for answer in ("yes thank you", "yes, thank you", "yes it is", "yes that's it", "that's correct"):
        assert choose(answer, [red], state, library) is red, answer
    # a yes beside a negation of one choice picks the other (it had been refused as saying both)
    for answer in ("yes, the one that isn't red", "sure, not the red one", "ok, not red",
                   "yeah the blue one not the green one"):
        assert choose(answer, [red, blue], state, library) is blue, answer
    # of several choices a bare negation declines nothing: which one is denied is asked again
    with pytest.raises(AnswerError, match="names none of the choices") as refused:
        choose("not that one", [red, blue], state, library)
    assert not isinstance(refused.value, Declined)
