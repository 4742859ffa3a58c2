"""``groundlang follow "COMMAND" --env FILE [--palette NAME] --model MODEL_DIR [--ask [--learn] | --guess] [--out PNG] [--json]``.

Exit codes: 0 the goal was reached; 1 it was not; 2 bad input; 3 the command
was read with confidence below ``--min-confidence`` and nothing was done (the
question is printed; ``--ask`` asks it on the terminal instead). With
``--learn``, an answer is also folded into the model (``Learner.update``) and
the model saved over ``--model``, so that the command is understood next time.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from pathlib import Path

from groundlang.commands import (PALETTE_HELP, add_lexicon_option, add_time_limit_option, as_typed, fraction,
                                 json_text, logged_by_file_names, output_path, positive_int)

# Exit code of a command that asked instead of acting (documented in the README).
ASKED = 3
# What follow's --min-confidence defaults to: groundlang.learner.DEFAULT_MIN_CONFIDENCE (not imported
# here: building the parser stays light; a test checks they agree).
DEFAULT_MIN_CONFIDENCE = 0.7
ANSWER_TRIES = 3
# An answer names one of a few choices ("the blue one", "2"); a longer line is no answer, and reading it
# whole would hold whatever a pipe sends in memory. Its rest is dropped up to a bound: beyond it, an input that
# never ends a line (/dev/zero) is no answer, and would be read forever.
MAX_ANSWER_CHARS = 1000
MAX_DROPPED_CHARS = 1 << 24


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "follow", help="interpret a command in an environment, plan and act (or ask when unsure)",
        description="Interpret COMMAND in the layout of --env with a trained model, plan to end where what it "
                    "means most probably holds, and act. Where that is less likely than --min-confidence, it does "
                    "not act: the competing readings are printed as a question and the exit code is 3.",
    )
    p.add_argument("command_text", metavar="COMMAND", help="the command, in quotes")
    p.add_argument("--env", required=True, metavar="FILE",
                   help="the initial state: a corpus file (*.txt: its first state), a one-line .state file, or a "
                        "one-line .bdm file (a state in the Williams et al. format)")
    p.add_argument("--palette", help=PALETTE_HELP + " (default: the model's, when it was trained on one; a palette file "
                   "of your own is read from the values the model records)")
    p.add_argument("--model", required=True, metavar="MODEL_DIR", help="a folder written by 'groundlang train'")
    p.add_argument("--out", type=output_path, metavar="PNG", help="draw the executed trajectory here (.png, .svg or .pdf; default: no picture)")
    p.add_argument("--top", type=positive_int, default=5, help="how many goals to list with their probabilities (default 5)")
    p.add_argument("--max-steps", type=positive_int, default=200,
                   help="stop acting after this many steps if the goal does not hold by then (default 200)")
    p.add_argument("--min-confidence", type=fraction, default=None, metavar="P",
                   help="ask instead of acting when the confidence (how likely what was meant holds where it would "
                        "end) is below P, 0 to 1 "
                        f"(default {DEFAULT_MIN_CONFIDENCE}, chosen on held-out crowd commands; see README)")
    ask = p.add_mutually_exclusive_group()
    ask.add_argument("--guess", action="store_true",
                     help="act however unsure (what --min-confidence 0 does)")
    ask.add_argument("--ask", action="store_true",
                     help="when unsure, ask on the terminal (stdin) and act on the answer: a number or words "
                          "such as 'the green one' (up to 3 tries; with --json it reports the question instead)")
    p.add_argument("--learn", action="store_true",
                   help="with --ask: learn from the answer (the command means the goal chosen; words the model did "
                        "not know are learned) and save the model over --model, all or nothing (default: the model "
                        "is left as it was)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text (default: text)")
    add_lexicon_option(p)
    add_time_limit_option(p)
    p.set_defaults(func=run)


def _choices_json(result, state, library, names=None) -> list[dict]:
    from groundlang.clarify import option_phrases
    from groundlang.logic.atoms import format_goal, renamed_words

    phrases = option_phrases(result.choices, state, library)
    return [{"number": k, "words": renamed_words(phrase, names), "goal": format_goal(c.goal, names),
             "probability": c.probability}
            for k, (phrase, c) in enumerate(zip(phrases, result.choices), start=1)]


def _print_question(result, state, library, names=None, places: int = 2) -> None:
    from groundlang.logic.atoms import renamed_words

    print(renamed_words(result.question, names))
    for row in _choices_json(result, state, library, names):
        print(f"  {row['number']}) {row['words']}  ({_down(row['probability'], places)}; {row['goal']})")


def _ask(learner, result, state, max_steps: int, names=None):
    """Ask on the terminal until an answer names one choice; None at end of input or after ANSWER_TRIES;
    clarify.Declined where an answer declines what is offered."""
    from groundlang.clarify import AnswerError, Declined
    from groundlang.logic.atoms import renamed_words

    _print_question(result, state, learner.library, names)
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
                return learner.clarify(result, renamed_words(line, {v: k for k, v in (names or {}).items()}),
                                       max_steps=max_steps)
        except Declined as exc:  # asking again would offer what was just declined
            print(f"  {exc}")
            raise
        except AnswerError as exc:
            print(f"  {exc}")
    return None


def _learn(learner, asked, answered, state, model) -> None:
    """Fold the answer into the model and save it over ``model`` (all or nothing: model_io)."""
    # The whole group the answer chose: goals with the same outcome in this layout are one answer.
    chosen = next((c for c in asked.choices if answered.goal in c.goals), answered.goal)
    before = set(learner.vocab.words)
    learner.update(asked.command, state, goal=chosen)
    learner.save(model)
    new = [w for w in learner.vocab.words if w not in before]
    said = f" (new words: {', '.join(repr(w) for w in new)})" if new else ""
    print(f"learned that {asked.command!r} means {answered.goal_words}{said}; model saved to {model}")


def _down(confidence: float, places: int = 2) -> str:
    """A confidence rounded down to ``places``: 0.6999 is not said to be 0.70 and "below 0.7" at once."""
    scale = 10 ** places
    return f"{math.floor(round(confidence * scale, 9)) / scale:.{places}f}"  # round first: 0.29 * 100 is 28.999...


def _places(threshold: float) -> int:
    """As many places as the threshold needs (2 to 6): 0.99 shown against --min-confidence 0.995 said nothing."""
    places = 2
    while places < 6 and round(threshold, places) != threshold:
        places += 1
    return places


def _habits(learner, result, state) -> dict[str, float]:
    """What following left true besides the goal because demonstrations of such goals did (end habits)."""
    if result.abstained or not result.reached or not learner.lm.end_habits or learner.habits is None:
        return {}
    return learner.habits.shown_at(result.goal, state, result.final_state, learner.library, learner.lm.habit_prior,
                                   learner.lm.moved_toys)


def _out_of_reach(result, names) -> str | None:
    """A line on the share of the words' reading conditioning on what can be done took away, if any."""
    from groundlang.logic.atoms import format_goal

    share = result.posterior.out_of_reach
    if share < 0.01 or result.posterior.out_of_reach_goal is None:
        return None
    most = format_goal(result.posterior.out_of_reach_goal, names)
    if result.reason == "unreachable":  # conditioning had nothing to keep: the interpretations above are these
        return f"none of the words' readings can be done from here (the most probable: {most})"
    return (f"{_down(share)} of the words' reading asks for what cannot be done from here (most: {most}); the "
            "interpretations above are what can")


