"""Asking whether what already holds is meant.

Following sets aside goals that hold at the start: they ask nothing, so acting on one would be no plan at all.
But words may most probably ask for one ("go to the blue room" said in it). Where they do, as surely as acting
needs, :meth:`Learner.follow` asks instead of acting on the rest of the reading: "Do you mean the blue room, as
it is now?". A yes is nothing to do (a plan of no steps, the goal reached); a no is the rest of the reading,
acted on or asked about as following would have (the result's ``otherwise``). Never taken without asking: the
reading of goals that hold is learned from words that never asked for one (demonstrations end elsewhere), so
"leave the blue room" said in it reads as it too.

So, too, where the words say only what not to do ("do not go to the blue room"): negation is no task, so
they are read as what they deny; following asks for a command that says what to do (no choice offered).
"""

from __future__ import annotations

from dataclasses import replace

from groundlang.clarify import (NOT_TO_DO_QUESTION, AnswerError, Declined, choose, competing, named_after_no,
                               number_said, option_phrases, says_only_what_not_to_do)
from groundlang.wording import choice_list
from groundlang.confidence import GoalGroup, goals_held_at_start
from groundlang.logic.atoms import Atom, shown
from groundlang.model.interpretations import NoTaskError
from groundlang.results import FollowResult, Posterior
from groundlang.wording import goal_phrase

__all__ = ["held_reading", "held_question", "held_result", "follow_or_ask", "answer_held"]


def held_reading(held: Posterior) -> tuple[tuple[Atom, ...], float] | None:
    """The goal ``held`` (``Learner.posterior(..., held=True)``) most probably reads its words as, with its
    probability, where that goal holds at the start; None otherwise, and for a command that says only what not
    to do: "do not go to the blue room" is read as a task without its negation (negation is no task), and what
    it asks for is not what it says. A command that also says what to do ("go to the red room, do not go to the
    blue room") is asked about."""
    if says_only_what_not_to_do(held.readings):
        return None
    return (held.best_goal, held.confidence) if held.best_goal in goals_held_at_start(held) else None


def held_question(goal, state, library) -> str:
    """The question whether ``goal``, which holds in ``state``, is what is meant, in words."""
    return f"Do you mean {goal_phrase(goal, state, library)}, as it is now? (yes: nothing to do; no: the rest of the reading)"


def held_result(command: str, state, held: Posterior, reading, otherwise: FollowResult | None,
                library) -> FollowResult:
    """The question whether ``reading`` (:func:`held_reading`'s) is meant, as an abstained result: its one
    choice is that goal; ``otherwise`` is following the rest of the reading (None where nothing else can be
    done in ``state``)."""
    goal, p = reading
    return FollowResult(command, held, goal, [state], [], False, "abstained", abstained=True,
                        question=held_question(goal, state, library), choices=[GoalGroup((goal,), p)],
                        goal_words=goal_phrase(goal, state, library), already_true=True, otherwise=otherwise,
                        held_reading=reading)


def follow_or_ask(command: str, state, held: Posterior | None, min_confidence: float | None, library,
                  follow) -> FollowResult:
    """``follow()`` (following the rest of the reading), or the question whether what already holds is meant
    where ``held``'s words most probably ask for it at least as surely as ``min_confidence`` (None or 0: never
    asked, as acting however unsure asks nothing). Asked also where nothing else can be done (``follow``
    raises NoTaskError): then ``otherwise`` is None."""
    said = held_reading(held) if min_confidence and held is not None else None
    reading = said if said is not None and said[1] >= min_confidence else None
    try:
        otherwise = follow()
    except NoTaskError:
        if reading is None:
            raise
        otherwise = None
    if reading is not None:
        return held_result(command, state, held, reading, otherwise, library)
    if min_confidence and says_only_what_not_to_do(otherwise.posterior.readings):
        # "do not go to the blue room" had walked into the blue room at 0.99: asked, never acted on
        return replace(otherwise, goal=otherwise.posterior.best_goal, states=[state], actions=[], reached=False,
                       reason="abstained", abstained=True, question=NOT_TO_DO_QUESTION, choices=[])
    return otherwise if said is None else replace(otherwise, held_reading=said)  # said by follow, not asked


def answer_held(result: FollowResult, answer: str, library, lexicon, answer_rest=None) -> FollowResult:
    """A held question's answer: taking its choice (its number, its words or a yes) is nothing to do, a plan of
    no steps whose goal holds; declining it is the rest of the reading (``result.otherwise``, as following
    acted on it or asked, with follow's ``max_steps``); a no that names what is meant ("no, the blue room")
    answers the rest's question with ``answer_rest(rest, words)``: the one it asks, or, where it acted, the one
    it would have asked (its competing goals). AnswerError where it
    names nothing; Declined where it declines and nothing else can be done."""
    state = result.states[0]
    rest = result.otherwise
    if (isinstance(answer, str) and answer_rest is not None and rest is not None
            and (named := named_after_no(answer, lexicon))):
        if rest.abstained:
            return answer_rest(rest, named)
        # The rest acted, so it asked nothing: the words after the no choose among what it would have asked
        # about ("no, the green room" had been refused for not naming the held choice, though a bare no acts on
        # the green room).
        asked = replace(rest, states=[state], actions=[], reached=False, reason="abstained", abstained=True,
                        choices=competing(rest.posterior.goal_groups()))
        phrases = option_phrases(asked.choices, state, library)
        if number_said(named, lexicon) is not None or named.strip().isdecimal():  # of a list never shown
            raise AnswerError(f"after a no, say in words what is meant (e.g. no, {phrases[0]}), or answer no alone "
                              f"to act on {phrases[0]}")
        try:
            return answer_rest(asked, named)
        except Declined:
            raise
        except AnswerError:  # its message would name a list, and answers ("1", "yes") of a question not asked
            raise AnswerError(f"{shown(repr(named), limit=60)} names nothing else the words could mean here "
                              f"({choice_list(phrases)}): answer no alone to act on {phrases[0]}, yes to leave "
                              "things as they are") from None
    try:
        chosen = choose(answer, result.choices, state, library, lexicon=lexicon)
    except Declined:
        if result.otherwise is None:
            raise Declined("nothing else can be done here: the words ask for what already holds") from None
        return result.otherwise
    return FollowResult(result.command, result.posterior, chosen.goal, [state], [], True, "goal",
                        goal_words=goal_phrase(chosen.goal, state, library))
