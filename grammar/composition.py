"""Semantic composition: phrase values to logical forms, and instantiation through a semantic lexicon.

Variables are named as in the paper, head noun plus a counter (star1, room1); a headless noun phrase
takes its last modifier (green1), a pronoun its own word (it1), anything else x1.
"""

from __future__ import annotations

import itertools
import re
from collections import Counter
from dataclasses import replace

from .lexicon import Lexicon, SemanticLexicon
from .logical_form import Clause, Entity, LogicalForm, Relation
from .phrases import NP, PP, VP, Adv, ClauseValue, Measure, Sub, top_k

_NOT_IDENT = re.compile(r"[^0-9a-z]+")


class _Composer:
    def __init__(self, lexicon: Lexicon) -> None:
        self.lexicon = lexicon
        self.entities: list[Entity] = []
        self.clauses: list[Clause | None] = []
        self.attachments: list[tuple[str, str, str]] = []
        self.counters: Counter[str] = Counter()
        self.queue: list[tuple[ClauseValue, str | None, str | None]] = []

    def fresh(self, base: str | None) -> str:
        name = _NOT_IDENT.sub("", (base or "").lower())
        if not name or name[0].isdigit():
            name = "x" + name
        self.counters[name] += 1
        return f"{name}{self.counters[name]}"

    def add_clause(self, value: ClauseValue, connective: str | None = None, subject: str | None = None) -> None:
        introduced_by = None
        while isinstance(value, Sub):
            connective = value.connective if connective is None else f"{connective} {value.connective}"
            introduced_by, value = value.connective, value.clause
        vp: VP = value
        if introduced_by in self.lexicon.negating_prepositions:
            vp = replace(vp, negated=True)  # "without going into the tan room": the going is not to be done
        idx = len(self.clauses)
        self.clauses.append(None)
        if vp.subject is not None:
            subject = self.add_np(vp.subject, idx, "subj")[0]
        args: list[str] = []
        preps: list[tuple[str, str]] = []
        adverbs = list(vp.adverbs)
        pending: list[Sub] = []
        if vp.obj is not None:
            args += self.add_np(vp.obj, idx, "dobj")
        for comp in vp.comps:
            if isinstance(comp, PP):
                objs = self.add_np(comp.obj, idx, "vpp", prep=comp.prep)
                args += objs
                preps += [(comp.prep, v) for v in objs]
            elif isinstance(comp, Adv):
                adverbs.append(comp.word)
            elif isinstance(comp, Measure):
                self.add_np(comp.np, idx, "measure")
            elif isinstance(comp, Sub):
                pending.append(comp)
        verb = self.lexicon.lemma(vp.verb) if vp.verb is not None else None
        self.clauses[idx] = Clause(verb, tuple(args), tuple(preps), vp.negated, subject, connective, tuple(adverbs))
        queued, self.queue = self.queue, []
        for sub in pending:
            self.add_clause(sub)
        for clause, conn, subj in queued:
            self.add_clause(clause, conn, subj)

    def add_np(self, np: NP, clause: int, role: str, prep: str | None = None, parent: str | None = None) -> list[str]:
        if np.conjuncts:
            out: list[str] = []
            for part in np.conjuncts:
                out += self.add_np(part, clause, role, prep, parent)
            self._attach(np.attached, out[-1], clause)
            return out
        base = np.head or (np.mods[-1] if np.mods else None) or np.pron or "x"
        var = self.fresh(base)
        self.entities.append(Entity(var, np.head, np.mods, np.det, clause, role, prep, parent, np.pron))
        self._attach(np.attached, var, clause)
        return [var]

    def _attach(self, attached: tuple, var: str, clause: int) -> None:
        for item in attached:
            if isinstance(item, PP):
                for obj in self.add_np(item.obj, clause, "npp", prep=item.prep, parent=var):
                    self.attachments.append((item.prep, var, obj))
            else:  # relative or participial clause about this noun phrase, after the current clause
                self.queue.append((item.clause, item.connective, var))

    def relations(self) -> list[Relation]:
        out: list[Relation] = []
        p_index = 0
        by_obj = {obj: (prep, head) for prep, head, obj in self.attachments}
        # Entities grouped by clause once: scanning every entity per clause made a long command quadratic.
        by_clause: dict[int, list] = {}
        for ent in self.entities:
            by_clause.setdefault(ent.clause, []).append(ent)
        for idx, clause in enumerate(self.clauses):
            assert clause is not None
            out.append(Relation(clause.verb or "_", clause.args, clause.verb, "verb", clause.negated))
            for ent in by_clause.get(idx, ()):
                if ent.head is not None:
                    out.append(Relation("isa", (ent.var, ent.head), ent.head, "isa"))
                for mod in ent.modifiers:
                    p_index += 1
                    out.append(Relation(f"P{p_index}", (ent.var, mod), mod, "modifier"))
                if ent.var in by_obj:
                    prep, head = by_obj[ent.var]
                    out.append(Relation(prep, (head, ent.var), prep, "prep"))
        return out


def compose(clauses: tuple[ClauseValue, ...], words: tuple[str, ...], tags: tuple[str, ...],
            fallback: bool, lexicon: Lexicon | None = None) -> LogicalForm:
    """The logical form of a sequence of clause values (all sentences of one command, in order); the
    lexicon (default: English) gives verb lemmas and the prepositions that negate the clause they introduce."""
    comp = _Composer(lexicon or Lexicon.english())
    for value in clauses:
        comp.add_clause(value)
    relations = comp.relations()
    return LogicalForm(
        clauses=tuple(c for c in comp.clauses if c is not None),
        entities=tuple(comp.entities),
        relations=tuple(relations),
        attachments=tuple(comp.attachments),
        words=words,
        tags=tags,
        fallback=fallback,
    )


def instantiate(lf: LogicalForm, lexicon: SemanticLexicon, beam: int) -> list[tuple[float, LogicalForm]]:
    """Readings of ``lf`` with known words' predicates instantiated, each with its probability.

    A verb ``push(star1, room1)`` becomes ``toyToRoom(star1, room1)``, ``isa(star1, star)`` becomes
    ``toyIsStar(star1)`` and ``P1(room1, green)`` becomes ``roomIsGreen(room1)``; words the lexicon
    does not know (or the probability mass it leaves) keep the uninstantiated relation.
    """
    options: list[list[tuple[float, Relation]]] = []
    for rel in lf.relations:
        if rel.kind not in ("verb", "isa", "modifier") or rel.word is None:
            options.append([(1.0, rel)])
            continue
        alts = []
        for pf, prob in lexicon.choices(rel.word):
            if pf is None:
                alts.append((prob, rel))
            elif rel.kind == "verb":
                alts.append((prob, Relation(pf, rel.args, rel.word, "verb", rel.negated, prob)))
            else:
                alts.append((prob, Relation(pf, rel.args[:1], rel.word, rel.kind, False, prob)))
        options.append(alts)
    partial: list[tuple[float, tuple[Relation, ...]]] = [(1.0, ())]
    for alts in options:
        partial = top_k([(p1 * p2, rels + (r,)) for (p1, rels), (p2, r) in itertools.product(partial, alts)], beam)
    return [(p, lf.with_relations(rels)) for p, rels in partial]
