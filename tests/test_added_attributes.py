"""An attribute a palette adds (attribute(Class, Attribute) of its file): read from .bdm states, written to
a state's facts, refused where a format has no field for it, kept in a saved model, and learned from
end to end (tests/fixtures/materials: two toys alike but for their material)."""

import json
import re
import os
import subprocess
import sys
from pathlib import Path

import pytest

from groundlang.bdm import format_bdm_state, parse_bdm_state, read_bdm
from groundlang.corpus import CorpusError, format_state, parse_state, read_state_file
from groundlang.model.geometry import state_facts
from groundlang.model.palette import Palette, WorldError, get_palette
from groundlang.model.world import Layout

MATERIALS = Path(__file__).parent / "fixtures" / "materials"
PALETTE = str(MATERIALS / "materials.lp")
LIBRARY = ["--library", "williams2018", "--library", str(MATERIALS / "materials_pfs.lp")]


def _line(block3: str = "material: {metal} ", room: str = "") -> str:
    return ("{agent0 (agent): [x: {2} y: {2} ] , door0 (door): [top: {3} left: {4} bottom: {3} right: {4} ] , "
            "block0 (block): [x: {6} y: {2} shape: {chair} colour: {red} material: {wood} ] , "
            f"block3 (block): [x: {{2}} y: {{5}} shape: {{chair}} colour: {{red}} {block3}] , "
            f"room0 (room): [top: {{7}} left: {{0}} bottom: {{0}} right: {{4}} colour: {{red}} {room}] , "
            "room1 (room): [top: {7} left: {4} bottom: {0} right: {8} colour: {green} ] , }")


def test_a_palette_reads_the_attributes_it_adds_and_their_values():
    palette = get_palette(PALETTE)
    assert palette.added == (("toy", "material"),) and palette.attributes_of("toy") == ("material",)
    assert palette.attributes_of("room") == () and palette.values_of("material") == ("wood", "metal")
    assert [a for a, _ in palette.all_values] == ["colour", "shape", "material"]
    assert Palette.from_record(json.loads(json.dumps(palette.record()))) == palette
    # a palette adding nothing is recorded as before attributes could be added (older models compare equal),
    # with its drawing hints beside the values
    record = get_palette("williams2018").record()
    assert set(record) == {"name", "colours", "shapes", "drawing", "value_classes"}
    assert record["drawing"]["glyph"]["box"] == "\u25a1" and record["drawing"]["rgb"]["large"] == "saddlebrown"
    old = {k: v for k, v in record.items() if k not in ("drawing", "value_classes")}  # a model saved before either
    assert Palette.from_record(old) == Palette.from_record(record) == get_palette("williams2018")
    assert Palette.from_record(record).value_classes == (("large", ("toy",)), ("small", ("toy",)))
    assert Palette.from_record(old).glyphs == () and Palette.from_record(record).glyphs == get_palette("williams2018").glyphs


def test_a_bdm_state_gives_each_toy_its_material_under_the_layouts_name(tmp_path):
    state, names = parse_bdm_state(_line(), PALETTE)
    assert names == ("block0", "block3")
    assert state.layout.added_attributes == (("block0", "material", "wood"), ("block1", "material", "metal"))
    facts = state_facts(state)
    assert "material(block1,metal)." in facts and "palette_material(wood)." in facts
    assert "material(room0" not in facts
    assert parse_bdm_state(format_bdm_state(state, names), PALETTE) == (state, names)
    one = tmp_path / "one.bdm"
    one.write_text(_line() + "\n")
    assert read_state_file(one, PALETTE) == state


@pytest.mark.parametrize("line, message", [
    (_line(block3=""), "state: block block3 has no material; palette materials gives every toy one"),
    (_line(block3="material: {glass} "), "state: block3 has the material 'glass', which the palette does not have "
                                         "(it has wood, metal)"),
])
def test_a_toy_without_its_material_or_with_another_is_refused_naming_it(line, message):
    with pytest.raises(CorpusError) as err:
        parse_bdm_state(line, PALETTE)
    assert str(err.value) == message


