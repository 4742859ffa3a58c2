"""``groundlang follow "COMMAND" --env FILE --palette NAME --model MODEL_DIR [--out PNG] [--json]``."""

from __future__ import annotations

import argparse
import json
import sys

from groundlang.commands import PALETTE_HELP, add_lexicon_option, positive_int


def register(subparsers) -> None:
    p = subparsers.add_parser("follow", help="interpret a command in an environment, plan and act")
    p.add_argument("command_text", metavar="COMMAND")
    p.add_argument("--env", required=True, metavar="FILE", help="a corpus file or a one-line .state file")
    p.add_argument("--palette", required=True, help=PALETTE_HELP)
    p.add_argument("--model", required=True, metavar="MODEL_DIR")
    p.add_argument("--out", metavar="PNG", help="draw the executed trajectory here")
    p.add_argument("--top", type=positive_int, default=5, help="interpretations to print")
    p.add_argument("--max-steps", type=positive_int, default=200)
    p.add_argument("--json", action="store_true")
    add_lexicon_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from groundlang.corpus import format_state, read_initial_state
    from groundlang.learner import Learner
    from groundlang.logic.atoms import format_goal

    if args.out:
        from groundlang.render import check_picture_destination

        check_picture_destination(args.out)
    state = read_initial_state(args.env, args.palette)
    learner = Learner.load(args.model)
    if args.lexicon:
        learner.add_words(args.lexicon)
    result = learner.follow(args.command_text, state, max_steps=args.max_steps)
    goals = result.posterior.goals()[: args.top]
    if args.out:
        from groundlang.render import save_picture

        save_picture(args.out, state, trajectory=result.states,
                     title=f"{args.command_text}\n-> {format_goal(result.goal)}")
    if args.json:
        print(json.dumps({
            "interpretations": [{"goal": format_goal(g), "probability": p} for g, p in goals],
            "actions": [a.word for a in result.actions],
            "final_state": format_state(result.final_state),
            "reached": result.reached,
            "reason": result.reason,
        }))
        return 0 if result.reached else 1
    print(f"command: {args.command_text}")
    print("interpretations:")
    for goal, p in goals:
        print(f"  {p:7.4f}  {format_goal(goal)}")
    print(f"plan ({len(result.actions)} steps): {', '.join(a.word for a in result.actions) or '(none)'}")
    print(f"goal {format_goal(result.goal)} {'reached' if result.reached else 'NOT reached'} ({result.reason})")
    if args.out:
        print(f"picture written to {args.out}")
    if not result.reached:
        why = ("no state reachable from the start satisfies it, so no plan can carry it out"
               if result.reason == "unreachable" else f"the plan stopped ({result.reason}) before it held")
        print(f"groundlang follow: goal {format_goal(result.goal)} not reached: {why}", file=sys.stderr)
        return 1
    return 0
