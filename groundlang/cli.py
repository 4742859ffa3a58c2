"""The ``groundlang`` command line: a thin layer over the library.

Each sub-command lives in ``groundlang/commands/<name>.py`` and provides
``register(subparsers)`` (adds its parser, sets ``func``) and a ``run(args)``
returning an exit code. Errors the library raises on bad input
(``ValueError`` subclasses, ``OSError``) become one line on stderr and exit
code 2; nothing else is caught, so real bugs still show their traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import os
import sys
import time

from groundlang.commands import report_beside
from groundlang.interrupt import (HeldInterrupt, cache_entry_count, close_progress_bars, interrupts_ignored,
                                  terminate_as_interrupt, what_was_kept)

# Order is the order of ``groundlang --help``.
COMMANDS = ["demo", "check", "show", "parse", "domain", "tasks", "irl", "discover", "train", "follow", "lexicon", "evaluate", "ablate"]
# Commands that fill the cache (behaviour likelihoods, evidence, readings; reported after an interruption).
CACHING_COMMANDS = {"train", "evaluate", "discover", "ablate"}


class _Parser(argparse.ArgumentParser):
    """Bad arguments are one line, as every other bad input is (argparse printed its usage block first);
    ``--help`` still prints the usage. Subcommands' parsers are of this class too."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="groundlang",
        description="Learn what verbal commands mean from demonstrations, then follow new ones.",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress bars or info logs")
    parser.add_argument("--verbose", action="store_true", help="debug logging")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMANDS:
        importlib.import_module(f"groundlang.commands.{name}").register(sub)
    for command in sub.choices.values():  # also after the command ("groundlang train ... --quiet"), as people type it
        command.add_argument("--quiet", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
        command.add_argument("--verbose", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    return parser


def _said(exc: BaseException) -> str:
    """What an error says: an operating-system error as ``path: reason`` (not "[Errno 2] ... 'x.lp'")."""
    if isinstance(exc, OSError) and exc.filename is not None and exc.strerror:
        # a failed rename names the temporary file first; the target is what the user asked for
        return f"{exc.filename2 or exc.filename}: {exc.strerror}"
    return str(exc)


def main(argv: list[str] | None = None) -> int:
    try:  # importing the subcommands takes seconds on a busy machine: an interrupt then is one line too
        with terminate_as_interrupt():
            parser = build_parser()
    except KeyboardInterrupt:
        print("groundlang: interrupted while starting; nothing was written", file=sys.stderr)
        return 130
    args = parser.parse_args(argv)
    for stream in (sys.stdout, sys.stderr):  # a goal's dash or a glyph where the terminal's encoding has none
        with contextlib.suppress(AttributeError, ValueError):  # (PYTHONIOENCODING=ascii): escaped, not an error
            stream.reconfigure(errors="backslashreplace")
    # Progress bars only where a person watches a terminal: quiet in CI, in
    # pipes and under --quiet.
    args.progress = not args.quiet and sys.stderr.isatty()
    level = logging.WARNING if args.quiet else (logging.DEBUG if args.verbose else logging.INFO)
    # The level is groundlang's own: torch's loggers stay at WARNING (at exit it logs its FakeTensor cache
    # statistics at INFO, which are not this run's to show).
    logging.basicConfig(level=logging.WARNING, format="%(message)s")
    logging.getLogger("groundlang").setLevel(level)
    started = time.time()
    caching = args.command in CACHING_COMMANDS
    cache_entries_before = None  # until counted: an interrupt before then cannot tell new entries from old
    try:
        # SIGTERM (a scheduler, `kill`) stops a run the way Ctrl-C does, from the first import of torch on
        # (cache_entry_count's, seconds on a busy machine).
        with terminate_as_interrupt():
            if os.environ.get("GROUNDLANG_MAX_STATES", "").strip():  # a bad value said first, not after a corpus
                from groundlang.model.state_search import default_max_states  # was read (demo checked it first)

                default_max_states()
            cache_entries_before = cache_entry_count(args) if caching else 0  # a bad cache folder is an error line
            json_path = getattr(args, "json", None)  # a path (evaluate, ablate) or a flag (follow, ...)
            with report_beside(json_path if isinstance(json_path, str) else None):
                return int(args.func(args) or 0)
    except BrokenPipeError:
        # The reader went away (`groundlang tasks ... | head`): nothing left to say, to anyone.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except (ValueError, OSError) as exc:
        message = " ".join(_said(exc).splitlines())  # one line, whatever the library said
        if "time_limit" in vars(args) and type(exc).__name__ == "AspTimeout":  # the library names no option
            message += "; --time-limit SECONDS sets it"
        print(f"groundlang {args.command}: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        with interrupts_ignored():
            close_progress_bars()
            kept = what_was_kept(args, started, uses_cache=caching, cache_entries_before=cache_entries_before,
                                 held=isinstance(exc, HeldInterrupt))
            print(f"groundlang {args.command}: interrupted; {kept}", file=sys.stderr)
        return 130


def run() -> None:
    """The ``groundlang`` command: :func:`main`, then the process ends with its code. When a grounding
    that timed out still runs (a layout too large for the time limit), or an interrupt stopped the work
    while native threads ran (torch's, clingo's), the interpreter's normal exit would wait on them or
    crash in their code ("terminate called without an active exception", a Ctrl-C during training): what
    was to be said is written, and what was written is whole, so the process ends at once."""
    from groundlang.logic.program import grounding_left_running

    code = main()
    if code == 130 or grounding_left_running():
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    run()
