"""Tests for groundlang.grammar.lexicon: the word files, extending the lexicon, multiword prepositions."""

from __future__ import annotations

import ast
import re
import json
from pathlib import Path

import pytest

from groundlang.cli import main
from groundlang.grammar.lexicon import FILE_CATEGORIES, Lexicon, LexiconError, read_word_file
from groundlang.grammar.parser import parse, tokenise
from groundlang.model.domain_words import domain_lexicon, extra_words

GRAMMAR = Path(__file__).resolve().parents[1] / "grammar"
LOGIC = Path(__file__).resolve().parents[1] / "logic"
CLEANUP = domain_lexicon()


def _entities(command: str, lexicon: Lexicon) -> list[tuple]:
    lf = parse(command, word_lexicon=lexicon)[0].logical_form
    return [(e.prep, e.modifiers, e.head, e.role) for e in lf.entities]


def test_the_english_file_loads_with_every_category_the_parser_reads():
    english = Lexicon.english()
    entries = read_word_file(GRAMMAR / "english.words")
    # hues are the domain's colour names; synonyms a domain's (its layouts' "east" is "right")
    assert set(entries) == set(FILE_CATEGORIES) - {"HUE", "SYNONYM"}
    assert sum(map(len, entries.values())) == 601  # entries of the file (a word may sit in several categories)
    assert english.ordinals["third"] == english.ordinals["3rd"] == "3" and english.choice_nouns == {"number", "option",
                                                                                                  "choice"}
    with pytest.raises(LexiconError, match="ORDINAL entry 'zillionth=0': expected one word and a number from 1 to 99"):
        english.extend({"ORDINAL": ["zillionth=0"]})
    with pytest.raises(LexiconError, match="ORDINAL entry 'twelfth' is not word=number"):
        english.extend({"ORDINAL": ["twelfth"]})
    # a word names one number (a second had been taken or not by sort order); full-width digits are digits
    with pytest.raises(LexiconError, match="ORDINAL 'third' is the number 3 and 4: a word names one number"):
        english.extend({"ORDINAL": ["third=4"]})
    assert english.extend({"ORDINAL": ["dritte=\uff13"]}).ordinals["dritte"] == "3"
    assert english.having_verbs == {"have", "contain", "hold", "include"} <= set(english.entries["VERB"])
    assert english.having_preposition == "with"
    assert english.listed("go") == frozenset({"VERB", "SERIAL"}) and english.listed("going") == frozenset({"GER"})
    assert {"yes", "ok", "sure"} <= english.yes_words and {"no", "nope", "none"} <= english.no_words
    assert english.listed("yes") == frozenset() and english.listed("none") == frozenset()  # answers' words only
    with pytest.raises(LexiconError, match="YES word 'of course' is more than one word"):  # never read whole
        english.extend({"YES": ["of course"]})
    assert english.listed("the") == {"DET"} and english.listed("without") == {"PREP"}
    assert english.listed("up") == {"PREP", "ADV"}  # a particle
    assert english.listed("left") == {"ADJ", "ADV"}  # not the past of "leave": a direction
    assert english.listed("pushed") == {"VERB", "ADJ"} and english.listed("pushing") == {"GER"}
    assert english.lemma("went") == "go" and english.lemma("'re") == "be" and english.lemma("pushes") == "push"
    assert english.negating_prepositions == {"without"}
    assert english.source_and_comitative_prepositions == {"from", "with"}
    assert english.listed("in_front_of") == {"PREP"} and english.listed("next_to") == {"PREP"}


def test_domain_words_are_in_the_domain_file_not_the_english_one():
    english = Lexicon.english()
    for word in ("star", "chair", "backpack", "block", "toy", "green", "beige", "orange", "salmon"):
        assert not english.listed(word), word
        assert CLEANUP.listed(word), word
    assert CLEANUP.listed("star") == {"NOUN"} and CLEANUP.listed("beige") == {"COLOR"}
    assert CLEANUP.split_compound_colour("bluegreen") == ("blue", "green")
    assert english.split_compound_colour("bluegreen") == ("bluegreen",)  # English knows no hues
    # No corpus's typos: unknown, they are guessed, parsed and learned like any unknown word.
    for typo in ("tranfser", "throught", "diagonaly"):
        assert not CLEANUP.listed(typo), typo
    assert CLEANUP.categories("diagonaly") == {"ADV"}  # by its -ly
    # an unknown word opening a clause may be its verb, whatever its ending: read as when it was listed
    assert CLEANUP.categories("tranfser", first=True) == {"ADJ", "NOUN", "VERB"}
    assert CLEANUP.categories("tranfser") == {"ADJ", "NOUN"}
    lf = parse("tranfser to blue retangle .", word_lexicon=CLEANUP)[0].logical_form
    assert lf.paper_str() == "tranfser(retangle1), P1(retangle1, blue)"