def _already_true(learner, command: str, state) -> tuple[tuple, float] | None:
    """The goal the words most probably ask for, with goals that hold at the start offered too, and its
    probability, where that goal holds at the start: following sets such a goal aside (it asks nothing), so
    without a word the interpretations shown would leave out what was named ("go to the blue room" said in it).
    None for a command with a negated clause: "do not go to the blue room" is read as a task without its
    negation (negation is no task), and what it asks for is not what it says."""
    from groundlang.confidence import goals_held_at_start

    held = learner.posterior(command, state, held=True)
    if any(c.negated for r in held.readings for c in r.logical_form.clauses):
        return None
    return (held.best_goal, held.confidence) if held.best_goal in goals_held_at_start(held) else None


def _print_already_true(done, state, library, names, places: int, settled: bool) -> None:
    from groundlang.wording import labelled_goal

    said = (f"already true here: {labelled_goal(done[0], state, library, names)}; the words most probably "
            f"ask for it ({_down(done[1], places)} of their reading with goals that hold at the start offered too)")
    print(f"{said}: nothing to do" if settled else
          f"{said}, but such a goal asks nothing: the interpretations below are the rest")


def _settled(done, args) -> bool:
    """Whether the words ask for what already holds as surely as acting needs (``--min-confidence``, or
    anyhow with ``--guess``): then nothing is done. Acting on the rest of their reading would do what was
    not asked ("stay in the blue room" said in it had pushed a chair there)."""
    return done is not None and (args.guess or done[1] >= args.min_confidence)


