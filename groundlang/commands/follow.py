"""``groundlang follow "COMMAND" --env FILE [--other-start FILE ...] [--palette NAME] --model MODEL_DIR [--ask [--learn] | --guess] [--out PNG] [--json]``.

Exit codes: 0 the goal was reached (or, asked, the answer said that what already holds is meant); 1 it
was not; 2 bad input; 3 the command was read with confidence below ``--min-confidence``, or its words
most probably ask for what already holds, and nothing was done (the question is printed; ``--ask`` asks
it on the terminal instead, :mod:`groundlang.commands.asking`). With
``--learn``, an answer is also folded into the model (``Learner.update``) and
the model saved over ``--model``, so that the command is understood next time.
"""

from __future__ import annotations

import argparse
import sys

from groundlang.commands import (input_path, PALETTE_HELP, add_lexicon_option, add_time_limit_option, as_typed, fraction,
                                 json_text, logged_by_file_names, output_path, positive_int)
from groundlang.commands.asking import (already_true, ask, ask_held, choices_json, down, learn_answer, places_for,
                                        print_question)

# Exit code of a command that asked instead of acting (documented in the README).
ASKED = 3
# What follow's --min-confidence defaults to: groundlang.learner.DEFAULT_MIN_CONFIDENCE (not imported
# here: building the parser stays light; a test checks they agree).
DEFAULT_MIN_CONFIDENCE = 0.7


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "follow", help="interpret a command in an environment, plan and act (or ask when unsure)",
        description="Interpret COMMAND in the layout of --env with a trained model, plan to end where what it "
                    "means most probably holds, and act. Where that is less likely than --min-confidence, it does "
                    "not act: the competing readings are printed as a question and the exit code is 3; so it does "
                    "where the words most probably ask for what already holds (is that what is meant?).",
    )
    p.add_argument("command_text", metavar="COMMAND", help="the command, in quotes")
    p.add_argument("--env", required=True, type=input_path, metavar="FILE",
                   help="the initial state: a corpus file (*.txt: its first state), a one-line .state file, or a "
                        "one-line .bdm file (a state in the Williams et al. format)")
    p.add_argument("--other-start", action="append", default=[], type=input_path, metavar="FILE", dest="other_starts",
                   help="another initial state the command was given in, read as --env is (repeatable; a Williams et "
                        "al. command's other layouts): a task that already holds in one of them is not what it asks")
    p.add_argument("--palette", help=PALETTE_HELP + " (default: the model's, when it was trained on one; a palette file "
                   "of your own is read from the values the model records)")
    p.add_argument("--model", required=True, type=input_path, metavar="MODEL_DIR", help="a folder written by 'groundlang train'")
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
                          "such as 'the green one', yes to a question of one choice, no to decline (up to 3 tries; "
                          "with --json it reports the question instead)")
    p.add_argument("--learn", action="store_true",
                   help="with --ask: learn from the answer (the command means the goal chosen; words the model did "
                        "not know are learned) and save the model over --model, all or nothing (default: the model "
                        "is left as it was)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text (default: text)")
    add_lexicon_option(p)
    add_time_limit_option(p)
    p.set_defaults(func=run)


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
    return (f"{down(share)} of the words' reading asks for what cannot be done from here (most: {most}); the "
            "interpretations above are what can")


def _refuse(result, args, done=None) -> None:
    # with --json nothing is asked on the terminal: the question and its choices are in the JSON printed
    how = ("the question and its choices are in the JSON (--ask asks only without --json)" if args.ask and args.json
           else "answer with --ask")
    places = places_for(args.min_confidence)
    if done is not None:  # result: the rest of the reading, None where nothing else can be done
        rest = ("no: the rest of their reading), or act on the rest with --guess" if result is not None else
                "no: nothing else can be done here)")
        print(f"groundlang follow: not acting: the words most probably ask for what already holds ({down(done[1], places)}"
              f"); {how} (yes: nothing to do; {rest}", file=sys.stderr)
        return
    if not result.choices:  # the words say only what not to do: nothing to choose among
        print("groundlang follow: not acting: the words say only what not to do (negation is no task, so they "
              "read as what they deny); give a command that says what to do, or act on that reading with --guess",
              file=sys.stderr)
        return
    print(f"groundlang follow: not acting: confidence {down(result.confidence, places)} is below "
          f"--min-confidence {args.min_confidence!r}; {how}, or act anyway with --guess", file=sys.stderr)


