"""Asking instead of guessing: the question for a command read with too little confidence, and its answer.

The question offers the competing goals (groups of goals with the same
outcome) in words. When they differ in one object only, of one class, it
asks for that object ("Which room do you mean: the blue room, the green room
or the red room?"); otherwise it asks for the whole goal. Words of the
command's noun phrases that the model never learned are named first ("I
don't know the word 'purple'."): they are why the words could not decide.

An answer is a number (the choice's place in the list, from 1) or words.
Words choose the choice whose phrase shares the most words with the answer,
counting only words that set the phrases apart ("the green one" picks "the
green room" among rooms; "room" and "the" count for none); words after a negation
in their clause name the choices left out ("not the red one", "red, not blue": see
:func:`_said_and_denied`); when none shares one,
or two tie, the answer is read by the model as a description of the object
asked for ("the tan one" in a model that learned "tan"), and counts only where
its words are themselves evidence for one choice: the reading with them is at
least twice as sure of it against every other choice as the reading without
them was. Words the model never learned ("abc") leave the reading as it was,
and so choose nothing. A question of one choice ("Do you mean the red room?")
also takes a yes; an answer that only declines ("no", "none of them"; to one
choice also "not the red room") raises :class:`Declined`. The words that take,
decline or say nothing are the ``YES``, ``NO`` and ``POLITE`` lines of a word
file (grammar/english.words).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Sequence

from groundlang.confidence import GoalGroup
from groundlang.grammar.lexicon import Lexicon
from groundlang.grammar.parser import tokenise, utf8_fault
from groundlang.logic.atoms import shown
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.phrase_keys import entity_words
from groundlang.model.world import object_class
from groundlang.model.world import State
from groundlang.results import FollowResult
from groundlang.wording import choice_list, goal_phrase, object_phrase

__all__ = ["AnswerError", "Declined", "competing", "unknown_words", "question", "choose", "clear_choice", "number_said"]

# Tokens that end a clause of an answer, and with it what a negation in it denies.
_CLAUSE_ENDS = frozenset({",", ".", ";", ":", "!", "?", "but"})
# A group is offered when it has at least this share of the most probable group's probability.
RELATIVE_FLOOR = 0.1
MAX_CHOICES = 6


class AnswerError(ValueError):
    """An answer that names none of the choices, or several."""


class Declined(AnswerError):
    """An answer that declines every choice ("no", "none of them"): nothing is to be done."""


# Categories of words that carry no choice of their own in an answer ("yes, that one please", "none of them"):
# a word all of whose categories are these says nothing; adverbs say something ("the one on the right"),
# but for the POLITE ones, and so do words with another category too ("next").
_FUNCTION = frozenset({"DET", "PRON", "AUX", "PREP", "TO", "CONJ", "REL", "SUB", "NUM", "COMMA"})


def _says_nothing(word: str, lexicon: Lexicon) -> bool:
    """Whether a word (or a token: "thank_you", "'s") of an answer says nothing of the choice meant. An
    auxiliary does, whatever else it is ("is" is a verb too): "yes it is"."""
    listed = lexicon.listed(word)
    return word in lexicon.polite_words or bool(listed) and (listed <= _FUNCTION or "AUX" in listed)


def says_only_what_not_to_do(readings) -> bool:
    """Whether every reading's clauses that say something are negated ("do not go to the blue room", "never
    enter it"): a task is what to do, and negation is none, so such words were read as what they deny. Not
    for a reading the grammar did not parse whole: its chunks put a negation on the clause it happens to be in
    ("move to the pink room no matter the location" is one negated chunk)."""
    return bool(readings) and all(not r.logical_form.fallback and not any(
        not c.negated and (c.verb is not None or c.args) for c in r.logical_form.clauses) for r in readings)


NOT_TO_DO_QUESTION = ("The words say only what not to do, and I plan for what to do: what should be done? (a "
                      "command that says it)")


def named_after_no(answer: str, lexicon: Lexicon) -> str | None:
    """The words after a leading no that name something, not denied ("no, the blue room": "the blue room"), or
    None: the answer to a question of one choice that declines it and names what is meant instead."""
    tokens = [t for t in tokenise(answer, lexicon) if any(c.isalnum() for c in t)]
    if not tokens or tokens[0] not in lexicon.no_words or any(_negates(t, lexicon) for t in tokens[1:]):
        return None
    return " ".join(tokens[1:]) if _content(tokens[1:], lexicon) else None


def _negates(token: str, lexicon: Lexicon) -> bool:
    """A negation: a word the lexicon lists as ``NEG``, or one ending in the clitic n't (kept whole)."""
    return "NEG" in lexicon.listed(token) or token.endswith("n't")