def _nothing_to_do(done, state, library, names, args) -> int:
    """What follow says and writes where the words ask for what already holds: no plan, the start kept."""
    from groundlang.corpus import format_state_like
    from groundlang.logic.atoms import format_goal, renamed_words
    from groundlang.wording import goal_phrase

    if args.out:
        from groundlang.render import picture_title, save_picture

        save_picture(args.out, state, trajectory=[state], title=picture_title(
            args.command_text, renamed_words(goal_phrase(done[0], state, library), names), format_goal(done[0], names)),
            names=names)
    if args.json:
        goal = {"goal": format_goal(done[0], names), "words": renamed_words(goal_phrase(done[0], state, library), names),
                "probability": done[1]}
        print(json_text({"interpretations": [goal], "confidence": done[1], "best_goal_probability": done[1],
                         "margin": None, "out_of_reach": 0.0, "already_true": goal, "abstained": False,
                         "goal": goal["goal"], "goal_words": goal["words"], "actions": [],
                         "final_state": format_state_like(state, args.env, names), "reached": True,
                         "reason": "already true", "habits": {}}))
        return 0
    print("plan (0 steps): (none)")
    if args.out:
        print(f"picture written to {args.out}")
    return 0


def _refuse(result, args) -> None:
    # with --json nothing is asked on the terminal: the question and its choices are in the JSON printed
    how = ("the question and its choices are in the JSON (--ask asks only without --json)" if args.ask and args.json
           else "answer with --ask")
    print(f"groundlang follow: not acting: confidence {_down(result.confidence, _places(args.min_confidence))} is below "
          f"--min-confidence {args.min_confidence!r}; {how}, or act anyway with --guess", file=sys.stderr)


