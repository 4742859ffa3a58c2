"""Logical forms: conjunctions of atomic predicates over variables, as the paper prints them.

Before training the parser knows syntax only, so the relation between a modifier and its noun is an
uninstantiated predicate ``P1(room1, green)``; with a semantic model it becomes ``roomIsGreen(room1)``.
The joint model reads, per reading: the clauses in order (verb lemma, arguments, the prepositions that
introduced them), the entities (variable, head noun, modifiers, role) and the noun-attached PPs.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

# Entity roles: direct object of a clause's verb, object of a PP attached to the verb, object of a PP
# attached to another noun phrase, subject of a (relative or subordinate) clause, or an adverbial
# measure phrase ("all way", "three steps").
ROLES = ("dobj", "vpp", "npp", "subj", "measure")


@dataclass(frozen=True)
class Entity:
    """A noun phrase's variable. ``head`` is None for fragments ("go to green") and pronouns."""

    var: str
    head: str | None
    modifiers: tuple[str, ...]
    determiner: str | None
    clause: int
    role: str
    prep: str | None = None
    parent: str | None = None  # for role "npp": the variable of the noun phrase the PP attaches to
    pronoun: str | None = None

    def to_json(self) -> dict:
        return {
            "var": self.var, "head": self.head, "modifiers": list(self.modifiers), "determiner": self.determiner,
            "clause": self.clause, "role": self.role, "prep": self.prep, "parent": self.parent,
            "pronoun": self.pronoun,
        }


@dataclass(frozen=True)
class Relation:
    """An atomic predicate. ``kind``: "verb", "isa", "modifier" or "prep"; ``word``: the word it came from."""

    name: str
    args: tuple[str, ...]
    word: str | None = None
    kind: str = "modifier"
    negated: bool = False
    probability: float = 1.0  # P(name | word) from the semantic lexicon; 1.0 when uninstantiated

    @property
    def instantiated(self) -> bool:
        """True when a semantic model gave this relation a domain meaning."""
        return self.word is not None and self.name != self.word and not (
            self.kind == "modifier" and self.name.startswith("P") and self.name[1:].isdigit()
        ) and not (self.kind == "isa" and self.name == "isa")

    def __str__(self) -> str:
        text = f"{self.name}({', '.join(self.args)})"
        return f"not {text}" if self.negated else text

    def to_json(self) -> dict:
        return {"name": self.name, "args": list(self.args), "word": self.word, "kind": self.kind,
                "negated": self.negated}


@dataclass(frozen=True)
class Clause:
    """One verb clause. ``args``: direct object(s) first, then objects of verb-attached PPs.

    ``verb`` is the lemma (None for verbless fragments such as "star to tan"); ``connective`` names the
    word that subordinates the clause ("until", "without", "that", "to") or is None for a main clause.
    """

    verb: str | None
    args: tuple[str, ...]
    preps: tuple[tuple[str, str], ...]
    negated: bool = False
    subject: str | None = None
    connective: str | None = None
    adverbs: tuple[str, ...] = ()

    def to_json(self) -> dict:
        return {"verb": self.verb, "args": list(self.args), "preps": [list(p) for p in self.preps],
                "negated": self.negated, "subject": self.subject, "connective": self.connective,
                "adverbs": list(self.adverbs)}


@dataclass(frozen=True)
class LogicalForm:
    """A reading of a command: clauses in order, entities, relations, noun-attached PPs, the tokens.

    ``attachments``: (preposition, head var, object var) for PPs attached to a noun phrase.
    ``tags``: the lexical categories guessed for each token ("ADJ|NOUN" for an unknown word).
    ``fallback``: some sentence did not parse with the grammar and was chunked instead.
    """

    clauses: tuple[Clause, ...]
    entities: tuple[Entity, ...]
    relations: tuple[Relation, ...]
    attachments: tuple[tuple[str, str, str], ...]
    words: tuple[str, ...]
    tags: tuple[str, ...] = ()
    fallback: bool = False

    def entity(self, var: str) -> Entity:
        """The entity with this variable; KeyError if none."""
        for ent in self.entities:
            if ent.var == var:
                return ent
        raise KeyError(f"logical form has no entity {var!r}")

    @property
    def verbs(self) -> tuple[str, ...]:
        """Verb lemmas in clause order (verbless clauses skipped)."""
        return tuple(c.verb for c in self.clauses if c.verb is not None)

    def paper_str(self) -> str:
        """The paper's printing: ``push(star1, room1), P1(room1, green)``.

        Uninstantiated ``isa`` relations are left out (the variable name carries the head noun); a
        verbless clause prints as ``_(args)``.
        """
        parts = [str(r) for r in self.relations if not (r.kind == "isa" and r.name == "isa")]
        return ", ".join(parts)

    def __str__(self) -> str:
        return self.paper_str()

    def with_relations(self, relations: tuple[Relation, ...]) -> "LogicalForm":
        return replace(self, relations=relations)

    def to_json(self) -> dict:
        return {
            "logical_form": self.paper_str(),
            "clauses": [c.to_json() for c in self.clauses],
            "entities": [e.to_json() for e in self.entities],
            "relations": [r.to_json() for r in self.relations],
            "attachments": [list(a) for a in self.attachments],
            "words": list(self.words),
            "tags": list(self.tags),
            "fallback": self.fallback,
        }


@dataclass(frozen=True)
class Reading:
    """A logical form with its probability among the command's readings (they sum to one)."""

    logical_form: LogicalForm
    probability: float

    def to_json(self) -> dict:
        return {"logical_form": self.logical_form.paper_str(), "probability": self.probability,
                "fallback": self.logical_form.fallback}
