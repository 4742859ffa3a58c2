"""Palettes as data: logic/palettes/*.lp and a user's own file, and their errors."""

from __future__ import annotations

import subprocess
import sys

import pytest

from groundlang import example_corpus_path, read_corpus
from groundlang.logic.palette_files import palette_names
from groundlang.model.world import WorldError, get_palette


def test_the_shipped_palettes_are_files():
    assert palette_names() == ["sokoban", "sokoban2", "williams2018"]
    sokoban = get_palette("sokoban")
    assert sokoban.colours[10] == "red" and sokoban.colours[5] == "green" and len(sokoban.colours) == 13
    assert sokoban.shapes == ("star", "moon", "circle", "smiley", "square")
    assert get_palette("sokoban2").shapes == ("chair", "bag", "backpack", "basket")


def test_a_copy_of_a_palette_file_reads_the_corpus_the_same(tmp_path):
    from importlib.resources import files

    mine = tmp_path / "mine.lp"
    mine.write_text((files("groundlang.logic") / "palettes" / "sokoban.lp").read_text(), encoding="utf-8")
    theirs = read_corpus(example_corpus_path(), "sokoban")
    ours = read_corpus(example_corpus_path(), str(mine))
    assert ours.palette.name == "mine" and ours.palette.colours == theirs.palette.colours
    assert [i.command for i in ours.instances] == [i.command for i in theirs.instances]
    assert [r.colour for r in ours.instances[0].initial_state.layout.rooms] == \
        [r.colour for r in theirs.instances[0].initial_state.layout.rooms]


@pytest.mark.parametrize("text, piece", [
    ("value(colour, 0, red). value(colour, 2, blue). value(shape, 0, star).", "1 is missing"),
    ("value(colour, 0, red). value(colour, 0, blue). value(shape, 0, star).", "index 0 is both"),
    ("value(colour, 0, red). value(colour, 1, red). value(shape, 0, star).", "has two indices"),
    ("value(colour, 0, red).", "no shape values"),
    ("colour(red).", "line 1: colour(red) is none of a palette's facts (value(Attribute, Index, Name)"),
    ("value(colour, 0, red). value(shape, 0, star).\n-value(colour, 1, x).", "line 2: -value(colour,1,x) is none"),
    # what one solve would read as nothing, or as whichever answer clingo gave first
    ("value(colour, 0, red). value(shape, 0, star).\n{ value(colour, 1, green) }.", "more than one answer set"),
    ("value(colour, 0, red). value(shape, 0, star).\n:- value(colour, 0, red).", "no answer set"),
    ("value(colour, 0, red). value(shape, 0, star).\n#program other.\nvalue(colour, 1, blue).",
     "line 2: #program other: a palette is read as one program"),
    ("value(colour, 0, red). value(shape, 0, star).\nvalue(colour, 1, @f(x)).", "a palette calls no script"),
    ('value(colour, 0, red). value(shape, 0, star).\nrgb(star, "gold").',
     "rgb(star, ...) names a value of shape; an rgb is of a colour value"),
    ("", "no value(Attribute, Index, Name) facts"),
    # a fact of a palette's name with a field missing or added, or misspelt, had been dropped without a word
    ("value(colour, 0, red). value(shape, 0, star).\nvalue(colour, violet).", "line 2: value(colour,violet) is none"),
    ("value(colour, 0, red). value(shape, 0, star).\nvalue(colour, 1, navy, 3).", "line 2: value(colour,1,navy,3)"),
    ("value(colour, 0, red). value(shape, 0, star).\nvalu(colour, 1, navy).", "line 2: valu(colour,1,navy) is none"),
    ("value(colour, 0, red). value(shape, 0, star).\nattribute(toy).", "line 2: attribute(toy) is none"),
    ('value(colour, 0, red). value(shape, 0, star).\nglyph(stra, "x").', "glyph(stra, ...) names a value no value/3 fact gives; a glyph is of a shape value"),
    ("value(colour, 0, \"red\"). value(shape, 0, star).", "lowerCamelCase constant"),
    ("value(colour, 0, red", "syntax error"),
])
def test_bad_palette_files_are_one_clear_error(tmp_path, text, piece):
    path = tmp_path / "bad.lp"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(WorldError) as info:
        get_palette(str(path))
    assert piece in str(info.value) and "bad.lp" in str(info.value)


