"""The ``groundlang`` command line: a thin layer over the library.

Each sub-command lives in ``groundlang/commands/<name>.py`` and provides
``register(subparsers)`` (adds its parser, sets ``func``) and a ``run(args)``
returning an exit code. Errors the library raises on bad input
(``ValueError`` subclasses, ``OSError``) become one line on stderr and exit
code 2; nothing else is caught, so real bugs still show their traceback.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys

# Order is the order of ``groundlang --help``.
COMMANDS = ["check", "show", "tasks", "parse", "irl", "discover"]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="groundlang",
        description="Learn what verbal commands mean from demonstrations, then follow new ones.",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress bars or info logs")
    parser.add_argument("--verbose", action="store_true", help="debug logging")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMANDS:
        importlib.import_module(f"groundlang.commands.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    level = logging.WARNING if args.quiet else (logging.DEBUG if args.verbose else logging.INFO)
    logging.basicConfig(level=level, format="%(message)s")
    try:
        return int(args.func(args) or 0)
    except (ValueError, OSError) as exc:
        print(f"groundlang {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"groundlang {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