def test_lexicon_py_names_no_domain_noun_or_colour_word():
    """grep, with Python's own parser: apart from docstrings (which give examples), no string in
    grammar/lexicon.py is a word of the domain (a noun, a colour) or a list of words; the only words it
    names are categories and suffixes."""
    tree = ast.parse((GRAMMAR / "lexicon.py").read_text(encoding="utf-8"))
    docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                  if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef)) and node.body
                  and isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant)}
    literals = [node.value for node in ast.walk(tree) if isinstance(node, ast.Constant)
                and isinstance(node.value, str) and id(node) not in docstrings]
    cleanup = read_word_file(LOGIC / "cleanup.words")
    domain = {w for words in cleanup.values() for w in words}
    assert {"star", "chair", "block", "green", "beige", "salmon"} <= domain and len(domain) == 58
    words = {w.strip(".,:;()!?'\"`").lower() for text in literals for w in text.split()}
    assert not words & domain
    assert not words & {"tranfser", "throught", "diagonaly", "push", "room", "doorway"}  # nor English words
    # the module lists no words: no literal is a run of more than four lowercase words
    assert max(len(text.split()) for text in literals if text.islower() and text.replace(" ", "").isalpha()) <= 4


def test_multiword_prepositions_are_one_preposition():
    # "left of the sink" lost "left" when read as two words ("go(chair1)": left was dropped)
    assert _entities("go left of the red chair", CLEANUP) == [("left_of", ("red",), "chair", "vpp")]
    assert _entities("go next to the box", CLEANUP) == [("next_to", (), "box", "vpp")]
    assert _entities("stand in front of the door", CLEANUP) == [("in_front_of", (), "door", "vpp")]
    assert _entities("push the star to the left of the door", CLEANUP) == [
        (None, (), "star", "dobj"), ("to_the_left_of", (), "door", "vpp")]
    lf = parse("put the star on top of the chair", word_lexicon=CLEANUP)[0].logical_form
    assert lf.clauses[0].preps == (("on_top_of", "chair1"),)
    # where "left" heads a noun phrase, its words stay apart
    assert tokenise("go to the left of the room", CLEANUP) == ["go", "to_the_left_of", "the", "room"]
    assert tokenise("walk along the left of the room", CLEANUP)[2:5] == ["the", "left", "of"]
    assert tokenise("stop to left of star", CLEANUP) == ["stop", "to", "left", "of", "star"]
    assert tokenise("start in bottom left of orange room", CLEANUP)[3:5] == ["left", "of"]
    assert tokenise("go left of star", CLEANUP) == ["go", "left_of", "star"]


def test_a_users_word_file_adds_a_noun_and_a_multiword_preposition(tmp_path):
    words = tmp_path / "kitchen.words"
    words.write_text("# a kitchen\nNOUN: sink mug\nPREP: left of   # written with a space: two entries\n"
                     "PREP: underneath_of\nHUE: mauve\n", encoding="utf-8")
    before = _entities("put the mug underneath of the mauve sink", CLEANUP)
    assert [e[0] for e in before] == [None, "of"]  # "underneath" lost, as "left" of "left of" was
    lexicon = CLEANUP.with_files(words)
    assert lexicon.listed("mug") == {"NOUN"} and lexicon.listed("underneath_of") == {"PREP"}
    assert lexicon.listed("mauve") == {"COLOR"}
    assert _entities("put the mug underneath of the mauve sink", lexicon) == [
        (None, (), "mug", "dobj"), ("underneath_of", ("mauve",), "sink", "vpp")]
    # the same as data, as a domain schema hands class names and palette values
    data = CLEANUP.extend({"NOUN": ["mug", "sink"], "PREP": ["underneath of"], "HUE": ["Mauve"]})
    assert data.listed("underneath_of") == {"PREP"} and data.listed("mauve") == {"COLOR"}
    assert _entities("put the mug underneath of the mauve sink", data) == _entities(
        "put the mug underneath of the mauve sink", lexicon)
    assert CLEANUP.listed("mug") == frozenset()  # extending gives a new lexicon
    assert extra_words([words, {"NOUN": ["kettle"]}])["NOUN"] == ["sink", "mug", "kettle"]


