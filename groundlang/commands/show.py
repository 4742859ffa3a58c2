"""``groundlang show FILE [--palette NAME] [--out PNG]``: a corpus file or a one-line state file as a picture."""

from __future__ import annotations

import argparse
from pathlib import Path

from groundlang.bdm import DEFAULT_PALETTE
from groundlang.commands import input_path, PALETTE_HELP, check_state_file, is_burlap_state_file, output_path
from groundlang.corpus import file_names, read_instance, read_state_file


def register(subparsers) -> None:
    p = subparsers.add_parser("show", help="draw a corpus file or a .state file (ASCII, and an image with --out)")
    p.add_argument("file", type=input_path, metavar="FILE", help="a corpus file (*.txt) or a one-line .state or .bdm file (a state "
                   "in the corpus's format, or a BURLAP state line as Williams et al. write them)")
    p.add_argument("--palette", help=PALETTE_HELP + "; required but for a BURLAP state line (default williams2018)")
    p.add_argument("--out", type=output_path, metavar="PNG", help="also write an image (.png, .svg or .pdf) with the demonstration drawn")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from groundlang.render import ascii_state, check_picture_destination, save_picture

    if args.out:
        check_picture_destination(args.out, reads=[("FILE", args.file)])
    path = Path(args.file)
    check_state_file(args.file, "show")
    burlap = is_burlap_state_file(args.file)
    if args.palette is None and not burlap:
        raise ValueError(f"{args.file}: --palette is required for a file in the corpus's format (e.g. --palette sokoban)")
    names = {}
    if path.suffix in (".state", ".bdm"):
        state = read_state_file(path, args.palette or DEFAULT_PALETTE)
        states, title = [state], path.name
        names = file_names(path)  # a BURLAP file's own names (block3, not the layout's block2), drawn as given
        print(f"state: {path}")
        print(ascii_state(state, names))
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
        out = save_picture(args.out, state, trajectory=states if len(states) > 1 else None, title=title, names=names)
        print(f"wrote {out}")
    return 0