def run(args: argparse.Namespace) -> int:
    from groundlang.corpus import file_names, format_state_like, read_initial_state
    from groundlang.inference.sweeps import plan_once
    from groundlang.learner import Learner
    from groundlang.logic.atoms import format_goal, renamed_words
    from groundlang.logic.palette_files import palette_names
    from groundlang.model.interpretations import NoTaskError
    from groundlang.model.palette import Palette, get_palette
    from groundlang.pair_tasks import tabulation_refusal
    from groundlang.wording import goal_phrase, labelled_goal

    if args.learn and not args.ask:
        raise ValueError("--learn learns from the answer to a question: use it with --ask")
    if args.guess and args.min_confidence is not None:  # it had been dropped without a word
        raise ValueError(f"--guess acts however unsure, so --min-confidence {args.min_confidence!r} would do "
                         "nothing: give one or the other")
    if args.min_confidence is None:
        args.min_confidence = DEFAULT_MIN_CONFIDENCE
    if args.out:
        from groundlang.render import check_picture_destination

        check_picture_destination(args.out)
        if Path(args.model).resolve() in Path(args.out).resolve().parents:
            # a model folder holds the model's files only: saving a model over it would be refused
            raise ValueError(f"--out {args.out}: inside the model folder --model {args.model}, which holds one "
                             "model only; write the picture elsewhere")
    plan_once()  # one command: a compiler pays only where one solve is worth it
    learner = Learner.load(args.model)
    # the library saved in the model, read back before the limit was known: it grounds the layout of --env
    if args.time_limit is not None:
        learner.library.time_limit = args.time_limit
    if args.learn:  # the model is saved after the answer: a folder that cannot take it is refused before asking
        from groundlang.model_io import check_model_destination

        check_model_destination(args.model, "--model")
    palette = args.palette
    if palette is None:
        trained = [p["name"] for p in learner.palettes or ()]
        if len(trained) != 1:
            raise ValueError(f"--palette is needed: the model was trained on {len(trained)} palettes "
                             f"({', '.join(trained) or 'none recorded'})")
        # The model's record of the values is the palette: a file of one's own (even a copy of a shipped one
        # under its name) needs no --palette, and a shipped palette changed since keeps the model's meaning. The
        # name is never opened as a path. The record keeps the drawing hints; for a model saved before it did,
        # a shipped palette of the same values lends its own.
        record = learner.palettes[0]
        palette = Palette.from_record(record)
        if "drawing" not in record and palette.name in palette_names() and get_palette(palette.name) == palette:
            palette = get_palette(palette.name)
    state = read_initial_state(args.env, palette)
    if (too_large := tabulation_refusal(state.layout)) is not None:  # said of the file before anything is grounded
        raise ValueError(f"{args.env}: {too_large}")
    names = file_names(args.env)  # goals and states are shown by the file's names of its objects
    if args.lexicon:
        learner.add_words(args.lexicon)
    threshold = None if args.guess else args.min_confidence
    try:
        with logged_by_file_names(names):
            result = learner.follow(args.command_text, state, max_steps=args.max_steps, min_confidence=threshold)
    except NoTaskError as exc:  # the state is at fault, not the command or the model: name its file
        raise NoTaskError(f"{args.env}: {exc}") from None
    if not args.json:
        print(f"command: {as_typed(args.command_text)}")
    # what the words say of the start, from the model as it was: before an answer is asked for or learned
    done = _already_true(learner, args.command_text, state)
    places = _places(args.min_confidence)
    if done is not None and not args.json:  # before a question, whose choices leave it out
        _print_already_true(done, state, learner.library, names, places, _settled(done, args))
    if _settled(done, args):
        return _nothing_to_do(done, state, learner.library, names, args)
    answered = None
    if result.abstained and args.ask and not args.json:
        from groundlang.clarify import Declined

        try:
            answered = _ask(learner, result, state, args.max_steps, names)
        except Declined:
            print("groundlang follow: the answer declined what was offered; nothing done", file=sys.stderr)
            return ASKED
        if answered is None:
            print("groundlang follow: no answer named a choice; nothing done", file=sys.stderr)
            return ASKED
        if args.learn:
            _learn(learner, result, answered, state, args.model)
        result = answered
    goals = result.posterior.goals()[: args.top]
    if args.out and not result.abstained:
        from groundlang.render import picture_title, save_picture

        save_picture(args.out, state, trajectory=result.states,
                     title=picture_title(args.command_text, renamed_words(result.goal_words, names),
                                         format_goal(result.goal, names)), names=names)
    if args.json:
        data = {
            "interpretations": [{"goal": format_goal(g, names),
                                 "words": renamed_words(goal_phrase(g, state, learner.library), names),
                                 "probability": p} for g, p in goals],
            "confidence": result.confidence,
            "best_goal_probability": result.posterior.confidence,
            "margin": result.posterior.margin,
            "out_of_reach": result.posterior.out_of_reach,
            "already_true": None if done is None else {
                "goal": format_goal(done[0], names), "words": renamed_words(goal_phrase(done[0], state, learner.library),
                                                                            names), "probability": done[1]},
            "abstained": result.abstained,
        }
        if result.abstained:
            data.update(question=renamed_words(result.question, names), choices=_choices_json(result, state, learner.library, names),
                        unknown_words=list(result.unknown_words))
        else:
            data.update(goal=format_goal(result.goal, names), goal_words=renamed_words(result.goal_words, names),
                        actions=[a.word for a in result.actions],
                        final_state=format_state_like(result.final_state, args.env, names),
                        reached=result.reached, reason=result.reason,
                        habits=_habits(learner, result, state))
        print(json_text(data))
        if result.abstained:
            _refuse(result, args)
            return ASKED
        return 0 if result.reached else 1
    print("interpretations:")
    for goal, p in goals:
        print(f"  {p:7.4f}  {labelled_goal(goal, state, learner.library, names)}")
    margin = f"margin {_down(result.posterior.margin, places)} over the next goal that differs"
    if answered is not None:  # what the words alone said, before the answer chose
        print(f"acting on the answer (from the words alone: the most probable goal "
              f"{_down(result.posterior.confidence, places)}, "
              f"{margin})")
    elif result.success is None:
        print(f"confidence {_down(result.confidence, places)} ({margin})")
    else:  # the end is chosen over the whole posterior: how likely what was meant holds there
        print(f"confidence {_down(result.confidence, places)} that what was meant holds where it "
              f"{'ends' if result.reached else 'would end'} (the most probable goal "
              f"{_down(result.posterior.confidence, places)}, {margin})")
    if (beyond := _out_of_reach(result, names)) is not None:
        print(beyond)
    if result.abstained:
        _print_question(result, state, learner.library, names, places)
        _refuse(result, args)
        return ASKED
    print(f"plan ({len(result.actions)} step{'' if len(result.actions) == 1 else 's'}): {', '.join(a.word for a in result.actions) or '(none)'}")
    print(f"goal {labelled_goal(result.goal, state, learner.library, names)}: "
          f"{'reached' if result.reached else 'NOT reached'} ({result.reason})")
    if habits := _habits(learner, result, state):
        print("also true at the end, as in demonstrations of such goals: " + ", ".join(
            f"{relation} ({q:.2f} of them)" for relation, q in habits.items()))
    if args.out:
        print(f"picture written to {args.out}")
    if not result.reached:
        why = ("no state reachable from the start satisfies it, so no plan can carry it out"
               if result.reason == "unreachable" else f"the plan stopped ({result.reason}) before it held")
        print(f"groundlang follow: goal {format_goal(result.goal, names)} not reached: {why}", file=sys.stderr)
        return 1
    return 0
