"""Loading and grounding ASP programs safely: package rules, user rules, clear errors.

A :class:`Program` is a checked, parsed set of sources (the package's ``.lp``
files, read with ``importlib.resources``, and any user ``.lp`` files; both are
read and parsed by :mod:`groundlang.logic.sources`). It is parsed once; each environment then gets one ``clingo.Control`` with the
program plus that environment's facts, grounded once.

Safety and errors (all ``AspError``, a ``ValueError``, so the CLI prints one line):

- syntax errors name the file, line and column (``AspSyntaxError``);
- unsafe variables and other grounding errors carry clingo's message with the
  file and line rewritten to the source's name (``AspGroundingError``);
- ``#script`` blocks are refused unless ``allow_scripts=True``, and
  ``#include`` is refused always: list the file among the sources instead
  (``AspScriptRefused``);
- grounding and solving stop after ``time_limit`` seconds (``AspTimeout``).
  clingo cannot interrupt its grounder, so a program built with
  ``isolated=True`` (user files) is solved in a child process that is killed
  at the limit and capped in memory; the package's own rules run in-process
  (a runaway there would be abandoned in a daemon thread).
"""

from __future__ import annotations

import functools
import logging
import numbers
import threading
from dataclasses import dataclass, field
from typing import Iterable, Sequence

import clingo
import clingo.ast as ast

from groundlang.logic.sources import (
    AspError,
    AspScriptRefused,
    AspSyntaxError,
    Source,
    file_source,
    one_line,
    package_source,
    parse_source,
)

__all__ = [
    "grounding_left_running",
    "AspError",
    "AspSyntaxError",
    "AspScriptRefused",
    "AspGroundingError",
    "AspTimeout",
    "Source",
    "package_source",
    "file_source",
    "Program",
    "DEFAULT_TIME_LIMIT",
]

log = logging.getLogger(__name__)

# Seconds; generous for the Cleanup World (milliseconds), short enough to notice a runaway program.
DEFAULT_TIME_LIMIT = 10.0


class AspGroundingError(AspError):
    """clingo refused to ground (unsafe variables, undefined operations that are errors...)."""


class AspTimeout(AspError):
    """Grounding or solving took longer than the time limit."""


MAX_TIME_LIMIT = 10**6  # seconds (11 days); longer waits overflow the platform's timeouts


def _checked_time_limit(time_limit: float | None) -> float | None:
    """``time_limit`` itself, refused unless None or seconds above 0 and at most ``MAX_TIME_LIMIT`` (an
    infinite or huge one overflowed the thread wait deep inside; 0 blamed the program for grounding
    infinitely many atoms)."""
    if time_limit is not None and not (isinstance(time_limit, numbers.Real) and not isinstance(time_limit, bool)
                                       and 0 < time_limit <= MAX_TIME_LIMIT):
        raise ValueError(f"time_limit must be seconds above 0 and at most {MAX_TIME_LIMIT} (or None), "
                         f"not {time_limit!r}")
    return None if time_limit is None else float(time_limit)  # np.float32, Fraction: waits take floats


# Groundings left running past their time limit (or an interrupt): clingo cannot stop one.
_ABANDONED: list[threading.Thread] = []


def grounding_left_running() -> bool:
    """Whether a grounding this process gave up on still runs. Python's normal exit then waits on it or
    crashes in clingo's native code as the interpreter is torn down: a program should end at once."""
    return any(thread.is_alive() for thread in _ABANDONED)


def _run_with_limit(work, time_limit: float | None, what: str) -> None:
    """Run ``work()`` in a daemon thread (clingo releases the GIL), wait at most ``time_limit`` s."""
    box: dict[str, BaseException] = {}

    def target() -> None:
        try:
            work()
        except BaseException as exc:  # re-raised in the caller's thread
            box["error"] = exc

    thread = threading.Thread(target=target, name="clingo", daemon=True)
    thread.start()
    try:
        thread.join(time_limit)
    finally:  # timed out, or interrupted while waiting: clingo's grounding cannot be stopped
        if thread.is_alive():
            _ABANDONED.append(thread)
    if thread.is_alive():
        # No option is named: not every command that grounds a program takes --time-limit (the CLI names it
        # where one does), and the API's is TaskLibrary's time_limit.
        raise AspTimeout(
            f"{what} did not finish within {time_limit:g} s; the program grounds too many atoms: infinitely "
            "many (a rule without a bound), or a large layout's many (raise the time limit if it is just large)"
        )
    if "error" in box:
        raise box["error"]


