"""``groundlang lexicon MODEL_DIR``: each word's most probable meanings."""

from __future__ import annotations

import argparse
import json

from groundlang.commands import positive_int


def register(subparsers) -> None:
    p = subparsers.add_parser("lexicon", help="print the learned meanings of words")
    p.add_argument("model", metavar="MODEL_DIR")
    p.add_argument("--top", type=positive_int, default=3, help="meanings per word")
    p.add_argument("--words", nargs="*", help="only these words")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from groundlang.learner import Learner

    lexicon = Learner.load(args.model).lexicon(top=args.top)
    if args.words:
        lexicon = {w: lexicon.get(w, []) for w in args.words}
    if args.json:
        print(json.dumps({w: [[t, p] for t, p in m] for w, m in lexicon.items()}))
        return 0
    for word, meanings in lexicon.items():
        text = ", ".join(f"{token} {p:.2f}" for token, p in meanings) or "(unknown word)"
        print(f"{word:<16} {text}")
    return 0
