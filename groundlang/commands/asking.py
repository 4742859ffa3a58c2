"""What ``groundlang follow`` asks on the terminal, and how it reads the answers.

Two questions: the competing readings of a command read with too little confidence (``Learner.clarify``
takes the answer), and, where the words most probably ask for what already holds, whether that is what is
meant (yes: nothing to do; no: the rest of their reading is acted on or asked about). Answers are read a
line at a time, bounded, up to ANSWER_TRIES; an answer that declines the readings ends the asking.
"""

from __future__ import annotations

import contextlib
import math
import sys

from groundlang.commands import as_typed, logged_by_file_names

ANSWER_TRIES = 3
# An answer names one of a few choices ("the blue one", "2"); a longer line is no answer, and reading it
# whole would hold whatever a pipe sends in memory. Its rest is dropped up to a bound: beyond it, an input that
# never ends a line (/dev/zero) is no answer, and would be read forever.
MAX_ANSWER_CHARS = 1000
MAX_DROPPED_CHARS = 1 << 24


def down(confidence: float, places: int = 2) -> str:
    """A confidence rounded down to ``places``: 0.6999 is not said to be 0.70 and "below 0.7" at once."""
    scale = 10 ** places
    return f"{math.floor(round(confidence * scale, 9)) / scale:.{places}f}"  # round first: 0.29 * 100 is 28.999...


def places_for(threshold: float) -> int:
    """As many places as the threshold needs (2 to 6): 0.99 shown against --min-confidence 0.995 said nothing."""
    places = 2
    while places < 6 and round(threshold, places) != threshold:
        places += 1
    return places


def choices_json(choices, state, library, names=None) -> list[dict]:
    from groundlang.clarify import option_phrases
    from groundlang.logic.atoms import format_goal, renamed_words

    phrases = option_phrases(choices, state, library)
    return [{"number": k, "words": renamed_words(phrase, names), "goal": format_goal(c.goal, names),
             "probability": c.probability}
            for k, (phrase, c) in enumerate(zip(phrases, choices), start=1)]


def print_question(question: str, choices, state, library, names=None, places: int = 2) -> None:
    from groundlang.logic.atoms import renamed_words

    print(renamed_words(question, names))
    for row in choices_json(choices, state, library, names):
        print(f"  {row['number']}) {row['words']}  ({down(row['probability'], places)}; {row['goal']})")


def read_answers(take, names=None, declined: str | None = None):
    """``take(answer)`` of each line read from stdin until it returns (an AnswerError is said and the next line
    read); None at end of input or after ANSWER_TRIES; clarify.Declined where an answer declines (said, or
    ``declined`` said instead)."""
    from groundlang.clarify import AnswerError, Declined
    from groundlang.logic.atoms import renamed_words

    stdin = sys.stdin  # None where the process was started with stdin closed: no answer can come
    with contextlib.suppress(AttributeError, ValueError):  # bytes that are not UTF-8 reach the answer as lone
        stdin.reconfigure(errors="surrogateescape")       # surrogates (said, asked again), not a decode error
    for _ in range(ANSWER_TRIES):
        print("answer> ", end="", flush=True)
        line = stdin.readline(MAX_ANSWER_CHARS + 1) if stdin is not None else ""
        if not line:
            print()
            return None
        if len(line) > MAX_ANSWER_CHARS and not line.endswith("\n"):
            dropped = 0  # the rest of the line, read in bounded pieces and dropped, up to a bound: an input
            while (rest := stdin.readline(1 << 16)) and not rest.endswith("\n"):  # of no line end (/dev/zero)
                dropped += len(rest)                                             # would be read forever
                if dropped > MAX_DROPPED_CHARS:
                    print(f"\n  no line end within {MAX_DROPPED_CHARS:,} characters: no answer")
                    return None
            print(f"\n  an answer is at most {MAX_ANSWER_CHARS} characters: a choice's number or its words")
            continue
        if not stdin.isatty():  # a piped answer is not echoed by a terminal: show what was read, as the
            print(as_typed(line.strip()))  # command is shown
        try:  # the choices were shown with the file's names: the answer is read with the layout's
            with logged_by_file_names(names or {}):
                return take(renamed_words(line, {v: k for k, v in (names or {}).items()}))
        except Declined as exc:  # asking again would offer what was just declined
            print(f"  {declined or exc}")
            raise
        except AnswerError as exc:
            print(f"  {exc}")
    return None


def ask(learner, result, state, max_steps: int, names=None, places: int = 2):
    """Ask the question of an abstained ``result`` until an answer names one choice: the result of acting on
    it; None at end of input or after ANSWER_TRIES; clarify.Declined where an answer declines."""
    print_question(result.question, result.choices, state, learner.library, names, places)
    return read_answers(lambda answer: learner.clarify(result, answer, max_steps=max_steps), names)


def learn_answer(learner, asked, answered, state, model) -> None:
    """Fold the answer into the model and save it over ``model`` (all or nothing: model_io)."""
    # The whole group the answer chose: goals with the same outcome in this layout are one answer.
    chosen = next((c for c in asked.choices if answered.goal in c.goals), answered.goal)
    before = set(learner.vocab.words)
    learner.update(asked.command, state, goal=chosen)
    learner.save(model)
    new = [w for w in learner.vocab.words if w not in before]
    said = f" (new words: {', '.join(repr(w) for w in new)})" if new else ""
    print(f"learned that {asked.command!r} means {answered.goal_words}{said}; model saved to {model}")


def already_true(learner, command: str, state) -> tuple[tuple, float] | None:
    """What the words most probably ask for where it holds at the start, with its probability
    (:func:`groundlang.held_question.held_reading`), said beside what following does."""
    from groundlang.held_question import held_reading

    return held_reading(learner.posterior(command, state, held=True))


def ask_held(learner, held, max_steps: int, names=None, places: int = 2):
    """Ask ``held``'s question, whether the goal that already holds is what is meant: the result of the answer
    (:meth:`Learner.clarify`: a yes is nothing to do, a no ``held.otherwise``, the rest of the reading); None
    where no answer named a choice; clarify.Declined where a no leaves nothing else to do (said)."""
    print_question(held.question, held.choices, held.states[0], learner.library, names, places)

    def take(answer):
        taken = learner.clarify(held, answer, max_steps=max_steps)
        if taken is held.otherwise:
            print("  not what holds now: the rest of the reading")
        return taken

    return read_answers(take, names)
