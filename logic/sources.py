"""ASP sources: the package's ``.lp`` files and a user's, read safely and parsed into checked statements.

What :class:`groundlang.logic.program.Program` is built from. Errors are ``AspError`` (a ``ValueError``):

- syntax errors name the file, line and column (``AspSyntaxError``);
- ``#script`` blocks are refused unless ``allow_scripts=True``, and
  ``#include`` is refused always: list the file among the sources instead
  (``AspScriptRefused``);
- a user's file is read only when it is a regular file of at most
  ``MAX_PROGRAM_BYTES`` in UTF-8.
"""

from __future__ import annotations

import errno
import functools
import os
import re
import stat
from collections.abc import Iterable
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path

import clingo.ast as ast
import numpy as np

from .storage import as_path

__all__ = ["AspError", "AspSyntaxError", "AspScriptRefused", "Source", "package_source", "file_source",
           "library_source", "library_sources",
           "MAX_PROGRAM_BYTES", "parse_source", "one_line"]


class AspError(ValueError):
    """An ASP program that cannot be used; the message names the file and line."""


class AspSyntaxError(AspError):
    """A source that clingo cannot parse."""


class AspScriptRefused(AspError):
    """A source with ``#script`` (without opt-in) or ``#include``."""


@dataclass(frozen=True)
class Source:
    """ASP text and the name its errors are reported under (a path or ``groundlang.logic/x.lp``)."""

    name: str
    text: str


def package_source(filename: str) -> Source:
    """A ``.lp`` file shipped in ``groundlang.logic``."""
    resource = files("groundlang.logic") / filename
    return Source(f"groundlang.logic/{filename}", resource.read_text(encoding="utf-8"))


def library_names() -> dict[str, str]:
    """The task libraries the package ships, by the name ``--library`` may give them (as ``--palette`` takes a
    palette's): ``tasks`` (``logic/tasks.lp``, the default) and each domain of ``logic/domains``
    (``williams2018``). A name, not a path, so that they can be named after an install that is not editable."""
    names = {"tasks": "tasks.lp"}
    domains = files("groundlang.logic") / "domains"
    names.update({p.name[:-3]: f"domains/{p.name}" for p in domains.iterdir() if p.name.endswith(".lp")})
    return names


def library_sources(paths, what: str) -> list[Source]:
    """The library files ``paths`` names: one path or an iterable of them (a str is one path, not letters to
    read one by one); TypeError starting with ``what`` for anything else."""
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    elif isinstance(paths, (bytes, bytearray)) or not isinstance(paths, Iterable):  # bytes iterate as ints
        raise TypeError(f"{what}: paths must be a path or paths, got {type(paths).__name__}")
    return [library_source(as_path(p, f"{what}: each path")) for p in paths]


def library_source(path: str | Path) -> Source:
    """A library file: one the package ships (``logic/domains/williams2018.lp``, or by its name,
    ``williams2018``) is read as the package's own, solved in-process; any other is a user's, solved in a
    child process that can be killed."""
    # A bare name (no folder, no suffix) that is not a file: the package's library of that name, even where a
    # folder of that name is in the working folder.
    if not Path(path).is_file() and Path(path).name == str(path) and not Path(path).suffix:
        shipped = library_names()
        if str(path) not in shipped:
            if Path(path).is_dir():  # "no such file" of a folder that is there read as a contradiction
                raise IsADirectoryError(21, "a folder, not a library file (name its .lp files), nor a library the "
                                        f"package ships ({', '.join(shipped)})", str(path))
            raise FileNotFoundError(2, f"no such file, nor a library the package ships ({', '.join(shipped)})", str(path))
        return package_source(shipped[str(path)])
    own = Path(str(files("groundlang.logic"))).resolve()
    try:
        relative = Path(path).resolve().relative_to(own)
    except (ValueError, OSError, RuntimeError):  # RuntimeError: a symlink loop (Python 3.11's resolve); read, it says so
        return file_source(path)
    return package_source(relative.as_posix()) if Path(path).is_file() else file_source(path)


# A task library is a few KB; a wrong path (a log, /dev/zero) must not be read whole.
MAX_PROGRAM_BYTES = 4 * 2**20