@dataclass(frozen=True)
class Program:
    """Checked, parsed ASP sources; ground them with an environment's facts via :meth:`control`."""

    sources: tuple[Source, ...]
    allow_scripts: bool = False
    isolated: bool = False  # solve() in a killable child process (for user-supplied sources)
    _statements: tuple = field(init=False, repr=False, compare=False)
    _by_source: tuple = field(init=False, repr=False, compare=False)  # each source's statements

    def __post_init__(self) -> None:
        by_source = tuple(tuple(parse_source(source, self.allow_scripts)) for source in self.sources)
        object.__setattr__(self, "_by_source", by_source)
        object.__setattr__(self, "_statements", tuple(stm for statements in by_source for stm in statements))

    def statements_by_source(self) -> Iterable[tuple[Source, tuple]]:
        """Each source with its parsed statements (read only), as the program was parsed once."""
        return zip(self.sources, self._by_source)

    @classmethod
    def from_sources(cls, sources: Iterable[Source], allow_scripts: bool = False,
                     isolated: bool = False) -> "Program":
        return cls(tuple(sources), allow_scripts, isolated)

    @property
    def names(self) -> str:
        return ", ".join(s.name for s in self.sources)

    @property
    def user_names(self) -> str:
        """The sources a user gave (files, texts), leaving out groundlang's own; all of them when
        every source is groundlang's: where an error in a user's library is to be looked for."""
        mine = [s.name for s in self.sources if not s.name.startswith("groundlang.")]
        return ", ".join(mine) if mine else self.names

    def declared_order(self, predicate: str, arity: int, position: int) -> list[str]:
        """The terms at argument ``position`` of the rule heads ``predicate/arity`` in source order
        (``declared_order("pf", 3, 1)``: PF names as the files declare them), each once."""
        out: dict[str, None] = {}
        for stm in self._statements:
            if stm.ast_type != ast.ASTType.Rule or stm.head.ast_type != ast.ASTType.Literal:
                continue
            atom = stm.head.atom
            if atom.ast_type != ast.ASTType.SymbolicAtom:
                continue
            term = atom.symbol
            if (term.ast_type == ast.ASTType.Function and term.name == predicate
                    and len(term.arguments) == arity):
                out.setdefault(str(term.arguments[position]), None)
        return list(out)

    def head_atoms(self) -> Iterable[tuple[str, object]]:
        """``(source name, atom)`` of every atom a rule head of the program may make true or ``#external``
        declares (AST terms), in source order."""
        for source, statements in self.statements_by_source():
            for stm in statements:
                if stm.ast_type == ast.ASTType.Rule:
                    yield from ((source.name, term) for term in _head_atoms(stm.head))
                elif stm.ast_type == ast.ASTType.External:
                    yield source.name, getattr(stm.atom, "symbol", stm.atom)

    def body_signatures(self, sources: Sequence[str] | None = None) -> set[tuple[str, int]]:
        """``(name, arity)`` of every atom a rule body reads (in literals, conditions and aggregates), of the
        sources named ``sources`` (default: all)."""
        return {signature for source, statements in self.statements_by_source()
                if sources is None or source.name in sources for stm in statements
                if stm.ast_type == ast.ASTType.Rule for node in _nodes(stm.body)
                if node.ast_type == ast.ASTType.SymbolicAtom and (signature := term_signature(node.symbol))}

    def script_call(self):
        """The first statement that calls a script (``@f(x)``), or None."""
        return next((stm for _, statements in self.statements_by_source() for stm in statements
                     if any(n.ast_type == ast.ASTType.Function and n.external for n in _nodes(stm))), None)

    def constants(self) -> dict[str, str]:
        """What each ``#const`` of the program names, as written (``#const near = agentNearRoom.``)."""
        return {stm.name: str(stm.value) for _, statements in self.statements_by_source() for stm in statements
                if stm.ast_type == ast.ASTType.Definition}

    def definitions(self) -> dict[tuple[str, int], str]:
        """``(name, arity)`` of every predicate a rule head of the program may make true (a plain head, a
        choice, a disjunction, a head aggregate's elements) or ``#external`` declares, with the name of the
        first source defining it. Conditions and bodies are not definitions."""
        out: dict[tuple[str, int], str] = {}
        for source, statements in self.statements_by_source():
            for stm in statements:
                if stm.ast_type == ast.ASTType.Rule:
                    heads = _head_atoms(stm.head)
                elif stm.ast_type == ast.ASTType.External:
                    heads = [getattr(stm.atom, "symbol", stm.atom)]
                else:
                    continue
                for term in heads:
                    if term.ast_type == ast.ASTType.Function:
                        out.setdefault((term.name, len(term.arguments)), source.name)
        return out

    def control(
        self, facts: str = "", *, time_limit: float | None = DEFAULT_TIME_LIMIT,
        arguments: Sequence[str] = (),
    ) -> clingo.Control:
        """A Control with the program and ``facts`` (trusted, generated text), grounded once."""
        time_limit = _checked_time_limit(time_limit)
        messages: list[str] = []

        def logger(code: clingo.MessageCode, msg: str) -> None:
            messages.append(msg)
            log.debug("clingo: %s", one_line(msg))

        if self.allow_scripts:
            _enable_python_scripts()
        ctl = clingo.Control(list(arguments), logger=logger)
        try:
            with ast.ProgramBuilder(ctl) as builder:
                for stm in self._statements:
                    builder.add(stm)
        except RuntimeError as exc:
            # e.g. an allowed #script in a language this clingo build cannot run
            raise AspGroundingError(one_line(" ".join(messages) or str(exc))) from None
        try:
            if facts:
                ctl.add("base", [], facts)
        except RuntimeError:
            raise AspSyntaxError(
                "environment facts: " + one_line(" ".join(messages)).replace("<block>", "facts")
            ) from None

        def ground() -> None:
            try:
                ctl.ground([("base", [])])
            except RuntimeError:
                errors = [m for m in messages if "error" in m] or messages
                raise AspGroundingError(one_line(" ".join(errors)) or "grounding failed") from None

        _run_with_limit(ground, time_limit, f"grounding {self.user_names}")
        return ctl

    def solve(
        self, facts: str = "", *, models: int = 0, time_limit: float | None = DEFAULT_TIME_LIMIT
    ) -> list[list[clingo.Symbol]]:
        """Ground once and return the shown atoms of every answer set (``models=0``: all).

        With ``isolated=True`` this runs in a child process (killed at the time limit);
        errors are re-raised here as the same AspError subclasses.
        """
        time_limit = _checked_time_limit(time_limit)
        if self.isolated:
            from groundlang.logic.child_process import solve_in_child

            return solve_in_child(self, facts, models, time_limit)
        ctl = self.control(facts, time_limit=time_limit, arguments=[f"--models={models}"])
        found: list[list[clingo.Symbol]] = []
        with ctl.solve(on_model=lambda m: found.append(m.symbols(shown=True)), async_=True) as handle:
            if not handle.wait(time_limit):
                handle.cancel()
                raise AspTimeout(
                    f"solving {self.user_names} did not finish within {time_limit:g} s"
                )
            handle.get()
        return found