def test_a_material_the_palette_does_not_give_rooms_is_not_read_as_one():
    state, _ = parse_bdm_state(_line(room="material: {wood} "), PALETTE)
    assert state.layout.added_values("room0") == {}  # read as the corpus's other fields are: ignored


def test_a_layout_checks_its_added_values_against_its_palette():
    state, _ = parse_bdm_state(_line(), PALETTE)
    lay = state.layout
    for added, message in [
        (lay.added_attributes[:1], "block1 has no material; palette 'materials' gives every toy one"),
        (lay.added_attributes + (("room0", "material", "wood"),), "room0 has a material, which palette"),
        ((("block0", "material", "wood"), ("block1", "material", "glass")), "block1 has the material 'glass'"),
        (lay.added_attributes + (("block1", "material", "wood"),), "block1 is given two values of material"),
    ]:
        with pytest.raises(WorldError, match=message):
            Layout(lay.rooms, lay.doors, lay.toy_attributes, lay.palette, added).validate()


def test_the_commands_to_tasks_format_has_no_field_for_an_added_attribute():
    with pytest.raises(CorpusError, match="palette materials gives every toy a material, which this format has no "
                                          "field for; write the states as .bdm lines"):
        parse_state("room,0,0,7,4,0 block,0,0,1,1 agent,2,2", PALETTE)
    assert parse_state("room,0,0,7,4,0 agent,2,2", PALETTE).layout.added_attributes == ()  # no toy, nothing lost
    with pytest.raises(WorldError, match="block0's material has no field in a commands-to-tasks state line"):
        format_state(parse_bdm_state(_line(), PALETTE)[0])


@pytest.mark.parametrize("facts, message", [
    ("attribute(agent, material).", "agent is not a class whose objects a palette describes (room, door, toy)"),
    ("attribute(toy, colour).", "colour and shape are the corpus formats' own fields"),
    ("attribute(toy, wall). value(wall, 0, thick).", "a state writes it as wall(Object, Value), which "
                                                     "groundlang.logic/domain.lp already defines"),
    ("attribute(toy, goal_atom). value(goal_atom, 0, thick).", "which groundlang.logic/groundings.lp already"),
    ("attribute(toy, x). value(x, 0, big).", "x is where an object is"),
    ("attribute(room, top). value(top, 0, big).", "top is where an object is"),
    ("attribute(toy, matKind). attribute(toy, matkind). value(matKind, 0, a). value(matkind, 0, b).",
     "attributes matKind and matkind differ in case only"),
    ("attribute(toy, weight).", "attribute(toy, weight) names an attribute of no value/3 fact"),
    ('attribute(toy, "material").', 'is not attribute(Class, Attribute) with two names'),
])
def test_an_added_attribute_that_cannot_be_one_is_refused_naming_the_fact(tmp_path, facts, message):
    palette = tmp_path / "odd.lp"
    palette.write_text("value(colour, 0, red). value(shape, 0, chair). value(material, 0, wood).\n" + facts + "\n")
    with pytest.raises(WorldError, match=message.replace("(", r"\(").replace(")", r"\)")):
        get_palette(str(palette))


@pytest.mark.parametrize("rule", ["heavy(T, yes) :- toy(T), shape(T, chair).", "{ heavy(T, yes) } :- toy(T).",
                                  "heavy(T, yes) ; light(T) :- toy(T)."])