def _content(tokens, lexicon: Lexicon) -> set[str]:
    """The words of ``tokens`` that say something: whole tokens first ("thank_you", "'s" say nothing), then
    their words ("left_of": "left")."""
    return {w for t in tokens if not _says_nothing(t, lexicon) for w in _words(t) if not _says_nothing(w, lexicon)}


def competing(groups: Sequence[GoalGroup]) -> list[GoalGroup]:
    """The groups worth asking about: those within RELATIVE_FLOOR of the best (at most MAX_CHOICES); none of none."""
    if not groups:
        return []
    top = groups[0].probability
    return [g for g in groups if g.probability >= RELATIVE_FLOOR * top][:MAX_CHOICES]


def unknown_words(readings: Sequence, known: Callable[[str], bool]) -> tuple[str, ...]:
    """Words of the best reading's noun phrases (modifiers and heads) that ``known`` rejects, in order."""
    if not readings:
        return ()
    found: list[str] = []
    for _, modifiers, head in entity_words(readings[0].logical_form):
        for word in (*modifiers, *head):
            if not known(word) and word not in found:
                found.append(word)
    return tuple(found)


def _differing_object(choices: Sequence[GoalGroup]) -> list[str] | None:
    """The one object per choice in which the choices' goals differ, when that is all they differ in."""
    shapes = {tuple((a.predicate, len(a.args)) for a in g.goal) for g in choices}
    if len(shapes) != 1:
        return None
    flat = [[x for a in g.goal for x in a.args] for g in choices]
    differing = [k for k in range(len(flat[0])) if len({f[k] for f in flat}) > 1]
    if not differing:
        return None
    objects = []
    for f in flat:
        here = {f[k] for k in differing}
        if len(here) != 1:
            return None
        objects.append(here.pop())
    if len({object_class(o) for o in objects}) != 1:
        return None
    return objects


def question(choices: Sequence[GoalGroup], unknown: Sequence[str], state: State, library: TaskLibrary) -> str:
    """One line: the unknown words, then which of ``choices`` is meant. ValueError for no choices."""
    if not choices:
        raise ValueError("question: no choices to ask about")
    said = ""
    if unknown:
        # a word file's multiword entry ("coffee_table") is said as it was written
        quoted = choice_list([f"'{w.replace('_', ' ')}'" for w in unknown]).replace(" or ", " and ")
        said = f"I don't know the word{'s' if len(unknown) > 1 else ''} {quoted}. "
    objects = _differing_object(choices)
    if objects is not None:
        phrases = [object_phrase(o, state, library) for o in objects]
        return f"{said}Which {object_class(objects[0])} do you mean: {choice_list(phrases)}?"
    phrases = [goal_phrase(g.goal, state, library) for g in choices]
    return f"{said}Do you mean {choice_list(phrases)}?"


def option_phrases(choices: Sequence[GoalGroup], state: State, library: TaskLibrary) -> list[str]:
    """What each choice is called in the question (an object's phrase or the goal's)."""
    objects = _differing_object(choices)
    if objects is not None:
        return [object_phrase(o, state, library) for o in objects]
    return [goal_phrase(g.goal, state, library) for g in choices]


def _words(text: str) -> set[str]:
    return set(re.findall(r"[a-z0-9]+", text.lower()))


def answer_text(answer, result) -> str:
    """``clarify``'s answer as text (an int is a choice's number), TypeError for arguments of the wrong type."""
    if not isinstance(result, FollowResult):
        raise TypeError(f"clarify: result must be the FollowResult follow() returned, got {type(result).__name__}")
    if isinstance(answer, int) and not isinstance(answer, bool):
        return str(answer)
    if not isinstance(answer, str):
        raise TypeError(f"clarify: answer must be a str (words, or a choice's number) or an int, got "
                        f"{type(answer).__name__}")
    return answer


