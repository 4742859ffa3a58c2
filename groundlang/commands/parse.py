"""``groundlang parse``: print the logical forms of commands with their probabilities.

    groundlang parse "push the star into the green room" [--json]
    groundlang parse --file commands.txt          # every non-empty line
    groundlang parse --file CORPUS_DIR            # the first line of every *.txt file below the folder
    groundlang parse --file part1.bdm             # the commands of a .bdm file (or a folder of them)
    groundlang parse --library williams2018 "stand left of the red chair"   # with the library's word file

With ``--file`` a summary follows: how many commands got a full parse, how many only the fallback.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from groundlang.commands import (LIBRARY_NAMES, input_path, add_lexicon_option, add_time_limit_option, as_typed, json_text,
                                 library_given, library_path, positive_int)
from groundlang.corpus import MAX_FILE_BYTES as MAX_CORPUS_FILE_BYTES
from groundlang.grammar.parser import ParseError, command_fault, parse, typed_words
from groundlang.logic.storage import read_limited
from groundlang.state_line import is_state_line, text_lines, utf8_text


def register(subparsers) -> None:
    p = subparsers.add_parser("parse", help="parse commands into logical forms with probabilities",
                              description=__doc__.replace("``", ""), formatter_class=argparse.RawDescriptionHelpFormatter)
    # dest "text": the CLI keeps the sub-command's name in args.command
    p.add_argument("text", nargs="?", metavar="COMMAND", help="the command to parse (quote it)")
    p.add_argument("--file", type=lambda text: Path(input_path(text)),
                   help="a text file (one command per line), a corpus file or folder (each file's first line), "
                        "or a .bdm file or folder (its commands)")
    p.add_argument("--json", action="store_true", help="one JSON object per command")
    p.add_argument("--max-readings", type=positive_int, default=8, help="readings kept per command (default 8)")
    add_lexicon_option(p)
    p.add_argument("--library", metavar="LP", action="append", type=library_path,
                   help="task library .lp file (repeatable): the words of its word file (mine.words beside "
                        "mine.lp) join the parser's, as a learner trained with it reads them" + LIBRARY_NAMES)
    p.add_argument("--palette", help="a palette (a name or a .lp file): its colour and shape names join the "
                                     "parser's words, as a learner trained on states of it reads them")
    add_time_limit_option(p, "stop grounding/solving the --library files after this long (default 10): parse reads "
                             "no layout, only their words and their checks")
    p.set_defaults(func=run)


# One command a line; the crowd corpus's 480 commands take 30 KB.
MAX_COMMANDS_BYTES = 16 * 2**20


def _commands(path: Path) -> list[tuple[str, str]]:
    """(source, command) pairs: the commands of a .bdm file or folder, first lines of a corpus folder's files
    or of one corpus file, or a file's non-empty lines."""
    from groundlang.bdm import bdm_files, command_texts

    if found := bdm_files(path):  # a state line or "---" read as a command would count as one
        return [(f"{f}:{line}", text) for f in found for line, text in command_texts(f)]
    if path.is_dir():
        files = sorted(p for p in path.rglob("*.txt") if p.is_file())
        if not files:
            raise ValueError(f"{path}: no *.txt command files in this folder")
        out = []
        for f in files:
            text = utf8_text(read_limited(f, MAX_CORPUS_FILE_BYTES, "a corpus file"), f)
            out.append((str(f), text_lines(text)[0].strip()))
        return out
    lines = text_lines(utf8_text(read_limited(path, MAX_COMMANDS_BYTES, "a file of commands"), path))
    if any(map(is_state_line, lines[1:])):  # one corpus file: its command is its first line
        return [(f"{path}:1", lines[0].strip())]
    return [(f"{path}:{i}", line.strip()) for i, line in enumerate(lines, 1) if line.strip()]


def run(args: argparse.Namespace) -> int:
    if (args.text is None) == (args.file is None):
        raise ValueError("give either a COMMAND or --file FILE_OR_CORPUS_DIR (exactly one)")
    from groundlang.grammar.parser import READING_LIMIT

    if not 1 <= args.max_readings <= READING_LIMIT:  # each reading widens every node's beam: time and memory
        raise ValueError(f"--max-readings {args.max_readings}: expected 1 to {READING_LIMIT} readings per command")
    from groundlang.model.domain_words import domain_lexicon, extra_words

    # the words a learner parses with: English, the Cleanup World's, the library's word files, --lexicon files
    from groundlang.training_vocabulary import word_files_beside

    library = library_given(args)
    beside = word_files_beside(library) if library is not None else []
    words = domain_lexicon(extra_words([*beside, *args.lexicon]))
    if args.palette:
        from groundlang.logic.tasks import TaskLibrary
        from groundlang.model.palette import get_palette
        from groundlang.training_vocabulary import unlisted_schema_words

        words = words.extend(unlisted_schema_words(library or TaskLibrary.load(), [get_palette(args.palette)], words))
    items = [("argument", args.text)] if args.file is None else _commands(args.file)
    full = fallback = empty = 0
    for source, command in items:
        fault = command_fault(command)
        if fault:
            if args.file is None:
                raise ParseError(f"cannot parse the command: it {fault}")
            empty += 1
            print(f"{source}: the command {fault}, skipped", file=sys.stderr)
            continue
        readings = parse(command, max_readings=args.max_readings, word_lexicon=words)
        if readings[0].logical_form.fallback:
            fallback += 1
        else:
            full += 1
        tokens = readings[0].logical_form.words
        if args.json:
            print(json_text({"command": command, "words": list(tokens), "readings": [r.to_json() for r in readings]}))
        else:
            print(as_typed(command))  # an escape sequence in it would act on the terminal, as follow's would
            if list(tokens) != typed_words(command):  # a multiword entry joined, a synonym read: say how
                print(f"  read as: {as_typed(' '.join(tokens))}")
            for r in readings:
                mark = "  [fallback]" if r.logical_form.fallback else ""
                print(f"  {r.probability:.3f}  {r.logical_form.paper_str()}{mark}")
    if args.file is not None:
        total = full + fallback
        summary = (f"{total} command{'s' * (total != 1)}: {full} full parse, {fallback} fallback only"
                   + (f", {empty} without words skipped" if empty else ""))
        print(summary, file=sys.stderr if args.json else sys.stdout)
    return 0