@pytest.mark.parametrize("text, line, expected", [
    ("NOUN: mug\nmug sink\n", 2, "expected `CATEGORY: word word ...`, got 'mug sink'"),
    ("# fine\n\nNOUNS: mug\n", 3, "unknown category 'NOUNS'"),
    ("NOUN:\n", 1, "no words after NOUN:"),
    ("IRREGULAR: went\n", 1, "IRREGULAR entry 'went' is not form=lemma"),
    ("VERB: go=went\n", 1, "only IRREGULAR, SYNONYM and ORDINAL pair words"),
    # an entry the tokeniser would split at a sign can never be read; a word, a clitic or one sign can
    ("NOUN: mug o'clock 're &\nNOUN: !!!\n", 2, "NOUN word '!!!' is not a word the tokeniser reads"),
    ("NOUN: a_b c-d e.f\n", 1, "NOUN word 'e.f' is not a word the tokeniser reads"),
    # the tokeniser reads a command without invisible format characters: an entry holding one is never read
    ("NOUN: mug\nNOUN: cup\u200b\n", 2, "NOUN word 'cup\\u200b' has an invisible or control character (U+200B)"),
    # a comment may hold a separator str.splitlines would end a line at: the lines are an editor's
    ("# a\u2028comment and\x0cthis\x85too\nNOUN: mug\nmug sink\n", 3, "got 'mug sink'"),
])
def test_a_malformed_word_file_is_one_line_naming_file_and_line(tmp_path, text, line, expected):
    path = tmp_path / "bad.words"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(LexiconError) as caught:
        Lexicon.from_files(path)
    message = str(caught.value)
    assert message.startswith(f"{path}:{line}: ") and expected in message and "\n" not in message
    assert isinstance(caught.value, ValueError)


def test_the_cli_turns_a_malformed_word_file_into_exit_code_2(tmp_path, capsys):
    path = tmp_path / "bad.words"
    path.write_bytes(b"NOUN: mug\nPREP left_of\n")
    assert main(["parse", "go left of the mug", "--lexicon", str(path)]) == 2
    err = capsys.readouterr().err
    assert err == f"groundlang parse: error: {path}:2: expected `CATEGORY: word word ...`, got 'PREP left_of'\n"
    path.write_bytes(b"NOUN: caf\xe9\n")
    assert main(["parse", "go", "--lexicon", str(path)]) == 2
    assert f"{path}: not UTF-8 text" in capsys.readouterr().err
    assert main(["parse", "go", "--lexicon", str(tmp_path / "absent.words")]) == 2
    assert "absent.words: No such file or directory" in capsys.readouterr().err


def test_cli_parse_reads_extra_word_files(tmp_path, capsys):
    path = tmp_path / "kitchen.words"
    path.write_text("NOUN: coffee_table\n", encoding="utf-8")
    assert main(["parse", "--json", "put the star on the coffee table", "--lexicon", str(path)]) == 0
    top = json.loads(capsys.readouterr().out)["readings"][0]["logical_form"]
    assert top == "put(star1, coffeetable1)"  # one word, one variable
    assert main(["parse", "--json", "put the star on the coffee table"]) == 0
    top = json.loads(capsys.readouterr().out)["readings"][0]["logical_form"]
    assert top == "put(star1, table1), P1(table1, coffee)"


def test_cli_parse_reads_a_palettes_names_as_a_learner_trained_on_it_does(tmp_path, capsys):
    """A user's palette with a new shape: "ball" read as a noun, not also as the ball's modifier, as training
    on states of that palette reads it (Learner.observe adds the schema's words)."""
    palette = tmp_path / "toys.lp"
    palette.write_text((LOGIC / "palettes" / "sokoban.lp").read_text() + "value(colour, 13, purple).\n"
                       "value(shape, 5, ball).\n", encoding="utf-8")
    command = "take the purple ball to the red room"
    readings = {}
    for extra in ([], ["--palette", str(palette)]):
        assert main(["parse", "--json", command, *extra]) == 0
        readings[bool(extra)] = [r["logical_form"] for r in json.loads(capsys.readouterr().out)["readings"]]
    assert any("P2(ball1, ball)" in lf for lf in readings[False])
    assert readings[True] == ["take(ball1, room1), P1(ball1, purple), P2(room1, red)",
                              "take(ball1), P1(ball1, purple), P2(room1, red), to(ball1, room1)"]