def choose(answer: str, choices: Sequence[GoalGroup], state: State, library: TaskLibrary,
           read: Callable[[str, Sequence[GoalGroup]], GoalGroup | None] | None = None,
           lexicon: Lexicon | None = None) -> GoalGroup:
    """The choice ``answer`` names: a number from 1, or words (see the module docstring).
    ``read(answer, choices)`` is the model's reading, used when no phrase matches one choice; ``lexicon``
    (default English) the words that take, decline or say nothing (``YES``, ``NO``, ``POLITE``).
    Raises AnswerError naming the choices when the answer names none of them or several, Declined where
    it declines them."""
    lexicon = lexicon or Lexicon.english()
    if not choices:  # a question that offers none ("what should be done?"): a new command answers it
        raise AnswerError("the question offers no choice to answer with: give the command again, saying what to do")
    text = answer.strip()
    if not text:
        raise AnswerError("empty answer: expected a number or words naming one of the choices")
    if fault := utf8_fault(answer):  # read after the command, it was blamed on the command
        raise AnswerError(f"the answer {fault}: expected a number or words naming one of the choices")
    phrases = option_phrases(choices, state, library)
    text = number_said(text, lexicon) or text
    if text.isdecimal():  # int() reads every decimal digit ("٣"), not every digit ("²")
        # int() refuses more than 4300 digits with its own error; no choice has a number that long
        k = int(text) if len(text) <= 18 else None
        if k is None or not 1 <= k <= len(choices):
            raise AnswerError(f"answer {shown(text)}: expected a number from 1 to {len(choices)}")
        return choices[k - 1]
    named = [_words(p) for p in phrases]
    taken = _yes_or_no(text, named[0] if len(choices) == 1 else None, lexicon)
    said_words, denied_words = _said_and_denied(text, lexicon)
    if len(choices) == 1 and taken is None:  # "not the red room": what it denies is the one choice's
        telling = {w for w in named[0] if not _says_nothing(w, lexicon)}
        denied = {w for w in denied_words if not _says_nothing(w, lexicon)}
        taken = False if denied and denied <= telling and not said_words & telling else None
    if taken is False:
        raise Declined(f"{shown(repr(text), limit=60)} declines {'the choice' if len(choices) == 1 else 'every choice'}"
                       ": nothing is done")
    if len(choices) == 1:  # "Do you mean ...?": its number, "yes", or words all of its phrase ("the red room")
        if taken:
            return choices[0]
        raise AnswerError(f"{shown(repr(text), limit=60)} does not name the choice ({phrases[0]}): answer 1, yes or "
                          "its words to act on it, no to decline it")
    # words some phrases have and others lack, and that say something ("to" of "next to" is no side)
    telling = {w for w in set().union(*named) - set.intersection(*named) if not _says_nothing(w, lexicon)}
    words = said_words & telling
    denied = {k for k, n in enumerate(named) if denied_words & telling & n}
    if denied and not words:  # "not the red one": the choices it names are the ones left out
        left = [c for k, c in enumerate(choices) if k not in denied]
        if len(left) == 1:
            return left[0]
        kept = [p for k, p in enumerate(phrases) if k not in denied]
        said = ("leaves out every choice" if not left else
                f"leaves more than one choice ({choice_list(kept)})")
        raise AnswerError(f"{shown(repr(text), limit=60)} says what is not meant and {said}: "
                          f"answer with the number, 1 to {len(choices)}, or the words of the one meant")
    overlap = [0 if k in denied else len(words & n) for k, n in enumerate(named)]  # "red, not blue": red
    best = max(overlap)
    if best > 0 and overlap.count(best) == 1:
        return choices[overlap.index(best)]
    chosen = read(text, choices) if read is not None else None
    if chosen is None:
        how = "names more than one" if best > 0 else "names none"
        raise AnswerError(f"{shown(repr(text), limit=60)} {how} of the choices ({choice_list(phrases)}): "
                          f"answer with their number, 1 to {len(choices)}, or their words")
    return chosen