def test_a_library_defining_the_attributes_predicate_is_refused_where_the_two_meet(tmp_path, rule):
    palette, library = tmp_path / "weights.lp", tmp_path / "heavy.lp"
    palette.write_text("value(colour, 0, red). value(colour, 1, green). value(shape, 0, chair). value(heavy, 0, yes). "
                       "value(heavy, 1, no).\n"
                       "attribute(toy, heavy).\n")
    library.write_text(rule + "\n")
    state = tmp_path / "one.bdm"
    state.write_text(_line().replace("material: {wood} ", "heavy: {no} ").replace("material: {metal} ", "heavy: {no} ")
                     + "\n")
    for args in (["domain"], ["tasks", str(state)]):
        run = _cli(*args, "--palette", str(palette), "--library", str(library))
        assert run.returncode != 0 and "Traceback" not in run.stderr and len(run.stderr.strip().splitlines()) == 1
        assert (f"palette weights: attribute(toy, heavy): a state writes it as heavy(Object, Value), which {library} "
                "defines too") in run.stderr
    # the shipped Williams library's area/2: a room's area facts would make every room the largest
    rooms = tmp_path / "rooms.lp"
    rooms.write_text("value(colour, 0, red). value(shape, 0, chair). value(area, 0, big). attribute(room, area).\n")
    run = _cli("domain", "--palette", str(rooms), "--library", "williams2018")
    assert run.returncode != 0 and "which groundlang.logic/domains/williams2018.lp defines too" in run.stderr
    assert _cli("domain", "--palette", str(rooms)).returncode == 0  # a library without area/2 has no clash


def test_domain_refuses_a_palette_every_other_command_refuses(tmp_path):
    palette = tmp_path / "agent.lp"
    palette.write_text("value(colour, 0, red). value(shape, 0, chair). value(mood, 0, calm). attribute(agent, mood).\n")
    run = _cli("domain", "--palette", str(palette))
    assert run.returncode != 0 and "agent is not a class whose objects a palette describes" in run.stderr


def test_an_end_state_whose_toys_are_made_of_something_else_is_refused(tmp_path):
    start, end = _line(), _line().replace("{wood}", "{metal}")
    corpus = tmp_path / "swapped.bdm"
    corpus.write_text(f"go next to the metal chair\n{start}\n{end}\ntrue\n")
    with pytest.raises(CorpusError, match=r"swapped.bdm, line 3: the end state's rooms, doors or blocks differ"):
        read_bdm(corpus, PALETTE)
    corpus.write_text(f"go next to the metal chair\n{start}\n{start}\ntrue\n")
    assert len(read_bdm(corpus, PALETTE)[0].pairs) == 1


def test_the_schema_shows_the_added_attributes_pf_class_as_a_property():
    run = _cli("domain", "--palette", PALETTE, *LIBRARY)
    assert run.returncode == 0, run.stderr
    assert "  material: wood, metal" in run.stdout
    assert "  material (property): toyIsWood(toy), toyIsMetal(toy)" in run.stdout
    # materials_pfs.lp's phrase/2 beside the Williams domain's two (a size stored as a colour)
    assert run.stdout.rstrip().endswith("phrases (3):\n  toyIsLarge: 'large'\n  toyIsSmall: 'small'\n"
                                        "  toyIsWood: 'wooden'")


def test_a_restriction_by_a_family_over_an_added_attribute_is_checked_when_the_library_loads(tmp_path):
    library = tmp_path / "made_of.lp"
    library.write_text('pf(material, madeOf(M), (toy,)) :- palette_material(M).\n'
                       'holds(madeOf(M), (T,)) :- toy(T), material(T, M).\n'
                       'task(woodRoom). var(woodRoom, "A", agent). var(woodRoom, "R", room).\n'
                       'goal(woodRoom, agentInRoom, ("A", "R")). restrict(woodRoom, "R", madeOf(wood)).\n')
    run = _cli("domain", "--palette", PALETTE, "--library", str(library))
    assert run.returncode != 0 and "Traceback" not in run.stderr
    assert "PF madeOf(wood) is a material PF of arguments (toy,), but variable 'R' is a room" in run.stderr


def _cli(*args: str, cache: Path | None = None) -> subprocess.CompletedProcess:
    env = dict(os.environ, GROUNDLANG_CACHE=str(cache)) if cache else None
    return subprocess.run([sys.executable, "-m", "groundlang.cli", *args], capture_output=True, text=True,
                          timeout=600, env=env)