def test_the_longest_multiword_entry_that_fits_is_joined_and_a_prefix_alone_is_not(tmp_path):
    words = tmp_path / "long.words"
    # "up to the" is no entry, though "up to" and "up to the top of" are
    words.write_text("PREP: up_to up_to_the_top_of\n", encoding="utf-8")
    lexicon = CLEANUP.with_files(words)
    assert lexicon.join_multiword("go up to the top of it".split()) == ["go", "up_to_the_top_of", "it"]
    assert lexicon.join_multiword("go up to the box".split()) == ["go", "up_to", "the", "box"]
    assert lexicon.join_multiword("go up to the top".split()) == ["go", "up_to", "the", "top"]
    # many entries sharing a first word (benchmarks/bench_parse.py times this against the word file's size)
    many = CLEANUP.extend({"PREP": [f"the side{i} of" for i in range(200)]})
    tokens = ["the", "side199", "of"] * 30 + ["the", "side", "of", "the", "box"]
    assert many.join_multiword(tokens) == ["the_side199_of"] * 30 + ["the", "side", "of", "the", "box"]


def test_a_colour_compound_is_cut_only_where_a_hue_ends():
    """A word file's 300,000-letter hue: every cut of a word that long had been tried, each a slice of it
    (hours); cuts only at the hues' lengths (benchmarks/bench_parse.py prints the cost against the length)."""
    hue = "q" * 300_000
    words = CLEANUP.extend({"HUE": [hue]})
    assert words.split_compound_colour(hue + "red") == (hue, "red")
    assert words.split_compound_colour("red" + hue) == ("red", hue)
    assert words.split_compound_colour(hue + "x") == (hue + "x",)
    assert words.split_compound_colour("bluegreen") == ("blue", "green")
    assert words.split_compound_colour("redo") == ("redo",) and words.split_compound_colour("tangerine") == ("tangerine",)


def test_compass_prepositions_join_and_adverbs_before_a_preposition_do_not_split_it():
    """"one spot east of the red chair" says a side as "left of" does; the exception that keeps "left" apart
    after a determiner looks at adjectives and nouns only, so "in front of" and "out of" after a preposition
    or an adjective stay whole ("in" and "out" are adverbs too)."""
    lexicon = Lexicon.english()
    assert lexicon.join_multiword("move to one spot west of the red chair".split())[4] == "west_of"
    assert "east_of" in lexicon.join_multiword("go one spot east of the chair".split())
    assert lexicon.join_multiword("go to in front of the chair".split())[2] == "in_front_of"
    assert lexicon.join_multiword("push star straight out of exit".split())[3] == "out_of"
    assert lexicon.join_multiword("go to the left of the room".split())[1] == "to_the_left_of"


WILLIAMS_WORDS = LOGIC / "domains" / "williams2018.words"


def test_a_synonym_is_read_as_its_word_before_multiword_entries_are_joined():
    """The Williams domain is drawn north up: "east" is read as "right", so "one spot east of the chair"
    is "right of" it and "the west side of" is "the left side of"; English alone keeps the compass words."""
    williams = CLEANUP.with_files(WILLIAMS_WORDS)
    assert williams.synonyms == {"east": ("right",), "west": ("left",), "big": ("large",), "bigger": ("larger",),
                                 "biggest": ("largest",), "tiny": ("small",), "tinier": ("smaller",),
                                 "tiniest": ("smallest",), "little": ("small",)}
    # degrees of size said with other words are the words the superlatives are learned from
    assert tokenise("go to the biggest room", williams)[3] == "largest"
    assert tokenise("go next to the tiny box", williams)[3] == "small"
    assert tokenise("move to one spot east of the red chair", williams)[4] == "right_of"
    assert tokenise("go to the West side of the chair", williams)[1] == "to_the_left_side_of"
    assert tokenise("move to the chair in the northeast room", williams)[-2] == "northeast"
    assert tokenise("move to one spot east of the red chair", CLEANUP)[4] == "east_of"
    lf = parse("move to one spot west of the red chair", word_lexicon=williams)
    assert any("left_of(spot1, chair1)" in str(r.logical_form) for r in lf)


