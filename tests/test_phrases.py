"""How a person reads a PF, said in ASP (``phrase(PF, "words")``): goals and objects in a library's own words,
and phrases that cannot be read refused when the library loads."""

import pytest

from groundlang.bdm import parse_bdm_state
from groundlang.logic.atoms import parse_goal
from groundlang.logic.program import AspError
from groundlang.logic.tasks import TaskLibrary
from groundlang.wording import goal_phrase, object_phrase

# a corner goal, a material of one's own (no value in its term) and a side of the agent, as a domain author wrote
MINE = """
goal_class(place).
corner(R, X, Y) :- room(R), rect(R, L, T, Rt, B), X = (L + 1; Rt - 1), Y = (B + 1; T - 1).
pf(place, agentInCornerOfRoom, (agent, room)).
holds(agentInCornerOfRoom, (A, R)) :- agent(A), at(A, X, Y), corner(R, X, Y).
pf(material, toyIsShiny, (toy,)).
holds(toyIsShiny, (T,)) :- toy(T), shape(T, basket).
viewpoint_class(bearing).
pf(bearing, toyEastOfAgent, (toy,)).
holds(toyEastOfAgent, (T,)) :- toy(T), agent(A), at(A, X, _), at(T, U, _), U > X.
"""
SAID = """
phrase(agentInCornerOfRoom, "{1} in a corner of {2}").
phrase(toyIsShiny, "shiny").
phrase(toyEastOfAgent, "east of where you stand").
"""
STATE = ("{agent0 (agent): [x: {2} y: {2} ] , door0 (door): [top: {3} left: {4} bottom: {3} right: {4} ] , "
         "block0 (block): [x: {6} y: {2} shape: {basket} colour: {red} ] , "
         "block1 (block): [x: {2} y: {5} shape: {chair} colour: {red} ] , "
         "block2 (block): [x: {6} y: {5} shape: {chair} colour: {red} ] , "
         "room0 (room): [top: {7} left: {0} bottom: {0} right: {4} colour: {red} ] , "
         "room1 (room): [top: {7} left: {4} bottom: {0} right: {8} colour: {green} ] , }")


def _library(tmp_path, text: str) -> TaskLibrary:
    mine = tmp_path / "mine.lp"
    mine.write_text(MINE + text)
    return TaskLibrary.load(["williams2018", str(mine)])


def test_goals_and_objects_read_in_the_librarys_words(tmp_path):
    state, _ = parse_bdm_state(STATE)
    said, unsaid = _library(tmp_path, SAID), _library(tmp_path, "")
    corner = parse_goal("agentInCornerOfRoom(agent0, room1)")
    assert goal_phrase(corner, state, said) == "the agent in a corner of the green room"
    assert goal_phrase(corner, state, unsaid) == "the agent in corner of the green room"  # its camel-case words
    assert object_phrase("block0", state, said) == "the red shiny basket"
    # two red chairs: told apart by the side of the agent each lies on, in the library's words
    assert object_phrase("block2", state, said) == "the red chair east of where you stand"
    assert object_phrase("block2", state, unsaid) == "the red chair east of the agent"
    assert said.phrases == {"agentInCornerOfRoom": "{1} in a corner of {2}", "toyIsShiny": "shiny",
                            "toyEastOfAgent": "east of where you stand",
                            "toyIsLarge": "large", "toyIsSmall": "small"}  # the Williams domain's own


@pytest.mark.parametrize("text, message", [
    ('phrase(toyIsShiny, "shiny"). phrase(toyIsShiny, "gleaming").', "PF toyIsShiny has two phrases"),
    ("phrase(toyIsShiny, shiny).", 'is not phrase(PF, "words") with a PF and words in quotes'),
    ('phrase(toyIsShiny, " ").', 'is not phrase(PF, "words")'),
    ('phrase(agentInCornerOfRoom, "in a corner of {2}").', "the words of a PF of 2 arguments have the places {1}, {2}"),
    ('phrase(agentInCornerOfRoom, "{1} in {2} of {3}").', "the words of a PF of 2 arguments have the places"),
    ('phrase(toyIsShiny, "{2} shines").', "the words of a PF of 1 argument have the places {1}, each once"),
    ('phrase(toyIsShinny, "shiny").', "no pf/3 declares a PF toyIsShinny"),
    # a family's member: its arguments are the family's, however many places the words give, and a place of
    # any size is out of range as it is (once a place of 10^8 built a list of 10^8 numbers)
    ('phrase(toyIs(red), "{1} {2} {3}").', "the words of a PF of 1 argument have the places {1}, each once"),
    ('phrase(toyIs(red), "{100000000}").', "the words of a PF of 1 argument have the places {1}, each once"),
    ('phrase(toyIs(red), "{' + "9" * 5000 + '}").', "the words of a PF of 1 argument have the places {1}"),
    # a family term that spells a PF of its own (agentInRoom, of two arguments; no family agentIn): it crashed
    # follow's wording before
    ('phrase(agentIn(room), "{1} {2} {3}").', "no family declares agentIn(room); the PF agentInRoom is pf/3's "
                                             "agentInRoom: write phrase(agentInRoom, ...)"),
    ('phrase(toyShaped(wood), "wooden").', "no pf/3 declares a PF toyShapedWood"),  # no such family
    # printed in every goal line and saved in the model: a line break or an escape forged output
    ('phrase(agentInRoom, "{1} in {2}\\nFAKE LINE").', "the words hold a control character"),
    ('phrase(agentInRoom, "{1} in \x1b[31m{2}").', "the words hold a control character"),
    ('phrase(agentInRoom, "{1} in\u2028{2}").', "the words hold a control character"),  # a line separator
])
def test_a_phrase_that_cannot_be_read_is_refused_when_the_library_loads(tmp_path, text, message):
    with pytest.raises(AspError, match=message.replace("(", r"\(").replace(")", r"\)").replace("{", r"\{")
                       .replace("}", r"\}")):
        _library(tmp_path, text)