def _next_to(state, material: str) -> bool:
    (toy,) = [k for k, name in enumerate(state.layout.toy_names)
              if state.layout.added_values(name)["material"] == material]
    x, y = state.toys[toy].x, state.toys[toy].y
    return abs(state.agent.x - x) + abs(state.agent.y - y) == 1


@pytest.mark.slow
def test_words_for_materials_are_learned_and_followed_in_a_layout_training_never_showed(tmp_path):
    """Each test command names one of two toys alike in colour and shape, which only their material tells
    apart, in a layout and a colour training never showed; choosing by anything else is right half the time
    (12 executions: all right by chance about once in 4,000)."""
    out = tmp_path / "result.json"
    run = _cli("evaluate", "--corpus", str(MATERIALS / "train.bdm"), "--test", str(MATERIALS / "test.bdm"),
               "--palette", PALETTE, *LIBRARY, "--json", str(out), cache=tmp_path / "cache")
    assert run.returncode == 0, run.stderr
    # the tasks of another library than the corpus's: the published figure is not set beside them
    assert "F1 0.82" not in run.stdout and json.loads(out.read_text())["published_f1"] is None
    rows = json.loads(out.read_text())["executions"]
    commands = read_bdm(MATERIALS / "test.bdm", PALETTE)
    assert len(rows) == 12
    for row in rows:
        final, _ = parse_bdm_state(row["final_state"], PALETTE)
        wanted = "wood" if "wooden" in commands[row["index"]].text else "metal"
        assert _next_to(final, wanted), (row["command"], row["goal"])
    # the same through a saved model: follow reads a one-line .bdm state without --palette (the model's
    # record of the palette holds the material) and writes its final state as a .bdm line
    model, start = tmp_path / "model", tmp_path / "start.bdm"
    assert _cli("train", str(MATERIALS / "train.bdm"), "--palette", PALETTE, *LIBRARY, "--no-cache",
                "-o", str(model)).returncode == 0
    start.write_text(format_bdm_state(commands[1].pairs[0].start) + "\n")
    run = _cli("follow", "--model", str(model), commands[1].text, "--env", str(start), "--json")
    assert run.returncode == 0, run.stderr
    final, _ = parse_bdm_state(json.loads(run.stdout)["final_state"], PALETTE)
    assert _next_to(final, "metal")


@pytest.mark.parametrize("change, message", [
    ({"added": [["toy", "Material"]], "added_values": {"Material": ["wood"]}}, "an attribute is a lowerCamelCase name"),
    ({"added_values": {"material": ["red", "metal"]}}, "red is a value of material and of another attribute"),
    ({"added": [["toy", "material"]], "added_values": {}}, "the same attributes in both"),
    ({"added": "toy"}, "added must be [[class, attribute], ...]"),
])
def test_a_saved_models_record_of_added_attributes_is_checked(change, message):
    from groundlang.model.palette_records import checked_palettes

    record = {**get_palette(PALETTE).record(), **change}
    with pytest.raises(ValueError, match=message.replace("[", r"\[").replace("]", r"\]")):
        checked_palettes([record])
    assert checked_palettes([get_palette(PALETTE).record()])


def test_a_material_reads_in_the_librarys_words():
    from groundlang.logic.tasks import TaskLibrary
    from groundlang.wording import object_phrase

    library = TaskLibrary.load(["williams2018", str(MATERIALS / "materials_pfs.lp")])
    state, _ = parse_bdm_state(_line(), PALETTE)
    # phrase(toyIs(wood), "wooden") in materials_pfs.lp; metal has none and reads as its value
    assert object_phrase("block0", state, library) == "the red wooden chair"
    assert object_phrase("block1", state, library) == "the red metal chair"


