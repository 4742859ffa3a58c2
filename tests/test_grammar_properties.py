"""Property tests for the command parser: any text gives readings or the one clear error for text without a word."""

from __future__ import annotations

import math
import re
import unicodedata

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from groundlang.grammar.parser import ParseError, parse

VOCAB = ("go push the star into to green room and , . n from orange take it walk door left "
         "until you are in blue stop don't with zorblax 4 up - ( ) ' ! without going tan").split()


def check(text: str) -> None:
    try:
        readings = parse(text, max_readings=4)
    except ParseError as exc:  # the one allowed error: no word (whitespace, punctuation, control characters)
        # judged on the text as the tokeniser reads it: control characters as spaces, invisible format characters
        # (a soft hyphen) dropped, Unicode NFKC (which makes some signs combining marks)
        read = unicodedata.normalize("NFKC", "".join(
            " " if unicodedata.category(c) == "Cc" else c for c in text if unicodedata.category(c) != "Cf"))
        assert not re.search(r"[^\W_]", read)
        assert ("empty or only whitespace" if not read.strip() else "has no word, only punctuation") in str(exc)
        return
    assert 1 <= len(readings) <= 4
    assert math.isclose(sum(r.probability for r in readings), 1.0, rel_tol=1e-9)
    assert all(r.probability >= 0 for r in readings)
    for r in readings:
        lf = r.logical_form
        assert isinstance(lf.fallback, bool) and isinstance(lf.paper_str(), str)
        assert len(lf.words) == len(lf.tags)


PROFILE = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@PROFILE
@given(st.text())
def test_any_unicode_text(text):
    check(text)


@PROFILE
@given(st.lists(st.sampled_from(VOCAB), max_size=30).map(" ".join))
def test_word_salad_from_the_domain(text):
    check(text)


@settings(max_examples=10, deadline=None)
@given(st.lists(st.sampled_from(VOCAB), min_size=400, max_size=1500).map(" ".join))
def test_very_long_input(text):
    check(text)


@settings(max_examples=30, deadline=None)
@given(st.text(alphabet=" \t\n\r\u00a0\u2003", max_size=20))
def test_whitespace_only_is_the_clear_error(text):
    check(text)