def _answer(asking):
    """What ``asking()`` (a question on the terminal) gave, or None, said, where the answer declined what was
    offered or no answer named a choice: nothing is done then."""
    from groundlang.clarify import Declined

    try:
        taken = asking()
    except Declined:
        print("groundlang follow: the answer declined what was offered; nothing done", file=sys.stderr)
        return None
    if taken is None:
        print("groundlang follow: no answer named a choice; nothing done", file=sys.stderr)
    return taken


def _print_already_true(done, state, library, names, places: int, asked: bool) -> None:
    from groundlang.wording import labelled_goal

    said = (f"already true here: {labelled_goal(done[0], state, library, names)}; the words most probably "
            f"ask for it ({down(done[1], places)} of their reading with goals that hold at the start offered too)")
    # as sure as acting needs, the question comes next: the reading of goals that hold is read from words
    # trained on none, so "leave the blue room" said in it reads as it, and it is asked, never taken
    print(said if asked else f"{said}, but such a goal asks nothing: the interpretations below are the rest")


def _picture(args, state, states, goal_words: str, goal, names) -> None:
    """--out: the states walked, titled with the command and the goal acted on."""
    from groundlang.logic.atoms import format_goal, renamed_words
    from groundlang.render import picture_title, save_picture

    save_picture(args.out, state, trajectory=states, names=names, title=picture_title(
        args.command_text, renamed_words(goal_words, names), format_goal(goal, names)))


def _nothing_to_do(done, state, library, names, args) -> int:
    """Where the answer says that what already holds is what is meant: no plan, the start kept."""
    from groundlang.wording import goal_phrase

    if args.out:
        _picture(args, state, [state], goal_phrase(done[0], state, library), done[0], names)
    print("nothing to do: plan (0 steps): (none)")
    if args.learn:  # the model learns what commands ask for, and this one asks nothing
        print(f"nothing learned: the model at {args.model} is left as it was")
    if args.out:
        print(f"picture written to {args.out}")
    return 0


def _answer_json(learner, result, done, state, names, args, held=None) -> dict:
    """follow's --json answer; ``held``: the result that asks whether what already holds is meant (``result``
    is then the rest of the reading: None where nothing else can be done, and there is none to show)."""
    from groundlang.corpus import format_state_like
    from groundlang.logic.atoms import format_goal, renamed_words
    from groundlang.wording import goal_phrase

    post = None if result is None else result.posterior
    data = {
        "interpretations": [] if post is None else [
            {"goal": format_goal(g, names), "words": renamed_words(goal_phrase(g, state, learner.library), names),
             "probability": p} for g, p in post.goals()[: args.top]],
        "confidence": None if result is None else result.confidence,
        "best_goal_probability": None if post is None else post.confidence,
        "margin": None if post is None else post.margin,
        "out_of_reach": 0.0 if post is None else post.out_of_reach,
        "already_true": None if done is None else {
            "goal": format_goal(done[0], names), "words": renamed_words(goal_phrase(done[0], state, learner.library),
                                                                        names), "probability": done[1]},
        "abstained": held is not None or result.abstained,
    }
    if held is not None:
        data.update(question_kind="already true", question=renamed_words(held.question, names),
                    choices=choices_json(held.choices, state, learner.library, names),
                    unknown_words=list((result or held).unknown_words))
    elif result.abstained:
        data.update(question_kind="readings" if result.choices else "what to do",
                    question=renamed_words(result.question, names),
                    choices=choices_json(result.choices, state, learner.library, names),
                    unknown_words=list(result.unknown_words))
    else:
        data.update(goal=format_goal(result.goal, names), goal_words=renamed_words(result.goal_words, names),
                    actions=[a.word for a in result.actions],
                    final_state=format_state_like(result.final_state, args.env, names),
                    reached=result.reached, reason=result.reason,
                    habits=_habits(learner, result, state))
    return data


