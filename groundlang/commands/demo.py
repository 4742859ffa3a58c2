"""``groundlang demo [--out PNG]``: the main job on the example corpus the project ships.

Loads and validates the example corpus, trains the default learner on it,
then follows a command in a layout the corpus never showed, printing the
interpretation and drawing what the agent did.
"""

from __future__ import annotations

import argparse
import time

from groundlang.commands import LANGUAGE_MODEL_NAMES, output_path

DEMO_COMMAND = "take the star to the red room"
DEMO_LAYOUT = "novel_a.state"


def register(subparsers) -> None:
    p = subparsers.add_parser("demo", help="train on the shipped example corpus and follow a command in a new layout",
                              description="Train the default model on the example corpus the package ships (24 "
                                          "commands with demonstrations), follow --command in a layout training "
                                          "never showed, print its readings and the steps taken, and draw them to --out.")
    p.add_argument("--out", default="demo.png", type=output_path, metavar="PNG", help="picture to write (default demo.png)")
    p.add_argument("--command", dest="demo_command", default=DEMO_COMMAND,
                   help=f"the command to follow (default {DEMO_COMMAND!r})")
    p.add_argument("--language-model", default="parse", choices=list(LANGUAGE_MODEL_NAMES),
                   help="language model: bow, ibm2 or parse (default parse)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from groundlang.corpus import example_corpus_path, read_corpus, read_state_file
    from groundlang.grammar.parser import command_fault
    from groundlang.labels import label_coverage, read_labels
    from groundlang.learner import Learner
    from groundlang.logic.atoms import format_goal
    from groundlang.render import ascii_state, check_picture_destination, picture_title, save_picture

    # Before the corpus check and the training, which it would otherwise follow by seconds
    if fault := command_fault(args.demo_command):
        raise ValueError(f"--command: the command {fault}; expected the command's words")
    folder = example_corpus_path()
    check_picture_destination(args.out, reads=[("the example corpus", folder)])
    corpus = read_corpus(folder, "sokoban")
    coverage = label_coverage(corpus, read_labels(folder / "labels.csv"))
    print(f"example corpus: {len(corpus)} instances, {len(corpus.commands())} distinct commands, "
          f"{len(corpus.distinct_layouts())} layout{'s' * (len(corpus.distinct_layouts()) != 1)}; every demonstration replays; "
          f"gold goal holds at the end of {coverage.holding}/{coverage.total}")
    started = time.perf_counter()
    learner = Learner(args.language_model).fit(corpus.instances, progress=args.progress)
    print(f"trained the {args.language_model} model in {time.perf_counter() - started:.1f} s")
    state = read_state_file(folder / DEMO_LAYOUT, "sokoban")
    print(f"\na layout the corpus never showed ({DEMO_LAYOUT}):\n{ascii_state(state)}")
    result = learner.follow(args.demo_command, state)
    print(f"\ncommand: {args.demo_command!r}")
    for goal, p in result.posterior.goals()[:3]:
        print(f"  {p:7.4f}  {format_goal(goal)}")
    print(f"executed {len(result.actions)} steps; goal {format_goal(result.goal)} "
          f"{'reached' if result.reached else 'NOT reached'}")
    save_picture(args.out, state, trajectory=result.states,
                 title=picture_title(args.demo_command, result.goal_words, format_goal(result.goal)))
    print(f"picture written to {args.out}")
    return 0 if result.reached else 1
