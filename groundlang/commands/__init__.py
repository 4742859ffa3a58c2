"""Sub-commands of the ``groundlang`` CLI, one module each (see groundlang/cli.py).

Names the parsers need are kept here, free of torch, so that building the
parser (``groundlang --help``) imports nothing heavy; a test checks that they
match the library's.
"""

import argparse
import contextlib
import json
import logging
import math
import os
import re
import stat
import sys
from pathlib import Path

from groundlang.logic.palette_files import palette_names
from groundlang.logic.storage import file_kind
from groundlang.logic.sources import library_names

LANGUAGE_MODEL_NAMES = ("bow", "ibm2", "parse")  # == tuple(groundlang.model.language_models.LANGUAGE_MODELS)


def _whole(text: str, least: int, what: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, not {text!r}") from None
    if value < least:
        raise argparse.ArgumentTypeError(f"expected {what}, not {text!r}")
    return value


def output_path(text: str) -> str:
    """An argparse type: the path of a file or folder to write; an empty one is refused (it was taken for
    no output at all, and the run wrote nothing)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an empty path; expected where to write")
    if text == "-":  # read elsewhere as standard output, here it had written a file named "-"
        raise argparse.ArgumentTypeError("'-' is no file here; name the file to write (a command's report "
                                         "goes to standard output already)")
    return text


def input_path(text: str) -> str:
    """An argparse type: the path of a file or folder to read; an empty one is refused (it was read as the
    current folder: a corpus of whatever lay there)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an empty path; expected a file or folder to read")
    return text


def library_path(text: str) -> str:
    """An argparse type: a task library (a .lp file, or a library the package ships by name); an empty one
    is refused (it was taken for the current folder: "Is a directory")."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an empty path; expected a .lp file or a library the package ships by name")
    return text


def positive_int(text: str) -> int:
    """An argparse type: a whole number of 1 or more (workers, steps, counts)."""
    return _whole(text, 1, "a whole number of 1 or more")


def fold_count(text: str) -> int:
    """An argparse type: 2 to MAX_FOLDS folds of a pair corpus ("--folds 0" had been told 1 or more, and 1 was
    then refused)."""
    from groundlang.pair_folds import MAX_FOLDS

    what = f"a whole number of folds from 2 to {MAX_FOLDS}"
    value = _whole(text, 2, what)
    if value > MAX_FOLDS:
        raise argparse.ArgumentTypeError(f"expected {what}, not {text!r}")
    return value


def seed(text: str) -> int:
    """An argparse type: a random seed, 0 to 2**32 - 1 (what numpy and torch accept)."""
    value = _whole(text, 0, "a seed from 0 to 4294967295")
    if value > 2**32 - 1:
        raise argparse.ArgumentTypeError(f"expected a seed from 0 to 4294967295, not {text!r}")
    return value


def _real(text: str, low: float, high: float, low_included: bool, what: str) -> float:
    try:
        value = float(text)  # "nan" compares false below, "inf" exceeds high
    except ValueError:
        value = math.nan
    if not ((low <= value if low_included else low < value) and value <= high):
        raise argparse.ArgumentTypeError(f"expected {what}, not {text!r}")
    return value


def positive_seconds(text: str) -> float:
    """An argparse type: seconds above 0 and at most 10**6 (clingo's time limits; the bound is
    groundlang.logic.program.MAX_TIME_LIMIT, not imported here: building the parser stays light)."""
    return _real(text, 0, 10**6, False, "seconds above 0 and at most 1000000")


def open_fraction(text: str) -> float:
    """An argparse type: a number strictly between 0 and 1 (a share to hold out)."""
    value = _real(text, 0, 1, False, "a number strictly between 0 and 1")
    if value >= 1:
        raise argparse.ArgumentTypeError(f"expected a number strictly between 0 and 1, not {text!r}")
    return value


def fraction(text: str) -> float:
    """An argparse type: a number from 0 to 1."""
    return _real(text, 0, 1, True, "a number from 0 to 1")


def add_language_model_settings(parser) -> None:
    """``--lm-setting KEY=VALUE`` (repeatable): a keyword of the language model, for ablations."""
    parser.add_argument(
        "--lm-setting", metavar="KEY=VALUE", action="append", default=[], dest="lm_settings",
        help="a setting of the language model, e.g. mention_phrases=any or argument_bonus=0 (repeatable; "
             "VALUE is read as JSON: numbers, true, false, null, else text)",
    )


def language_model_settings(pairs: list[str]) -> dict:
    """``["argument_bonus=0", "mention_phrases=any"]`` -> ``{"argument_bonus": 0, "mention_phrases": "any"}``.
    Raises ValueError for an item without ``=`` or a value nested too deeply to read."""
    from groundlang.model.language_models import setting_value

    settings = {}
    for pair in pairs:
        key, sep, text = pair.partition("=")
        text = text.strip()
        if not sep or not key.strip():
            raise ValueError(f"--lm-setting {pair!r}: expected KEY=VALUE, e.g. mention_phrases=any")
        try:
            settings[key.strip()] = setting_value(text)
        except ValueError as exc:
            raise ValueError(f"--lm-setting {key.strip()}={exc}") from None
    return settings


def add_em_acceleration_option(parser) -> None:
    """``--em-acceleration {squarem,none}``: how the fit chains EM steps (both reach the same MAP)."""
    parser.add_argument("--em-acceleration", choices=["squarem", "none"], default="squarem",
                        help="how EM steps are chained: squarem extrapolates along two steps, none takes one "
                             "after another (default squarem; both reach the same MAP)")


# Read off the package's folder: a palette added there is listed without an edit here.
PALETTE_HELP = (f"colour and shape values of the files: a palette the package ships ({', '.join(palette_names())}; "
                "the package's logic/palettes/) or the path of a .lp file of value(Attribute, Index, Name) facts")


LIBRARY_NAMES = (f"; a file, or a library the package ships by name ({', '.join(library_names())}), which "
                 "replaces the default: name tasks too to add to its tasks")


def json_text(data, indent: int | None = None) -> str:
    """``data`` as strict JSON text, a figure without a value (NaN: no reading acted on at a threshold, an
    infinite log-likelihood) written as null: JSON has no NaN, and jq or a browser refuse text that holds one."""
    def finite(value):
        if isinstance(value, float) and not math.isfinite(value):
            return None
        if isinstance(value, dict):
            return {k: finite(v) for k, v in value.items()}
        if isinstance(value, (list, tuple)):
            return [finite(v) for v in value]
        return value

    return json.dumps(finite(data), indent=indent, allow_nan=False)


def as_typed(text: str) -> str:
    """``text`` as typed unless it holds characters a terminal would obey (an escape sequence clears the screen)
    or not show: then as a Python string literal, every character visible."""
    return text if text.isprintable() else ascii(text)


def report_beside(json_path):
    """A context in which the command's report goes to standard error where ``json_path`` (``--json``) is standard
    output (``--json /dev/stdout``): the JSON alone reaches a pipe (the report had come first, and a reader
    could not parse it). Otherwise nothing changes."""
    try:
        to_stdout = json_path is not None and os.path.samestat(os.stat(json_path), os.fstat(sys.stdout.fileno()))
    except (OSError, ValueError, AttributeError):  # no such file yet, or stdout is no file (captured in tests)
        to_stdout = False
    return contextlib.redirect_stdout(sys.stderr) if to_stdout else contextlib.nullcontext()


def json_bytes(data) -> bytes:
    """``data`` as the JSON text of a result file (:func:`json_text`, indented)."""
    return (json_text(data, indent=1) + "\n").encode("utf-8")


def library_given(args: argparse.Namespace):
    """The TaskLibrary of the ``--library`` files given, or None (the command's default) without one; with
    ``--time-limit``, the package's tasks when none is given, so that the limit has a library to hold."""
    time_limit = getattr(args, "time_limit", None)
    if not args.library and time_limit is None:
        return None
    from groundlang.logic.tasks import TaskLibrary

    return words_beside_checked(TaskLibrary.load(args.library or None, **time_limit_given(args)))


def words_beside_checked(library):
    """``library``, once the word files beside its files (``mine.words`` beside ``mine.lp``) are read: a malformed
    one is refused by file and line by every command that reads the library, not only those that parse (check
    and domain had passed a file train then refused)."""
    from groundlang.model.domain_words import extra_words
    from groundlang.training_vocabulary import word_files_beside

    extra_words(word_files_beside(library))
    return library


def add_time_limit_option(parser, help: str = "stop grounding/solving the task library in a layout after this long "
                                               "(default 10; raise it for a very large layout)") -> None:
    """``--time-limit SECONDS`` for a command that grounds a library in layouts it reads (train, follow, evaluate,
    and check, parse and discover, which read a user's .lp files; ``help`` says what it limits there): the CLI
    names it beside the message of a grounding that did not finish in time."""
    parser.add_argument("--time-limit", type=positive_seconds, default=None, metavar="SECONDS", help=help)


def time_limit_given(args: argparse.Namespace) -> dict:
    """``TaskLibrary.load``'s ``time_limit`` keyword where ``--time-limit`` was given (else its default)."""
    time_limit = getattr(args, "time_limit", None)
    return {} if time_limit is None else {"time_limit": time_limit}


def add_lexicon_option(parser) -> None:
    """``--lexicon FILE`` (repeatable): a word file whose words the parser should know too."""
    parser.add_argument(
        "--lexicon", metavar="FILE", action="append", default=[],
        help="a word file (`CATEGORY: word word ...` lines, see grammar/english.words) whose nouns, "
             "adjectives, verbs and prepositions the parser should know too (repeatable)",
    )


def lexicon_beside(args, library) -> None:
    """LexiconError, naming ``--lexicon``'s file, where it gives a SYNONYM form another word than the word
    files of ``library`` (None: the default) do. A Learner receives ``--lexicon``'s words as data, read once
    for the workers, so its own check could name only the library's file."""
    if args.lexicon:
        from groundlang.logic.tasks import TaskLibrary
        from groundlang.model.domain_words import extra_words
        from groundlang.training_vocabulary import word_files_beside

        extra_words([*word_files_beside(library if library is not None else TaskLibrary.load()), *args.lexicon])


def inputs_read(args, *names: str) -> list[tuple[str, str]]:
    """``(option, path)`` for each of ``args``' path options ``names`` that is given (a repeatable option
    gives one pair per path), for :func:`groundlang.logic.storage.check_destination` to keep an output off
    them. A positional argument is named by its own name."""
    out = []
    for name in names:
        value = getattr(args, name, None)
        option = f"--{name.replace('_', '-')}" if name not in _POSITIONALS else name
        for path in value if isinstance(value, list) else [value]:
            if isinstance(path, str) and path:
                out.append((option, path))
    return out


_POSITIONALS = frozenset({"directory"})


def is_burlap_state_file(path: str) -> bool:
    """Whether ``path`` is a one-line state file (``.state`` or ``.bdm``) holding a BURLAP state line, the
    Williams et al. format, which is read with its own domain and palette by default."""
    if Path(path).suffix not in (".state", ".bdm") or not Path(path).is_file():
        return False
    with open(path, "rb") as handle:
        return handle.read(64).removeprefix(_BOM).lstrip().startswith(b"{")


_BOM = b"\xef\xbb\xbf"  # a UTF-8 byte order mark, which some editors write first; the readers skip it


def renumbering_note(names: dict[str, str]) -> str | None:
    """A line saying which objects of a state file the layout renumbered (``corpus.file_names``), for
    commands that list objects by the layout's names; None when it renamed none."""
    if not names:
        return None
    return ("objects are numbered from 0 in each class here; in the file: "
            + ", ".join(f"{own} is {name}" for own, name in names.items()))


class _FileNames(logging.Filter):
    """Writes a log line's object names as the state file gives them (``corpus.file_names``): the planner
    below logs the layout's (block2), the command's output the file's (block3)."""

    def __init__(self, names: dict[str, str]):
        super().__init__()
        self.names = names
        self.pattern = re.compile(r"\b(" + "|".join(map(re.escape, sorted(names, key=len, reverse=True))) + r")\b")

    def filter(self, record: logging.LogRecord) -> bool:
        # A record is shared by every handler, each with this filter: renamed once ({block0: block1, block1:
        # block2} must not turn block0 into block2). A call whose arguments do not fit its format is left to
        # logging, which says so and goes on.
        if getattr(record, "by_file_names", False):
            return True
        try:
            text = record.getMessage()
        except (TypeError, ValueError):
            return True
        record.msg = self.pattern.sub(lambda m: self.names[m.group(1)], text)
        record.args, record.by_file_names = None, True
        return True


@contextlib.contextmanager
def logged_by_file_names(names: dict[str, str]):
    """Within it, the lines logged name objects by ``names`` (the layout's name -> the file's); nothing
    changes where the file renamed none."""
    handlers = list(logging.getLogger().handlers) if names else []
    renamer = _FileNames(names) if names else None
    for handler in handlers:
        handler.addFilter(renamer)
    try:
        yield
    finally:
        for handler in handlers:
            handler.removeFilter(renamer)


def require_palette(args, corpus: str) -> None:
    """One line when a ``*.txt`` corpus is read without ``--palette``, saying first what is wrong with
    ``corpus`` if anything: a path that does not exist, or a folder that holds no corpus file of either
    format, is refused without asking for a palette it would not need. (With one, the corpus reader's
    own messages say more.)"""
    if args.palette is not None:
        return
    path = Path(corpus)
    if not path.exists():
        raise ValueError(f"{corpus}: No such file or directory")
    if path.is_dir() and not any(p.suffix == ".txt" for p in path.iterdir()):
        raise ValueError(f"{corpus}: no corpus files; expected corpus files (*.txt, with --palette) "
                         "or .bdm files (Williams 2018)")
    raise ValueError(f"{corpus}: --palette is required for a commands-to-tasks corpus (e.g. --palette sokoban)")


def check_state_file(path: str, what: str) -> None:
    """One line for a state file that is absent or has nothing in it, or a ``.bdm`` file of commands where
    ``what`` (the command) wants one state: before asking for a palette none of them would need."""
    try:
        mode = os.stat(path).st_mode  # a symlink loop says so, where Path.exists would say "no such file"
    except OSError as exc:
        raise ValueError(f"{path}: {exc.strerror}") from None
    if not stat.S_ISREG(mode):
        raise ValueError(f"{path}: {file_kind(mode)}, not a regular file; expected a state file (.state, a one-line .bdm) "
                         "or a corpus file")
    if Path(path).suffix in (".state", ".bdm"):
        with open(path, "rb") as handle:
            if not handle.read(1 << 16).removeprefix(_BOM).strip():
                raise ValueError(f"{path}: the file is empty; expected one state line")
        if Path(path).suffix == ".bdm" and not is_burlap_state_file(path):
            raise ValueError(f"{path}: line 1 is not a state line; {what} reads a one-line .bdm or .state file, "
                             "or a corpus file (*.txt), not a .bdm file of commands")


def cache_option(args: argparse.Namespace):
    """The cache folder ``--cache-dir`` / ``--no-cache`` name: False for none, None for the default. ValueError
    for both, or an empty --cache-dir (which would be the working folder)."""
    if args.cache_dir is not None and not args.cache_dir.strip():
        raise ValueError("--cache-dir: empty; name a folder (or leave the option out for $GROUNDLANG_CACHE "
                         "or ./.groundlang-cache)")
    if args.no_cache and args.cache_dir is not None:
        raise ValueError(f"--no-cache and --cache-dir {args.cache_dir}: choose one (no cache, or this one)")
    return False if args.no_cache else args.cache_dir


def check_cache_outside(cache, model: str) -> None:
    """ValueError, before any work, where the cache folder (``cache``: :func:`cache_option`'s value) is the
    model folder ``-o model`` or inside it: the save at the end would find the folder holding other files
    than a model's, and the training would be lost."""
    if cache is False:
        return
    from groundlang.inference.likelihoods import cache_directory, environment_cache

    root, folder = cache_directory(cache).resolve(), Path(model).resolve()
    if root == folder or folder in root.parents:
        named = f"--cache-dir {cache}" if cache is not None else (
            f"GROUNDLANG_CACHE {environment_cache()}" if environment_cache() else f"the cache folder {root}")
        raise ValueError(f"{named}: inside the model folder -o {model}, which holds one model only; name a cache "
                         "folder elsewhere")