def _yes_or_no(text: str, offered: set[str] | None, lexicon: Lexicon) -> bool | None:
    """True where the answer takes what a question of one choice offers (``offered``: its phrase's words;
    None for a question of several): a word of ``YES`` (grammar/english.words) or of the phrase, and nothing
    else but words that say nothing of what is meant (:func:`_says_nothing`): "yes please", "yes, the red
    one", "the red room". False where it declines: a word of ``NO`` ("no", "nope", "none of them") and
    nothing else that says something; to a question of one choice also a bare negation ("not that one").
    None otherwise: "no, the red one" is left to the words it names, "the one on the right" to "right".
    AnswerError for an answer of a yes and a no and nothing else ("yes no")."""
    tokens = [t for t in lexicon.join_multiword(tokenise(text)) if _words(t)]
    declining = {t for t in tokens if t in lexicon.no_words}
    negating = {t for t in tokens if _negates(t, lexicon)} - declining
    yes = {t for t in tokens if t in lexicon.yes_words}
    telling = _content([t for t in tokens if t not in yes | declining | negating], lexicon)
    if yes and (declining or negating) and not telling:
        raise AnswerError(f"{shown(repr(text), limit=60)} says both yes ({', '.join(sorted(yes))}) and no "
                          f"({', '.join(sorted(declining | negating))}): answer one or the other")
    if declining or negating:
        return False if not telling and not yes and (declining or offered is not None) else None
    named = {w for w in offered or () if not _says_nothing(w, lexicon)}
    return True if (yes or telling & named) and telling <= named else None


def number_said(text: str, lexicon: Lexicon) -> str | None:
    """The number an answer names a choice by, in digits, where that is all it says: "the third one", "option
    two", "number 2", "2nd please" (``ORDINAL``, ``CHOICE_NOUN`` and ``DET_DEFINITE`` of the word files; polite
    words say nothing); None otherwise ("the red one", "two rooms", "all three", "no 2")."""
    typed = tokenise(text)
    if any(not _words(t) and t not in ".,!?" for t in typed):  # "-1" is no choice's number
        return None
    said = [t for t in typed if _words(t) and t not in lexicon.polite_words and t not in lexicon.choice_nouns]
    tokens = [t for t in said if t not in lexicon.definite_determiners]
    if len(tokens) == 2 and tokens[1] == "one" and tokens[0] != "one":  # "the second one": one, the pronoun
        tokens = tokens[:1]
    if len(tokens) != 1 or (tokens == ["one"] and len(said) > 1):  # "the one" names no number
        return None
    return tokens[0] if tokens[0].isdecimal() else lexicon.ordinals.get(tokens[0])


def _said_and_denied(text: str, lexicon: Lexicon) -> tuple[set[str], set[str]]:
    """The answer's words said of the choice meant, and those a negation denies: a word English lists as a
    negation (``NEG`` of grammar/english.words, or one ending in the clitic n't, which the tokeniser keeps
    whole) denies the words after it up to the clause's end (a comma, a full stop, "but"): "not the red one",
    "the one that isn't red", "red, not blue"; "no, the red one" and "the red one, no?" deny nothing named."""
    said: set[str] = set()
    denied: set[str] = set()
    negating = False
    for token in tokenise(text):
        if token in _CLAUSE_ENDS:
            negating = False
        elif _negates(token, lexicon):
            negating = True
        else:
            (denied if negating else said).update(_words(token))
    return said, denied


def clear_choice(goals: dict, choices: Sequence[GoalGroup], before: dict | None = None) -> GoalGroup | None:
    """The choice at least twice as probable as any other, where ``goals`` maps each goal to its
    probability (the model's reading of the command followed by the answer), or None. With ``before`` (the
    reading of the command alone), only a choice the answer's words made at least twice as likely against
    each other choice as it was without them (a Bayes factor of 2): a reading the answer left as it was
    (words the model never learned) is the question's own doubt, not an answer."""
    mass = [sum(goals.get(g, 0.0) for g in c.goals) for c in choices]
    if not choices or not all(math.isfinite(m) and m >= 0 for m in mass) or not sum(mass) > 0:
        return None  # a reading that gives the choices nothing, or no number, says nothing of them
    order = sorted(range(len(choices)), key=lambda k: -mass[k])
    if len(order) > 1 and mass[order[0]] < 2 * mass[order[1]]:
        return None
    top = order[0]
    if before is not None and len(order) > 1:
        prior = [sum(before.get(g, 0.0) for g in c.goals) for c in choices]
        if any(mass[top] * prior[k] < 2 * prior[top] * mass[k] for k in order[1:]):
            return None
    return choices[top]
