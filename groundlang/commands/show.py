"""``groundlang show FILE --palette NAME [--out PNG]``: a corpus file or a ``.state`` file as a picture."""

from __future__ import annotations

import argparse
from pathlib import Path

from groundlang.commands import PALETTE_HELP
from groundlang.corpus import read_instance, read_state_file


def register(subparsers) -> None:
    p = subparsers.add_parser("show", help="draw a corpus file or a .state file (ASCII, and an image with --out)")
    p.add_argument("file", metavar="FILE", help="a corpus file (*.txt) or a one-line .state file")
    p.add_argument("--palette", required=True, help=PALETTE_HELP)
    p.add_argument("--out", metavar="PNG", help="also write an image (.png, .svg or .pdf) with the demonstration drawn")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from groundlang.render import ascii_state, check_picture_destination, save_picture

    if args.out:
        check_picture_destination(args.out)
    path = Path(args.file)
    if path.suffix == ".state":
        state = read_state_file(path, args.palette)
        states, title = [state], path.name
        print(f"state: {path}")
        print(ascii_state(state))
    else:
        inst = read_instance(path, args.palette)
        states, state, title = list(inst.states), inst.initial_state, inst.command
        print(f"command: {inst.command}")
        print(f"steps: {len(inst.actions)} ({','.join(a.word for a in inst.actions)})")
        print("initial state:")
        print(ascii_state(inst.initial_state))
        if inst.actions:
            print("final state:")
            print(ascii_state(inst.final_state))
    if args.out:
        out = save_picture(args.out, state, trajectory=states if len(states) > 1 else None, title=title)
        print(f"wrote {out}")
    return 0
