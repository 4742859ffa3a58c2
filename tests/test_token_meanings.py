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


def test_a_library_phrase_says_what_a_palette_value_is():
    """The Williams palette stores a box's size in its colour field; the domain's phrase/2 says "large" is
    read as a size, so the lexicon does not explain toyIsLarge as a colour."""
    from groundlang.bdm_check import default_library as williams_library

    library = williams_library()
    schema = domain_schema(library, "williams2018")
    meanings = token_meanings(["toyIsLarge", "toyIsSmall", "toyIsRed"], [schema], library.phrases)
    assert meanings == {"toyIsLarge": "a large toy", "toyIsSmall": "a small toy",
                        "toyIsRed": "a toy's colour is red"}
    # a phrase of several words follows the noun, as object_phrase puts it ("the red chair east of where you stand")
    assert token_meanings(["toyIsLarge"], [schema], {"toyIsLarge": "bigger than the others"}) == {
        "toyIsLarge": "a toy bigger than the others"}
    # without the phrases the schema alone speaks
    assert token_meanings(["toyIsLarge"], [schema])["toyIsLarge"] == "a toy's colour is large"


def test_a_phrase_with_places_reads_each_place_as_its_class():
    from groundlang.wording import _pf_meaning

    corner = next(d for d in domain_schema().pfs.values() if len(d.signature) == 2)
    said = _pf_meaning(corner, [], "{1} in a corner of {2}")
    assert said == f"{'an' if corner.signature[0][0] in 'aeiou' else 'a'} {corner.signature[0]} in a corner of " \
                   f"{'an' if corner.signature[1][0] in 'aeiou' else 'a'} {corner.signature[1]}"


def test_a_task_whose_goal_pf_has_a_phrase_is_read_by_it():
    """A library's phrase/2 for a goal PF reads the task's goal too (its variables in the places)."""
    schema = domain_schema(default_library(), "williams2018")
    said = {"agentLeftOfToy": "{1} to the west of {2}"}
    assert token_meanings(["agentLeftOfToy"], [schema], said)["agentLeftOfToy"] == \
        "a task ending with agent A to the west of toy T"
