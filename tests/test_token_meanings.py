"""The model's semantic tokens explained in words read from the domain's schema (``groundlang lexicon``'s legend)."""

from __future__ import annotations

from groundlang.bdm_check import default_library
from groundlang.logic.schema import domain_schema
from groundlang.wording import token_meanings


def test_the_package_domain_tokens_read_from_their_declarations():
    meanings = token_meanings(["roomIsRed", "toyIsStar", "roomIsDarkGray", "agentInRoom", "doorWestOfAgent",
                               "CLASS:room", "CLASS:agent", "NULL", "toyToRoom", "toyToRoomAgentToRoom"],
                              [domain_schema()])
    assert meanings == {
        "roomIsRed": "a room's colour is red",
        "toyIsStar": "a toy's shape is star",
        "roomIsDarkGray": "a room's colour is dark gray",
        "agentInRoom": "an agent in a room",
        "doorWestOfAgent": "a door west of the agent",
        "CLASS:room": "names a room",
        "CLASS:agent": "names an agent",
        "NULL": 'no meaning in the domain (a word such as "the")',
        "toyToRoom": "a task ending with toy T in room R",
        "toyToRoomAgentToRoom": "a task ending with agent A in room RA and toy T in room RT",
    }


def test_each_token_once_in_first_seen_order_and_undeclared_ones_left_out():
    meanings = token_meanings(["roomIsBlue", "NULL", "roomIsBlue", "noSuchToken"], [domain_schema()])
    assert list(meanings) == ["roomIsBlue", "NULL"]


def test_a_user_domain_is_explained_from_its_own_files():
    schema = domain_schema(default_library(), "williams2018")
    meanings = token_meanings(["roomIsLargestOfItsColour", "toyIsChair", "agentLeftOfToy"], [schema])
    assert meanings["roomIsLargestOfItsColour"] == "a room is largest of its colour"
    assert meanings["toyIsChair"] == "a toy's shape is chair"
    # declared both as a PF and as a task: a word names it as the task
    assert meanings["agentLeftOfToy"] == "a task ending with agent A left of toy T"