def _read_regular(path: Path) -> bytes:
    """A regular file of at most MAX_PROGRAM_BYTES (storage.read_limited's twin, raising AspError for an ASP
    program). Opened non-blocking: a FIFO must not hang the open."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    try:
        mode = os.fstat(fd).st_mode
    except BaseException:
        os.close(fd)
        raise
    if not stat.S_ISREG(mode):  # checked before fdopen, which refuses a folder naming only the descriptor
        os.close(fd)
        if stat.S_ISDIR(mode):
            raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
        raise AspError(f"{path}: not a regular file (a FIFO or device); expected an ASP program (.lp)")
    with os.fdopen(fd, "rb") as handle:
        data = handle.read(MAX_PROGRAM_BYTES + 1)
    if len(data) > MAX_PROGRAM_BYTES:
        raise AspError(f"{path}: more than the {MAX_PROGRAM_BYTES:,} bytes allowed for an ASP program")
    return data


def file_source(path: str | Path) -> Source:
    """A user's ``.lp`` file; raises OSError when unreadable and AspError when not UTF-8."""
    path = Path(path)
    data = _read_regular(path)
    try:  # a leading byte-order mark (some Windows editors write one) is read past, as in every other input file
        return Source(str(path), data.decode("utf-8").removeprefix("\ufeff"))
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise AspSyntaxError(f"{path}:{line}: not UTF-8 text (byte {exc.start})") from None


# Comments and strings are removed before looking for directives, so that "% no #include here" is fine.
_COMMENT_OR_STRING = re.compile(r'%\*.*?\*%|%[^\n]*|"(?:\\.|[^"\\])*"', re.DOTALL)
_INCLUDE = re.compile(r"#include\b")
_NON_ASCII = re.compile(r"[^\x00-\x7f]")


def _blank(match: re.Match) -> str:
    return re.sub(r"[^\n]", " ", match.group(0))


def one_line(text: str) -> str:
    return " ".join(text.split())


# A fact of constants, numbers and strings alone (``value(colour, 0, red).``), as ``str`` of its AST
# prints it: no variable, operator or interval, so no message of clingo's names it or a place inside it.
# clingo's: _X and _ are variables. Possessive (*+): inside the repeated group below, every lowercase letter could
# start another identifier, and a name that fails to match was tried split every way (20 letters: 48 s).
_IDENTIFIER = r"_*+[a-z][A-Za-z0-9_']*+"
_GROUND_FACT = re.compile(rf'{_IDENTIFIER}(?:\((?:{_IDENTIFIER}|-?\d+|"(?:[^"\\]|\\.)*"|[,() ])*\))?\.')


def _relocate(node, name: str) -> None:
    """Give every location in an AST the source's name (clingo says ``<string>``)."""
    if isinstance(node, ast.AST):
        if "location" in node.keys():
            b, e = node.location.begin, node.location.end
            node.location = ast.Location(
                ast.Position(name, b.line, b.column), ast.Position(name, e.line, e.column)
            )
        for key in node.child_keys:
            _relocate(getattr(node, key), name)
    elif isinstance(node, (ast.ASTSequence, list, tuple)):
        for child in node:
            _relocate(child, name)


# A term nested deeper than this is refused. clingo's own printing of a statement recurses in C++ and ends the
# process (a segfault, no message) at some ten thousand levels (x(1+1+...) 20,000 deep); the Python walk
# below stops at its recursion limit, about a thousand.
MAX_TERM_DEPTH = 1000
# A statement shorter than this (characters) cannot nest a term MAX_TERM_DEPTH deep: each level takes at least
# two characters (``f(``, ``1+``), so only longer ones are measured after parsing.
_MEASURED_STATEMENT = 2 * MAX_TERM_DEPTH
# Before parsing: a statement with more operators than this is refused unparsed. Freeing the parse of a chain
# 1+1+... (or 1..1..., or f(f(...))) 100,000 long ends the process in clingo's C++ too; 70,000 is freed safely,
# and a chain under this bound is refused after parsing, as nested too deeply. A flat statement of as many
# operators (a disjunction of 30,000 atoms) is refused too: split it. Characters that are operators of a term;
# an interval's ".." counts as one.
_MAX_STATEMENT_OPERATORS = 30 * MAX_TERM_DEPTH
_OPERATORS = np.frombuffer(b"+-*/\\^&|?~", dtype=np.uint8)
_SPACES = np.frombuffer(b" \t\r\n\f\v", dtype=np.uint8)
_BEFORE_NEGATION = np.frombuffer(b"(,;:", dtype=np.uint8)
# A #script block's body is another language's: its parentheses and operators are not ASP's (a Python "%"
# had been blanked as a comment, leaving "(" open).
_SCRIPT = re.compile(r"#script\b.*?#end\s*\.", re.DOTALL)