def test_a_users_synonym_may_stand_for_a_multiword_entry_and_is_read_once(tmp_path):
    words = tmp_path / "near.words"
    words.write_text("SYNONYM: beside=next_to alongside=beside\n", encoding="utf-8")
    lexicon = CLEANUP.with_files(words)
    assert tokenise("stand beside the box", lexicon) == ["stand", "next_to", "the", "box"]
    # a word read as another is not read again: "alongside" is "beside", not "next to"
    assert tokenise("stand alongside the box", lexicon) == ["stand", "beside", "the", "box"]
    assert lexicon != CLEANUP  # so the parse cache, keyed by the lexicon, does not serve the old readings


@pytest.mark.parametrize("text, expected", [
    ("SYNONYM: east\n", "SYNONYM entry 'east' is not form=word"),
    ("SYNONYM: north_east=up\n", "the form 'north_east' must be one word"),
    ("SYNONYM: east=a.b\n", "'a.b' is not letters, digits or apostrophes"),
    ("NOUN: east=right\n", "only IRREGULAR, SYNONYM and ORDINAL pair words"),
    ("SYNONYM: east=right east=left\n", "SYNONYM 'east' is read as left here and as right on line 2"),
    # a word read in place of one is a few words: a million would multiply a command's tokens without bound
    ("SYNONYM: x=" + "_".join(["red"] * 9) + "\n", "the word must be at most 8 words"),
    ("SYNONYM: go=.\n", "with a letter or digit"),  # only a sign: the command would have nothing to read
])
def test_a_malformed_synonym_is_one_line_naming_file_and_line(tmp_path, text, expected):
    path = tmp_path / "bad.words"
    path.write_text("NOUN: mug\n" + text, encoding="utf-8")
    with pytest.raises(LexiconError) as caught:
        Lexicon.from_files(path)
    assert str(caught.value).startswith(f"{path}:2: ") and expected in str(caught.value)


def test_one_form_given_two_words_by_two_files_is_refused(tmp_path):
    first, second = tmp_path / "a.words", tmp_path / "b.words"
    first.write_text("SYNONYM: east=right\n", encoding="utf-8")
    second.write_text("SYNONYM: east=left\n", encoding="utf-8")
    with pytest.raises(LexiconError) as caught:
        CLEANUP.with_files(first, second)
    assert str(caught.value) == f"{second}: SYNONYM 'east' is read as left here and as right in the words before"
    assert CLEANUP.with_files(first, first).synonyms == {"east": ("right",)}  # the same pair twice is one


@pytest.mark.parametrize("form", ["it's", ",", "&"])
def test_a_synonym_form_the_tokeniser_splits_or_reads_as_a_sign_is_refused(tmp_path, form):
    """The tokeniser splits "it's" into it 's and reads a sign alone as punctuation: such a form would never
    be read as its word (a comma read as "and" would join clauses the parser keeps apart)."""
    path = tmp_path / "bad.words"
    path.write_text(f"SYNONYM: {form}=and\n", encoding="utf-8")
    with pytest.raises(LexiconError, match="must be one word"):
        Lexicon.from_files(path)
    path.write_text("SYNONYM: don't=not\n", encoding="utf-8")  # kept whole by the tokeniser: read
    assert tokenise("don't go", Lexicon.from_files(path))[0] == "not"


def test_a_synonym_between_colour_compounds_reads_as_the_tokeniser_splits_one(tmp_path):
    """A form is read before a solid colour compound is split, and a word that is one is split after."""
    path = tmp_path / "colours.words"
    path.write_text("HUE: teal\nSYNONYM: aqua=bluegreen bluegreen=teal\n", encoding="utf-8")
    lexicon = CLEANUP.with_files(path)
    assert tokenise("the aqua room", lexicon) == ["the", "blue", "green", "room"]
    assert tokenise("the bluegreen room", lexicon) == ["the", "teal", "room"]
    assert tokenise("the bluegreen room", CLEANUP) == ["the", "blue", "green", "room"]


