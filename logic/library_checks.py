"""What a task library's own solve says of its PF classes, and the checks of restrict/3 made when it is loaded:
the part each PF class plays (``goal_class/1``, ``viewpoint_class/1`` of pfs.lp or a library), and whether
a restriction names a property PF of its variable's class."""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Sequence
from dataclasses import dataclass

import clingo
from clingo import ast

from .program import AspError, Program, term_signature
from .terms import pf_name, symbol_text, tuple_args

__all__ = ["PFRoles", "Declarations", "declare", "declare_families", "read_pf_roles", "restriction_problem",
           "check_tasks_declared_once", "check_pfs_declared_once", "check_domain_left_alone", "read_phrases"]

_PLACE = re.compile(r"\{(\d+)\}")  # "{1}": a phrase's place for a PF's first argument


def read_phrases(atoms: Sequence[clingo.Symbol], declared: "Declarations", where: str) -> dict[str, str]:
    """``phrase(PF, "words")`` atoms as ``{PF name: words}``: how a person reads the PF. Words with places
    ``{1}``, ``{2}``, ... for its arguments read an atom (``"{1} in a corner of {2}"``); words without
    them describe the one object a PF of one argument holds of (``"shiny"``). AspError starting with
    ``where`` for a PF named twice, words that are not a non-empty string, or places that are not
    ``{1}`` to ``{n}`` of a PF of n arguments, each once."""
    out: dict[str, str] = {}
    for atom in sorted(atoms):
        term, text = atom.arguments
        if term.type is not clingo.SymbolType.Function or text.type is not clingo.SymbolType.String \
                or not text.string.strip():
            raise AspError(f'{where}: {atom} is not phrase(PF, "words") with a PF and words in quotes')
        if any(unicodedata.category(c) in ("Cc", "Zl", "Zp") for c in text.string):
            # printed in every goal line and saved in models: a newline or an escape would forge output
            raise AspError(f"{where}: {atom}: the words hold a control character (a line break, a tab, an escape); "
                           "a phrase is one line of plain text")
        name = pf_name(term)
        if term not in declared:  # a family's member (toyIs(wood)) was declared with its values: declare_families
            spelled = next((t for t in declared if pf_name(t) == name), None)
            if spelled is not None:  # agentIn(room) spells agentInRoom, a PF of its own, not a family's member
                raise AspError(f"{where}: {atom}: no family declares {term}; the PF {name} is pf/3's {spelled}: "
                               f"write phrase({spelled}, ...)")
            raise AspError(f"{where}: {atom}: no pf/3 declares a PF {name}")
        if name in out:
            raise AspError(f"{where}: PF {name} has two phrases, {out[name]!r} and {text.string!r}")
        # A place of more digits than any PF has arguments is out of range as it is: never converted.
        places = [int(p) if len(p) < 4 else 1000 for p in _PLACE.findall(text.string)]
        arities = {len(sig) for _, sig in declared[term]}
        arity = arities.pop() if len(arities) == 1 else None
        if places or (arity or 1) > 1:
            n = arity or len(places)
            if sorted(places) != list(range(1, n + 1)):
                raise AspError(f"{where}: {atom}: the words of a PF of {n} argument{'s' * (n > 1)} have the places "
                               f"{', '.join('{%d}' % k for k in range(1, n + 1))}, each once")
        out[name] = text.string
    return out

_TASK_FACT = re.compile(r'task\(("?)([^"()]+)\1\)\.')


def check_tasks_declared_once(program: Program) -> None:
    """AspError naming both files where two sources of ``program`` declare a task of one name (``task(t).``):
    its var/3 and goal/3 atoms would join into one task (a user's task over the package's one of that name:
    a goal of both), where a task of its own was meant. Within one file, a task's atoms are written as meant."""
    declared: dict[str, str] = {}
    for source, statements in program.statements_by_source():
        names = {m.group(2) for stm in statements if (m := _TASK_FACT.fullmatch(str(stm)))}
        for name in sorted(names):
            if (first := declared.setdefault(name, source.name)) != source.name:
                raise AspError(f"task {name} is declared in both {first} and {source.name}: its atoms would join "
                               "into one task; rename the task of one of them")


def check_pfs_declared_once(program: Program) -> None:
    """AspError naming both files (or one, twice) where a PF of one name is declared with two classes or signatures
    (``pf(position, agentInRoom, (agent, toy)).`` beside ``pfs.lp``'s ``(agent, room)``), in a fact or a rule's
    head: its holds/2 rules would answer for both, and the error came later, blaming a task of another file for
    its arguments' classes."""
    declared: dict[str, tuple[str, str, str]] = {}
    for where, term in program.head_atoms():
        if term_signature(term) != ("pf", 3) or term.ast_type != ast.ASTType.Function:
            continue
        cls, name, signature = (re.sub(r"\s+", "", str(a)).replace(",", ", ").replace(", )", ",)")
                                for a in term.arguments)
        first = declared.setdefault(name, (cls, signature, where))
        if first[:2] != (cls, signature):
            raise AspError(f"PF {name} is declared as pf({first[0]}, {name}, {first[1]}) in {first[2]} and as "
                           f"pf({cls}, {name}, {signature}) in {where}: a PF has one class and one signature; give "
                           "one of them another name")