def _nesting_refused_unparsed(name: str, scrubbed: str) -> None:
    """AspSyntaxError where a statement of the text (comments, strings and script bodies blanked) nests
    parentheses deeper than MAX_TERM_DEPTH, or holds more than _MAX_STATEMENT_OPERATORS operators: vectorised
    over the characters, before clingo parses (and later frees) a term its C++ recursion cannot."""
    scrubbed = _SCRIPT.sub(_blank, scrubbed)
    codes = np.frombuffer(scrubbed.encode("latin-1", "replace"), dtype=np.uint8)
    dot = codes == ord(".")
    before_dot = np.concatenate([[False], dot[:-1]])
    after_dot = np.concatenate([dot[1:], [False]])
    # A statement ends at a full stop that is not part of an interval's "..".
    ends = dot & ~before_dot & ~after_dot
    statement = np.cumsum(ends) - ends
    # Parentheses counted from each statement's start: one left open by a broken statement does not carry over.
    depth = np.cumsum((codes == ord("(")).astype(np.int32) - (codes == ord(")")))
    depth -= np.concatenate([[0], depth[np.flatnonzero(ends)]])[statement]
    deep = np.flatnonzero(depth > MAX_TERM_DEPTH)
    where, what = None, ""
    if deep.size:
        where, what = int(deep[0]), f"a term nested too deeply (more than {MAX_TERM_DEPTH} levels of parentheses)"
    else:
        # A minus sign right after "(", ",", ";" or ":" negates a number ("p(-1;-2;...)", a long flat pool):
        # not counted. Spaces are skipped to find the character before.
        shown = np.flatnonzero(~np.isin(codes, _SPACES))
        visible = codes[shown]
        before = np.concatenate([[ord(",")], visible[:-1]])
        negation = (visible == ord("-")) & np.isin(before, _BEFORE_NEGATION)
        interval = dot & after_dot  # the first dot of each ".."
        operators = np.union1d(shown[np.isin(visible, _OPERATORS) & ~negation], np.flatnonzero(interval))
        if operators.size > _MAX_STATEMENT_OPERATORS:
            counts = np.bincount(statement[operators])
            if counts.max() > _MAX_STATEMENT_OPERATORS:
                first = operators[statement[operators] == int(np.argmax(counts))]
                where = int(first[_MAX_STATEMENT_OPERATORS])
                what = (f"a statement of more than {_MAX_STATEMENT_OPERATORS} operators: a term nested too deeply, "
                        "or too long a statement to parse safely (split it)")
    if where is not None:
        line = scrubbed.count("\n", 0, where) + 1
        raise AspSyntaxError(f"{name}:{line}: {what}")


def _nested_beyond(node, limit: int) -> bool:
    """Whether an AST nests deeper than ``limit``, walked with a stack of its own (no recursion, in Python or
    in clingo's printer)."""
    stack = [(node, 0)]
    while stack:
        item, depth = stack.pop()
        if depth > limit:
            return True
        if isinstance(item, ast.AST):
            stack.extend((getattr(item, key), depth + 1) for key in item.child_keys)
        elif isinstance(item, (ast.ASTSequence, list, tuple)):
            stack.extend((child, depth) for child in item)
    return False


def _span(stm, line_starts: list[int]) -> int:
    """How many characters of the source text a statement spans (from its location)."""
    return _offset(stm.location.end, line_starts) - _offset(stm.location.begin, line_starts)


def _offset(position, line_starts: list[int]) -> int:
    """A location's position (line, column) as an offset into the source text."""
    return line_starts[min(position.line, len(line_starts)) - 1] + position.column