def test_the_cli_takes_a_palette_name_or_file_and_names_a_bad_one(tmp_path):
    E = example_corpus_path()
    ok = subprocess.run([sys.executable, "-m", "groundlang.cli", "check", str(E), "--palette", "sokoban"],
                        capture_output=True, text=True)
    assert ok.returncode == 0 and "palette sokoban" in ok.stdout
    bad = subprocess.run([sys.executable, "-m", "groundlang.cli", "check", str(E), "--palette", "sokobann"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and len(bad.stderr.splitlines()) == 1, bad.stderr
    assert "unknown palette 'sokobann'; expected one of sokoban, sokoban2" in bad.stderr
    missing = subprocess.run([sys.executable, "-m", "groundlang.cli", "check", str(E), "--palette",
                              str(tmp_path / "none.lp")], capture_output=True, text=True)
    assert missing.returncode == 2 and "none.lp" in missing.stderr and "Traceback" not in missing.stderr


def test_the_help_lists_every_palette_the_package_ships():
    from groundlang.commands import PALETTE_HELP
    from groundlang.logic.palette_files import palette_names

    assert "williams2018" in palette_names()  # the folder is read, not a list kept by hand
    assert f"ships ({', '.join(palette_names())};" in PALETTE_HELP


def test_a_state_is_read_with_the_palette_record_a_trained_model_keeps(tmp_path):
    """A model trained on a palette file of one's own reads states without the file: its record will do."""
    from groundlang.corpus import example_corpus_path, read_state_file
    from groundlang.model.palette import Palette
    from groundlang.model.world import WorldError

    record = get_palette("sokoban").record()
    state = read_state_file(example_corpus_path() / "novel_a.state", record)
    assert state.layout.palette == Palette.from_record(record)
    assert [r.colour for r in state.layout.rooms] == ["blue", "green", "red"]
    with pytest.raises(WorldError, match="not a palette's record"):
        read_state_file(example_corpus_path() / "novel_a.state", {"name": "x"})


@pytest.mark.parametrize("change, said", [
    ({"name": 5}, "name: str (not blank)"), ({"name": " "}, "name: str (not blank)"),
    ({"colours": [None] * 13}, "colours: [str]"), ({"colours": ["red"] * 13}, "distinct lowerCamelCase names"),
    ({"shapes": "star"}, "shapes: [str]"), ({"value_classes": {"red": "toy"}}, "value_classes must be"),
    ({"added": "ab"}, "added must be"),
])
def test_a_malformed_palette_record_is_refused_in_one_line_naming_it(change, said):
    from groundlang.corpus import example_corpus_path, read_state_file

    record = {**get_palette("sokoban").record(), **change}
    with pytest.raises(WorldError, match="palette record") as caught:
        read_state_file(example_corpus_path() / "novel_b.state", record)
    assert said in str(caught.value) and "\n" not in str(caught.value)


def test_a_palette_of_the_wrong_type_is_a_type_error_naming_what_is_taken():
    with pytest.raises(TypeError, match="palette must be a name, the path of a .lp file, a Palette or a palette's"):
        get_palette([get_palette("sokoban").record()])


def test_a_palette_may_compute_its_values_with_helpers_a_rule_reads(tmp_path):
    """Only what is neither a palette's fact nor read by a rule is refused: a helper table is a palette's own."""
    path = tmp_path / "computed.lp"
    path.write_text("name(0, red). name(1, blue).\nvalue(colour, I, N) :- name(I, N).\nvalue(shape, 0, star).\n")
    assert get_palette(str(path)).colours == ("red", "blue")
    at = tmp_path / "at.lp"  # an "@" in a glyph's text is no script call (a text check had refused it)
    at.write_text('value(colour, 0, red).\nvalue(shape, 0, star).\nglyph(star, "@").\n')
    assert get_palette(str(at)).glyphs == (("star", "@"),)
    negated = tmp_path / "negated.lp"  # a classically negated helper is a helper too
    negated.write_text("-name(0, red).\nvalue(colour, I, N) :- -name(I, N).\nvalue(shape, 0, star).\n")
    assert get_palette(str(negated)).colours == ("red",)