def _placeholders(signature) -> str:
    """``(A, B)`` for a pf/3 signature of two classes, as a holds/2 rule writes its objects."""
    count = len(signature.arguments) if signature.ast_type == ast.ASTType.Function and not signature.name else 1
    return "(" + ", ".join("ABCDEFGH"[:count]) + ("," if count == 1 else "") + ")"


def check_domain_left_alone(program: Program, domain: str = "groundlang.logic/domain.lp",
                            reads: tuple[str, ...] = ("groundlang.logic/domain.lp", "groundlang.logic/pfs.lp")) -> None:
    """AspError naming the file and atom where a user's rule makes true a predicate ``domain`` defines (its rule
    heads: ``movable/1``, ``walkable/2``, ``class/1`` ...) or one of the layout's facts (what the ``reads`` files
    read and no file of the package defines: ``room/1``, ``at/3``, ``rect/5`` ...; a palette's ``palette_*`` values
    aside): the world's dynamics (walls, doors, pushing) are code that reads the layout, not these atoms, so the PF
    tables and the moves would silently disagree."""
    heads = [(where, term, term_signature(term)) for where, term in program.head_atoms()]
    own = {sig for where, _, sig in heads if where == domain} - {None}
    package = {sig for where, _, sig in heads if where.startswith("groundlang.")}
    facts = {sig for sig in program.body_signatures(reads) - package if not sig[0].startswith("palette_")}
    theirs = own | facts
    for where, term, signature in heads:
        if not where.startswith("groundlang.") and signature in theirs:
            whose = (f"the domain's own ({domain}), which the world's moves follow without reading it" if signature
                     in own else "a fact of the layout, given with each state, which the world's moves read from it")
            raise AspError(f"{where}: {term}: {signature[0]}/{signature[1]} is {whose}; a library adds PFs and tasks, "
                           "not to it")


def check_pfs_said_to_hold(program: Program) -> None:
    """AspError naming the file where a PF is declared (pf/3) but no rule head says where it holds (holds/2 of
    its name, a ``#const`` naming it, or an ``#external``): it would hold nowhere, and a task made of it could
    never be done (a rule written holds/3 had trained without a word). A holds/2 head whose PF is a variable or
    a script's call may say it of any, and passes all."""
    constants = program.constants()
    declared: dict[tuple[str, int], tuple[str, str, object]] = {}
    said, other, open_head = set(), {}, False
    for where, term in program.head_atoms():
        signature = term_signature(term)
        if term.ast_type != ast.ASTType.Function or signature is None or (signature != ("pf", 3)
                                                                           and signature[0] != "holds"):
            continue
        if term.arguments[0].ast_type == ast.ASTType.SymbolicTerm and str(term.arguments[0]) in constants:
            key = term_signature(ast.SymbolicTerm(term.location, clingo.parse_term(constants[str(term.arguments[0])])))
        else:
            key = term_signature(term.arguments[0 if term.name == "holds" else 1])
        if term.name == "pf":
            if key is not None:
                declared.setdefault(key, (where, str(term.arguments[1]), term.arguments[2]))
        elif len(term.arguments) != 2:
            other.setdefault(key, len(term.arguments))
        elif key is None:
            open_head = True
        else:
            said.add(key)
    if open_head:
        return
    for key, (where, written, signature) in declared.items():
        if key not in said:
            objects = _placeholders(signature)
            hint = (f"; a rule says holds/{other[key]} of it, but holds takes the PF and the tuple of its objects, "
                    f"holds({written}, {objects})" if key in other else f"; add holds({written}, {objects}) :- ... for it")
            raise AspError(f"{where}: PF {written} is declared (pf/3) but no rule says where it holds{hint}")


@dataclass(frozen=True)
class PFRoles:
    """The part each PF class plays (``goal_class/1`` and ``viewpoint_class/1``, pfs.lp or a library's own):
    goals are made of a goal class's PFs; a viewpoint class's describe an object as seen from the agent at
    the start; every other class is a property (what an object is: restrict/3 may name one)."""

    goal_classes: frozenset[str] = frozenset()
    viewpoint_classes: frozenset[str] = frozenset()

    def property_class(self, cls: str) -> bool:
        return cls not in self.goal_classes and cls not in self.viewpoint_classes

    def part(self, cls: str) -> str:
        """``goal``, ``viewpoint`` or ``property``: the part PF class ``cls`` plays."""
        if cls in self.goal_classes:
            return "goal"
        return "viewpoint" if cls in self.viewpoint_classes else "property"


