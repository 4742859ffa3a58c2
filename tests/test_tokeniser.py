"""The tokeniser (groundlang.grammar.parser): how a command's text becomes words, and what text is no command."""

from __future__ import annotations

import re

import pytest

from groundlang.grammar import parser
from groundlang.grammar.parser import ParseError
from test_grammar_parser import parse, tag, tokenise  # read with the Cleanup World's words, as a learner reads


def test_a_word_typed_with_combining_accents_is_the_word_its_precomposed_spelling_is(tmp_path):
    decomposed, composed = "te\u0301le\u0301", "t\u00e9l\u00e9"
    assert tokenise(f"go to the {decomposed} room") == tokenise(f"go to the {composed} room") == [
        "go", "to", "the", composed, "room"]
    # invisible format characters are no part of a word: a zero-width joiner, a soft hyphen, marks of direction
    assert tokenise("go to the re\u200dd room") == tokenise("go to the gr\u00adeen\u200f room\ufeff")[:3] + ["red", "room"]
    assert tokenise("go to the gr\u00adeen\u200f room\ufeff") == ["go", "to", "the", "green", "room"]
    from groundlang.grammar.word_files import read_word_file
    words = tmp_path / "accents.words"
    words.write_text(f"NOUN: {decomposed}\n", encoding="utf-8")
    assert read_word_file(words) == {"NOUN": (composed,)}
    # full-width letters, as an East Asian keyboard types them, are the letters (every word had been unknown)
    assert tokenise("\uff27\uff2f to the \uff52\uff45\uff44 room") == ["go", "to", "the", "red", "room"]
    words.write_text("NOUN: \uff4d\uff55\uff47\n", encoding="utf-8")
    assert read_word_file(words) == {"NOUN": ("mug",)}


def test_tokeniser_keeps_every_word_and_splits_hyphens_and_clitics():
    assert tokenise("Go to the GREEN-floored room, you're there!") == [
        "go", "to", "the", "green", "floored", "room", ",", "you", "'re", "there", "!"]
    cats = tag(tokenise("go to zorblax"))
    assert cats[2] == frozenset({"ADJ", "NOUN"})
    lf = parse("go to the zorblax")[0].logical_form
    assert "zorblax" in lf.words and lf.tags[lf.words.index("zorblax")] == "ADJ|NOUN"


def test_tokeniser_splits_colour_compounds_written_solid_as_it_does_hyphenated_ones():
    # "bluegreen" was <unk> to a model trained without it; split, its hues name the blue room (ABLATIONS.md).
    assert tokenise("walk into the bluegreen room") == tokenise("walk into the blue-green room") == [
        "walk", "into", "the", "blue", "green", "room"]
    # Only hue + hue: a word that merely starts with a hue, or a hue with a suffix, stays whole.
    assert tokenise("tangerine redo greenish orangey tan") == ["tangerine", "redo", "greenish", "orangey", "tan"]
    lf = parse("go to the greyblue room")[0].logical_form
    assert {"grey", "blue"} <= set(lf.entities[0].modifiers)


@pytest.mark.parametrize("text", ["", "   ", "\n\t  "])
def test_empty_command_is_a_clear_error(text):
    with pytest.raises(ParseError, match="empty"):
        parse(text)
    assert issubclass(ParseError, ValueError)


def test_a_command_without_a_word_is_refused_and_control_characters_are_spaces():
    for text, said in (("?!., ;", "it has no word, only punctuation ('?!., ;')"),
                       ("__ _", "it has no word, only punctuation ('__ _')"),
                       # a command-line argument that is not UTF-8 reaches Python as lone surrogates
                       ("go to the r\udce9d room", "it is not UTF-8 text (byte 0xe9 at character 12)"),
                       ("\x00\x1b \t", "it is empty or only whitespace")):
        with pytest.raises(ParseError, match=re.escape(said)):
            parser.parse(text)
    # a NUL or a terminal's escape is no token (it would become a word of the vocabulary), and no word is cut
    assert parser.tokenise("go\x00 to the\x07 red\x1b[31m room\r") == ["go", "to", "the", "red", "[", "31m", "room"]
    assert parser.parse("go\x00to the red room")[0].logical_form.words == parser.parse("go to the red room")[0].logical_form.words