def test_files_that_read_one_form_as_two_words_are_named_when_a_learner_merges_them(tmp_path):
    first, second = tmp_path / "a.words", tmp_path / "b.words"
    first.write_text("SYNONYM: east=right\n", encoding="utf-8")
    second.write_text("SYNONYM: east=left\n", encoding="utf-8")
    with pytest.raises(LexiconError) as caught:
        extra_words([first, second])
    assert str(caught.value) == f"{second}: SYNONYM 'east' is read as left here and as right in {first}"
    assert extra_words([first, first])["SYNONYM"] == ["east=right"]


def test_words_given_as_data_that_read_one_form_as_two_words_are_refused_citing_the_first():
    with pytest.raises(LexiconError) as caught:
        Lexicon({"SYNONYM": ["east=right", "west=left", "east=left"]})
    assert str(caught.value) == "SYNONYM 'east' is read as left here and as right in the words before"
    assert Lexicon({"SYNONYM": ["east=right", "east=right"]}).synonyms == {"east": ("right",)}


@pytest.mark.parametrize("command", ["train", "evaluate"])
def test_a_synonym_the_domains_word_file_reads_otherwise_names_the_users_file(tmp_path, capsys, command):
    """--lexicon's words reach the learner as data; the clash had been said of "a trained model's own" words."""
    words = tmp_path / "mine.words"
    words.write_text("SYNONYM: big=huge\n", encoding="utf-8")
    small = str(Path(__file__).parent / "fixtures" / "williams2018" / "small.bdm")
    argv = (["train", small, "-o", str(tmp_path / "m")] if command == "train"
            else ["evaluate", "--corpus", small, "--test", small])
    assert main(["--quiet", *argv, "--lexicon", str(words)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"groundlang {command}: error: {words}: SYNONYM 'big' is read as huge here and as large in ")
    assert err.rstrip().endswith("williams2018.words") and "trained model" not in err
    assert not (tmp_path / "m").exists()


def test_a_word_files_closed_class_word_that_is_a_serial_verb_or_degree_word_is_named_by_file_and_line(tmp_path, capsys):
    """"NEG: go" in a user's file had been refused as grammar/english.words' VERB_SERIAL word, naming no file."""
    mine = tmp_path / "mine.words"
    # lines numbered as the file's reader numbers them: a form feed or U+2028 in a comment ends no line
    mine.write_text("NOUN: mug\n# a comment \u2028 \x0c here\nNEG: Go\n", encoding="utf-8")
    assert main(["--quiet", "parse", "--lexicon", str(mine), "go to the mug"]) == 2
    assert capsys.readouterr().err.strip() == (
        f"groundlang parse: error: {mine}:3: NEG word 'go' is a serial verb (VERB_SERIAL) of English or an "
        "earlier word file, an open word: a closed class cannot take it")
    # between two files, whichever comes second is named
    degree, closed = tmp_path / "degree.words", tmp_path / "closed.words"
    degree.write_text("ADV_DEGREE: mighty\n", encoding="utf-8")
    closed.write_text("DET: mighty\n", encoding="utf-8")
    with pytest.raises(LexiconError, match=rf"^{re.escape(str(closed))}:1: DET word 'mighty' is a degree word"):
        extra_words([degree, closed])
    with pytest.raises(LexiconError, match=rf"^{re.escape(str(degree))}:1: ADV_DEGREE word 'mighty' is DET in "
                                           "English or an earlier word file"):
        extra_words([closed, degree])
    assert extra_words([degree])["ADV_DEGREE"] == ["mighty"]  # alone, a degree word of one's own is fine
    # and against English's closed classes, named by the file's line: "to" is no serial verb
    serial = tmp_path / "serial.words"
    serial.write_text("NOUN: mug\nVERB_SERIAL: dash to\n", encoding="utf-8")
    with pytest.raises(LexiconError, match=rf"^{re.escape(str(serial))}:2: VERB_SERIAL word 'to' is PREP, TO in "
                                           "English or an earlier word file, a closed class: a serial verb is an open"):
        extra_words([serial])


def test_word_files_together_are_bounded(tmp_path, monkeypatch):
    """Each file's size was bounded, not how many files: three of 400,000 verbs each took 3.5 GB."""
    import groundlang.model.domain_words as domain_words

    monkeypatch.setattr(domain_words, "MAX_WORDS", 8)
    first, second = tmp_path / "a.words", tmp_path / "b.words"
    first.write_text("VERB: blick\nNOUN: mug cup\n", encoding="utf-8")  # a verb weighs its four forms: 6
    second.write_text("NOUN: jar pot urn\n", encoding="utf-8")
    assert extra_words([first, first])["NOUN"] == ["mug", "cup"]  # the same words again count once
    with pytest.raises(LexiconError, match=rf"^{re.escape(str(second))}: word files of 9 words together, a verb "
                                           "counted as its 4 forms; at most 8"):
        extra_words([first, second])
    second.write_text("VERB: glorp frob\nNOUN: jar\n", encoding="utf-8")
    with pytest.raises(LexiconError, match=rf"^{re.escape(str(second))}: a word file of 9 words, a verb"):
        extra_words([second])
    # a saved model's words (data) are weighed before a lexicon is built of them
    with pytest.raises(LexiconError, match=r"^words given as data: 12 words, a verb counted as its 4 forms; at most 8"):
        extra_words([{"VERB": ["a", "b", "c"]}])


def test_a_verb_of_having_is_a_verb_and_one_preposition_reads_such_a_clause(tmp_path):
    """VERB_HAVING words not listed under VERB were no verbs (their clauses went unread), and a second PREP_HAVING
    word was dropped for the alphabetically first."""
    own = Lexicon.english().extend({"VERB_HAVING": ["own"]})
    assert own.listed("owns") == {"VERB"} and "own" in own.having_verbs
    with pytest.raises(LexiconError, match=r"^PREP_HAVING lists 2 words \(near, with\); expected one"):
        Lexicon.english().extend({"PREP_HAVING": ["near"]})
    mine = tmp_path / "mine.words"
    mine.write_text("NOUN: mug\nPREP_HAVING: near\n", encoding="utf-8")
    with pytest.raises(LexiconError, match=rf"^{re.escape(str(mine))}:2: PREP_HAVING word 'near': a clause of "
                                           "having reads as one preposition, and English or an earlier word file says "
                                           "'with'"):
        extra_words([mine])
    mine.write_text("PREP_HAVING: with\n", encoding="utf-8")  # the same one again is no conflict
    assert extra_words([mine]) == {"PREP_HAVING": ["with"]}


def test_a_word_files_ordinal_of_another_number_is_named_by_file_and_line(tmp_path):
    mine = tmp_path / "mine.words"
    mine.write_text("NOUN: mug\nORDINAL: third=4\n", encoding="utf-8")
    with pytest.raises(LexiconError, match=rf"^{re.escape(str(mine))}:2: ORDINAL 'third' is the number 4 here and 3 in "
                                           "English or an earlier word file"):
        extra_words([mine])


def test_a_form_of_two_verbs_is_refused_in_a_file_across_files_and_against_english(tmp_path):
    """IRREGULAR entries were sorted and the last kept: "zoomt=go zoomt=push" read "zoomt" as push, whatever the
    order written, and a user's "went=come" lost to English's "went=go" without a word."""
    mine, other = tmp_path / "mine.words", tmp_path / "other.words"
    mine.write_text("NOUN: mug\nIRREGULAR: zoomt=go zoomt=push\n", encoding="utf-8")
    with pytest.raises(LexiconError, match=rf"^{re.escape(str(mine))}:2: IRREGULAR 'zoomt' is a form of 'push' here and "
                                           "of 'go'"):
        extra_words([mine])
    mine.write_text("IRREGULAR: zoomt=go\n", encoding="utf-8")
    other.write_text("IRREGULAR: zoomt=push\n", encoding="utf-8")
    with pytest.raises(LexiconError, match=rf"^{re.escape(str(other))}:1: IRREGULAR 'zoomt'"):
        extra_words([mine, other])
    other.write_text("IRREGULAR: went=come\n", encoding="utf-8")
    with pytest.raises(LexiconError, match=rf"^{re.escape(str(other))}:1: IRREGULAR 'went' is a form of 'come' here "
                                           "and of 'go'"):
        extra_words([other])
    with pytest.raises(LexiconError, match="IRREGULAR 'zoomt' is a form of 'go' and of 'push': a form is of one verb"):
        Lexicon.english().extend({"IRREGULAR": ["zoomt=push", "zoomt=go"]})
    assert extra_words([mine]) == {"IRREGULAR": ["zoomt=go"]} and Lexicon.english().extend(
        {"IRREGULAR": ["zoomt=go", "went=go"]}).lemma("zoomt") == "go"  # the same pair again is no conflict