def read_pf_roles(by_signature: dict[tuple[str, int], list[clingo.Symbol]], where: str) -> PFRoles:
    """The PF roles among a library's shown atoms (by name and arity); AspError starting with ``where`` for
    a class named by a string or a number (the rules of groundings.lp would read it as another class than
    pf/3's), or of two parts (a goal's PFs are tabulated, a viewpoint's never)."""
    parts = {}
    for part in ("goal_class", "viewpoint_class"):
        for atom in by_signature.get((part, 1), []):
            if atom.arguments[0].type is not clingo.SymbolType.Function or atom.arguments[0].arguments:
                raise AspError(f"{where}: {atom}: a PF class is a name as pf/3 writes it, such as {part}(position)")
        parts[part] = frozenset(str(a.arguments[0]) for a in by_signature.get((part, 1), []))
    if both := sorted(parts["goal_class"] & parts["viewpoint_class"]):
        raise AspError(f"{where}: PF class {both[0]} is declared both goal_class and viewpoint_class; a class "
                       "plays one part (goals are made of where objects are, not of how they look from the start)")
    return PFRoles(parts["goal_class"], parts["viewpoint_class"])


# A palette_A/1 atom in a library's text: the families over an attribute's values (comments too, harmlessly).
_PALETTE_ATOM = re.compile(r"\bpalette_([a-z][A-Za-z0-9_]*)\s*\(")

# PF term -> its declarations: (PF class, classes of its arguments), one per pf/3 atom.
Declarations = dict[clingo.Symbol, list[tuple[str, tuple[str, ...]]]]


def declare(declared: Declarations, pf_atom: clingo.Symbol) -> None:
    cls_, name, sig = pf_atom.arguments
    declared.setdefault(name, []).append((symbol_text(cls_), tuple(symbol_text(s) for s in tuple_args(sig))))


def declare_families(program: Program, named: Sequence[clingo.Symbol], declared: Declarations,
                     time_limit: float | None) -> None:
    """Add to ``declared`` the pf/3 atoms of the PFs ``named`` (by restrict/3 or phrase/2) that only an
    environment declares.

    Property PFs are families over the environment's palette (``pf(colour, roomIs(C), (room,))
    :- palette_colour(C)``; a palette's added attribute ``material`` has ``palette_material/1``), so the
    library solved alone declares none of them. One more solve, with the values the restrictions name
    added as values of every attribute the library's files name a ``palette_A/1`` of, declares those that exist,
    so that a family of the wrong class (``roomIs(red)`` on a toy) is refused at load time. Whether a
    value is in a given environment's palette is that environment's business: :func:`ground_environment`
    refuses a restriction the environment cannot honour.
    """
    missing = {p for p in named if p not in declared and p.type is clingo.SymbolType.Function}
    values = sorted({str(x) for p in missing for x in p.arguments})
    if not values:
        return
    attributes = sorted({"colour", "shape"} | {a for source in program.sources for a in _PALETTE_ATOM.findall(source.text)})
    probe = "".join(f"palette_{a}({x}).\n" for x in values for a in attributes)
    models = program.solve(probe, models=1, time_limit=time_limit)
    if not models:
        raise AspError(f"{program.user_names}: the task library has no answer set once the palette values its "
                       f"restrict/3 and phrase/2 PFs name ({', '.join(values)}) are added, so they cannot be checked")
    for a in models[0]:
        if a.name == "pf" and len(a.arguments) == 3 and a.arguments[1] in missing:
            declare(declared, a)


def restriction_problem(term: clingo.Symbol, var: str, cls: str,
                         declarations: Sequence[tuple[str, tuple[str, ...]]], roles: PFRoles) -> str | None:
    """What is wrong with restricting variable ``var`` of class ``cls`` by PF ``term``, declared as
    ``declarations`` (not empty); None: nothing."""
    usable = [(c, sig) for c, sig in declarations if roles.property_class(c)]
    wanted = f"a property PF (colour, shape: a class neither goal_class/1 nor viewpoint_class/1) of one {cls}"
    if not usable:
        found = {c for c, _ in declarations}
        classes = " and ".join(sorted(found))
        hint = " (a goal's PF belongs in goal/3)" if found & roles.goal_classes else ""
        return f"PF {term} is a {classes} PF; restrict needs {wanted}{hint}"
    if all(sig != (cls,) for _, sig in usable):
        classes = " and ".join(sorted({c for c, _ in usable}))
        sigs = " or ".join(sorted({"(" + ", ".join(sig) + ("," if len(sig) == 1 else "") + ")"
                                   for _, sig in usable}))
        return (f"PF {term} is a {classes} PF of arguments {sigs}, but variable {var!r} is a {cls}; "
                f"restrict needs {wanted}")
    return None