def _nodes(node) -> Iterable:
    """Every AST node under ``node`` (itself first), through child nodes and sequences of them."""
    if isinstance(node, ast.AST):
        yield node
        for key in node.child_keys:
            yield from _nodes(getattr(node, key))
    elif isinstance(node, (list, tuple, ast.ASTSequence)):
        for item in node:
            yield from _nodes(item)


def term_signature(term) -> tuple[str, int] | None:
    """``(name, arity)`` of an atom or term as written (``toyInRoom``, ``roomIs(C)``, ``holds(P, (A,))``); None
    for a variable, a number, a string, a script call (``@f()``) or a computed term; ``-name`` for a classically
    negated atom."""
    if term.ast_type == ast.ASTType.UnaryOperation and term.operator_type == ast.UnaryOperator.Minus:
        inner = term_signature(term.argument)  # a classically negated atom: -name/2, a predicate of its own
        return None if inner is None else ("-" + inner[0], inner[1])
    symbol = getattr(term, "symbol", None) if term.ast_type == ast.ASTType.SymbolicTerm else None
    if symbol is not None:
        return (symbol.name, len(symbol.arguments)) if symbol.type == clingo.SymbolType.Function else None
    if term.ast_type == ast.ASTType.Function and term.name:
        return term.name, len(term.arguments)
    return None


def _head_atoms(node) -> list:
    """The symbols of the atoms a rule's head ``node`` may make true: a literal's; a choice's, a disjunction's
    or a head aggregate's elements' (their literals, not their conditions)."""
    kind = node.ast_type
    if kind == ast.ASTType.Literal:
        if node.atom.ast_type != ast.ASTType.SymbolicAtom:
            return []
        symbol = node.atom.symbol  # "movable(agent; toy)" is a pool of movable(agent) and movable(toy)
        return list(symbol.arguments) if symbol.ast_type == ast.ASTType.Pool else [symbol]
    if kind == ast.ASTType.ConditionalLiteral:
        return _head_atoms(node.literal)
    if kind in (ast.ASTType.Aggregate, ast.ASTType.Disjunction):
        return [a for element in node.elements for a in _head_atoms(element)]
    if kind == ast.ASTType.HeadAggregate:
        return [a for element in node.elements for a in _head_atoms(element.condition)]
    return []


@functools.cache
def _enable_python_scripts() -> None:
    """Let clingo run ``#script (python)`` blocks of a program allowed them: the clingo module leaves
    Python scripting off until asked (a program that is not allowed scripts is refused them when read)."""
    import clingo.script

    clingo.script.enable_python()