def test_rooms_listed_in_another_order_keep_their_added_values(tmp_path):
    palette = tmp_path / "floors.lp"
    palette.write_text("value(colour, 0, red). value(colour, 1, green). value(shape, 0, chair). "
                       "value(floor, 0, wood). value(floor, 1, tile). attribute(room, floor).\n")
    rooms = ("room0 (room): [top: {7} left: {0} bottom: {0} right: {4} colour: {red} floor: {%s} ]",
             "room1 (room): [top: {7} left: {4} bottom: {0} right: {8} colour: {green} floor: {%s} ]")
    door = "door0 (door): [top: {3} left: {4} bottom: {3} right: {4} ]"

    def line(agent_x: int, first: int, floors: tuple[str, str]) -> str:
        listed = [rooms[0] % floors[0], rooms[1] % floors[1]]
        listed = listed if first == 0 else listed[::-1]
        return "{agent0 (agent): [x: {%d} y: {2} ] , %s , %s , }" % (agent_x, door, " , ".join(listed))

    corpus = tmp_path / "floors.bdm"
    # the end line lists the rooms the other way round: the same rooms, the same floors
    corpus.write_text(f"go to the tiled room\n{line(2, 0, ('wood', 'tile'))}\n{line(6, 1, ('wood', 'tile'))}\ntrue\n")
    (command,) = read_bdm(corpus, str(palette))
    assert command.pairs[0].end.layout.added_values("room1") == {"floor": "tile"}
    corpus.write_text(f"go to the tiled room\n{line(2, 0, ('wood', 'tile'))}\n{line(6, 1, ('tile', 'wood'))}\ntrue\n")
    with pytest.raises(CorpusError, match="line 3: the end state's rooms, doors or blocks differ"):
        read_bdm(corpus, str(palette))


def test_a_value_whose_pf_takes_another_pfs_name_is_refused(tmp_path):
    """A colour named largest makes toyIs(largest) toyIsLargest, the Williams library's size PF: the schema
    had kept one of the two silently."""
    palette = tmp_path / "big.lp"
    palette.write_text("value(colour, 0, red). value(colour, 1, largest). value(shape, 0, chair).\n")
    run = _cli("domain", "--palette", str(palette), "--library", "williams2018")
    assert run.returncode != 0 and "Traceback" not in run.stderr
    assert "PFs toyIsLargest and toyIs(largest) are both called toyIsLargest in groundlang" in run.stderr


def test_a_value_a_palette_gives_to_one_class_is_refused_on_another(tmp_path):
    # the Williams palette stores a box's size in the colour field: a room coloured "large" had loaded, and
    # was then both roomIsLarge and roomIsSmallest
    large_room = _line().replace("colour: {red} ] , room1", "colour: {large} ] , room1")
    with pytest.raises(CorpusError, match=r"room0 has the colour large, which palette williams2018 gives to toys only"):
        parse_bdm_state(large_room.replace(" material: {wood}", "").replace("material: {metal} ", ""), "williams2018")
    with pytest.raises(CorpusError, match=re.escape("room0 has the colour 'purple', which the palette does not have "
                                                    "(it has red, green, blue, yellow)")):  # no sizes offered a room
        parse_bdm_state(large_room.replace("{large}", "{purple}").replace(" material: {wood}", "")
                        .replace("material: {metal} ", ""), "williams2018")
    assert parse_bdm_state(_line().replace(" material: {wood}", "").replace("material: {metal} ", "")
                           .replace("colour: {red} ] , block3", "colour: {large} ] , block3"), "williams2018")
    # a palette file of one's own says it the same way; a value or class it cannot mean is refused by name
    palette = tmp_path / "sizes.lp"
    base = "value(colour, 0, red). value(colour, 1, huge). value(shape, 0, box). "
    palette.write_text(base + "value_class(huge, toy). value_class(huge, door).\n")
    assert get_palette(str(palette)).value_classes == (("huge", ("door", "toy")),)
    for fact, message in (("value_class(tiny, toy).", "value_class(tiny, ...) names a value no value/3 fact gives"),
                          ("value_class(huge, lamp).", "value_class(huge, lamp): lamp is not a class"),
                          ('value_class(huge, "toy").', "is not value_class(Value, Class) with two names")):
        palette.write_text(base + fact + "\n")  # the same file edited: read again, not the first reading
        with pytest.raises(WorldError, match=re.escape(message)):
            get_palette(str(palette))