def run(args: argparse.Namespace) -> int:
    from groundlang.corpus import file_names, read_initial_state
    from groundlang.inference.sweeps import plan_once
    from groundlang.learner import Learner
    from groundlang.learner_state import check_state
    from groundlang.results import LAYOUT_ERRORS
    from groundlang.logic.atoms import format_goal
    from groundlang.logic.palette_files import palette_names
    from groundlang.model.interpretations import NoTaskError
    from groundlang.model.palette import Palette, get_palette
    from groundlang.wording import labelled_goal

    if args.learn and not args.ask:
        raise ValueError("--learn learns from the answer to a question: use it with --ask")
    if args.guess and args.min_confidence is not None:  # it had been dropped without a word
        raise ValueError(f"--guess acts however unsure, so --min-confidence {args.min_confidence!r} would do "
                         "nothing: give one or the other")
    if args.min_confidence is None:
        args.min_confidence = DEFAULT_MIN_CONFIDENCE
    if args.out:
        from groundlang.render import check_picture_destination

        check_picture_destination(args.out, reads=[("--env", args.env)])  # a model folder's refused there too
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
    other_starts = [read_initial_state(path, palette) for path in args.other_starts]
    for path, other in zip(args.other_starts, other_starts):  # a file that cannot be read is named, as --env is
        try:
            check_state(learner.palettes, "--other-start", args.command_text, other)
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from None
    names = file_names(args.env)  # goals and states are shown by the file's names of its objects
    if args.lexicon:
        learner.add_words(args.lexicon)
    threshold = None if args.guess else args.min_confidence
    try:
        with logged_by_file_names(names):
            result = learner.follow(args.command_text, state, max_steps=args.max_steps, min_confidence=threshold,
                                    other_starts=other_starts)
    except NoTaskError as exc:  # the state is at fault, not the command or the model: name its file
        raise NoTaskError(f"{args.env}: {exc}") from None
    except LAYOUT_ERRORS as exc:  # a layout no method plans in, tabulates or reads: its file
        raise ValueError(f"{args.env}: {exc}") from None
    if not args.json:
        print(f"command: {as_typed(args.command_text)}")
    # The words most probably ask for what already holds, as surely as acting needs (--guess and
    # --min-confidence 0 ask nothing): Learner.follow asks whether that is meant, the rest of the reading aside.
    held = result if result.already_true else None
    # what the words say of the start, from the model as it was: read by Learner.follow where it had a threshold
    done = result.held_reading if threshold else already_true(learner, args.command_text, state)
    if held is not None:
        result = held.otherwise  # None: nothing else can be done
    places = places_for(args.min_confidence)
    if done is not None and not args.json:  # before a question, whose choices leave it out
        _print_already_true(done, state, learner.library, names, places, held is not None)
    if held is not None and (args.json or not args.ask):
        if args.json:
            print(json_text(_answer_json(learner, result, done, state, names, args, held=held)))
        else:
            print_question(held.question, held.choices, state, learner.library, names, places)
        _refuse(result, args, done)
        return ASKED
    answered = None
    if held is not None:  # a no where nothing else can be done declines
        taken = _answer(lambda: ask_held(learner, held, args.max_steps, names, places))
        if taken is None:
            return ASKED
        if taken.goal == held.goal:  # taken: nothing to do
            return _nothing_to_do(done, state, learner.library, names, args)
        if taken is not result:  # "no, the blue room": the rest's question answered too
            answered = taken
            if args.learn:
                learn_answer(learner, result, answered, state, args.model)
            result = taken
        elif args.learn and not result.abstained:  # acted on as read: no answer chose what it means
            print(f"nothing learned: the answer said only what is not meant; the model at {args.model} is left as it was")
    if answered is None and result.abstained and args.ask and not args.json and result.choices:
        answered = _answer(lambda: ask(learner, result, state, args.max_steps, names, places))
        if answered is None:
            return ASKED
        if args.learn:
            learn_answer(learner, result, answered, state, args.model)
        result = answered
    if args.out and not result.abstained:
        _picture(args, state, result.states, result.goal_words, result.goal, names)
    if args.json:
        print(json_text(_answer_json(learner, result, done, state, names, args, )))
        if result.abstained:
            _refuse(result, args)
            return ASKED
        return 0 if result.reached else 1
    print("interpretations:")
    for goal, p in result.posterior.goals()[: args.top]:
        print(f"  {p:7.4f}  {labelled_goal(goal, state, learner.library, names)}")
    margin = f"margin {down(result.posterior.margin, places)} over the next goal that differs"
    if result.abstained and not result.choices:  # read as what they deny: no confidence in what was meant
        print(f"read as what the negation denies (the most probable goal {down(result.posterior.confidence, places)}, "
              f"{margin}): negation is no task")
    elif answered is not None:  # what the words alone said, before the answer chose
        print(f"acting on the answer (from the words alone: the most probable goal "
              f"{down(result.posterior.confidence, places)}, "
              f"{margin})")
    elif result.success is None:
        print(f"confidence {down(result.confidence, places)} ({margin})")
    else:  # the end is chosen over the whole posterior: how likely what was meant holds there
        print(f"confidence {down(result.confidence, places)} that what was meant holds where it "
              f"{'ends' if result.reached else 'would end'} (the most probable goal "
              f"{down(result.posterior.confidence, places)}, {margin})")
    if (beyond := _out_of_reach(result, names)) is not None:
        print(beyond)
    if result.abstained:
        print_question(result.question, result.choices, state, learner.library, names, places)
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