def parse_source(source: Source, allow_scripts: bool) -> list:
    """Parse one source into AST statements, refusing scripts and includes.

    A process loads the same library many times (every model loaded, every fold, every layout's
    tables), and naming the locations of a parse walks its whole AST in Python: most of the time of
    ``Learner.load``. So parses are kept, by name and text; the statements are only ever read. Only
    sources of up to ``KEPT_SOURCE_BYTES`` are kept, so the memory they hold stays bounded."""
    parse = _parsed if len(source.text) <= KEPT_SOURCE_BYTES else _parsed.__wrapped__
    return list(parse(source.name, source.text, allow_scripts))


# Parses kept per process (64 sources at most, each this long at most): the package's files are a few KB.
KEPT_SOURCE_BYTES = 256 * 2**10


@functools.lru_cache(maxsize=64)
def _parsed(name: str, text: str, allow_scripts: bool) -> tuple:
    source = Source(name, text)
    scrubbed = _COMMENT_OR_STRING.sub(_blank, source.text)
    m = _INCLUDE.search(scrubbed)
    if m:
        line = scrubbed.count("\n", 0, m.start()) + 1
        raise AspScriptRefused(
            f"{source.name}:{line}: #include is not allowed; pass the included file as another source"
        )
    # clingo reads the text as a C string: a NUL would end it there, and what follows would silently not be
    # part of the program.
    nul = source.text.find("\x00")
    if nul >= 0:
        line = source.text.count("\n", 0, nul) + 1
        raise AspSyntaxError(f"{source.name}:{line}: a NUL byte; ASP text has none (clingo would stop reading "
                             "the file there)")
    # clingo's lexer reports a non-ASCII character one byte at a time, and the
    # half character in its message aborts the process (a decode error inside
    # a C callback): refuse such text here, with the position.
    m = _NON_ASCII.search(scrubbed)
    if m:
        line = scrubbed.count("\n", 0, m.start()) + 1
        column = m.start() - scrubbed.rfind("\n", 0, m.start())
        raise AspSyntaxError(
            f"{source.name}:{line}:{column}: unexpected character {m.group(0)!r}; "
            "names and operators are ASCII (other text only in comments and strings)"
        )
    _nesting_refused_unparsed(source.name, scrubbed)
    messages: list[str] = []
    statements: list = []
    try:
        ast.parse_string(
            source.text, statements.append, logger=lambda code, msg: messages.append(msg)
        )
    except RuntimeError:
        # clingo's "<string>:2:1-2: error: syntax error, ...": the CLI's line says "error:" already
        text = re.sub(r"(<string>:[\d:-]+): error: ", r"\1: ", one_line(" ".join(messages))) or "syntax error"
        raise AspSyntaxError(text.replace("<string>", source.name)) from None
    line_starts = [0] + [m.end() for m in re.finditer("\n", source.text)]
    for stm in statements:
        if _span(stm, line_starts) > _MEASURED_STATEMENT and _nested_beyond(stm, MAX_TERM_DEPTH):
            raise AspSyntaxError(f"{source.name}:{stm.location.begin.line}: a term nested too deeply (more than "
                                 f"{MAX_TERM_DEPTH} levels of parentheses or operators)")
        if stm.ast_type == ast.ASTType.Minimize:
            # Optimisation keeps only the best answer sets, and every program here is read for all of them
            # (a library's groundings, a PF's table): its groundings would silently go missing.
            raise AspSyntaxError(f"{source.name}:{stm.location.begin.line}: an optimisation statement (#minimize, "
                                 "#maximize or a weak constraint :~) is not allowed: groundlang reads every answer "
                                 "set of a program, and optimisation keeps only the best")
        if stm.ast_type == ast.ASTType.Script and not allow_scripts:
            raise AspScriptRefused(
                f"{source.name}:{stm.location.begin.line}: #script blocks are refused; "
                "allow them only for programs you trust "
                "(allow_scripts=True in Python; --allow-scripts of tasks and domain)"
            )
        try:
            # The walk costs about 0.3 ms a statement in Python: a library of 40,000 facts took a minute
            # to load, three programs over. No message of clingo's names a place in a ground fact.
            if not _GROUND_FACT.fullmatch(str(stm)):
                _relocate(stm, source.name)
        except RecursionError:  # walked in Python: a term nested deeper than its stack (f(f(...)), 1+1+...)
            raise AspSyntaxError(f"{source.name}:{stm.location.begin.line}: a term nested too deeply (more than "
                                 "about a few hundred levels of parentheses or operators)") from None
    return tuple(statements)
