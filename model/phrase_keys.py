"""What a command's noun phrases are keyed by for the alignment model: each phrase's preposition key
(``to+obj|last``, ``with@np``, ``not:to``), the key it backs off to, its bare preposition, and whether it
can name an object. The encoding (:mod:`groundlang.model.encoding`) reads them; the regularities each
key states are in :func:`entity_words`."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from groundlang.grammar.lexicon import Lexicon
from groundlang.grammar.logical_form import LogicalForm
from groundlang.model.domain_words import domain_lexicon
from groundlang.model.vocabulary import DIRECT_OBJECT, NEGATED_PREP, Vocabulary

__all__ = ["PhraseKeys", "entity_words", "backoff_key", "bare_preposition", "backoff_prep_ids", "is_referring"]


@dataclass(frozen=True)
class PhraseKeys:
    """Which marks a phrase's preposition key carries (the parse model's settings of these names; each
    on by default). What each measured: ABLATIONS.md."""

    # Commands end with where things go: the last phrase with words has a key of its own (``|last``).
    last_phrase_key: bool = True
    # A clause with a direct object says where the object goes, one without it where the agent goes:
    # a verb-attached phrase in a clause with a direct object has a key of its own (``+obj``).
    object_key: bool = True
    # A phrase saying where a motion starts or what goes along ("from ...", "with ...") never says where
    # it ends: ``|last`` passes over it to the phrase before.
    last_passes_over_source: bool = True
    # A phrase attached to another noun phrase ("the room *with the chair*") describes that phrase's object
    # rather than saying where things go: it has a key of its own (``@np``); off, the bare preposition.
    noun_attached_key: bool = True
    # A phrase in a negated clause ("do not enter *the green room*") says what not to do: it has a key of its
    # own (``not:``), so it may learn to align with nothing; off, the key the clause has unnegated.
    negation_key: bool = True
    # A phrase in a negated clause says where things must not go, so it is not where a command ends ("take
    # the star to the green room, but do not enter the green room"): ``|last`` passes over it too, in a fallback
    # chunk as well (ABLATIONS.md, thirty-eighth session: held-out likelihood against trusting only whole parses).
    last_passes_over_negated: bool = True


def entity_words(lf: LogicalForm, lexicon: Lexicon | None = None,
                 keys: PhraseKeys = PhraseKeys()) -> list[tuple[str | None, tuple[str, ...]]]:
    """(preposition key, modifiers, head) per entity of a logical form.

    The key is the preposition for a verb-attached phrase, ``prep@np`` for a
    phrase attached to another noun phrase (the two readings of "push the
    star into the green room" differ here) and None for a direct object.
    A verb-attached phrase in a clause with a direct object gets ``prep+obj``:
    "take the star *to* the red room" names where the object goes, "go *to*
    the red room" where the agent goes. Phrases in a negated clause ("do not
    enter the green room") get a ``not:`` prefix, so they may learn to align
    with nothing. The last phrase with words gets a ``|last`` suffix: commands
    end with where things go. A verb-attached phrase that says where a motion
    starts or what goes along ("from the blue room", "... go to the beige room
    *with the star*"; ``PREP_SOURCE`` of the word files; ``lexicon``, default
    :func:`domain_lexicon`) never says where things end, so ``|last`` passes
    over it to the phrase before. The object of a relative or participial clause about a noun phrase
    whose verb says what it holds ("the room *that has the chair*", "the room *containing the chair*";
    ``VERB_HAVING`` of the word files) is keyed as a noun-attached phrase of ``PREP_HAVING`` ("with":
    ``with@np``): it describes the noun phrase as "the room *with the chair*" does. ``keys`` switches the
    ``+obj`` and ``|last`` marks and the passing over (:class:`PhraseKeys`). What each of these measured:
    ABLATIONS.md.
    """
    lexicon = lexicon or domain_lexicon()
    passed_over = lexicon.source_and_comitative_prepositions if keys.last_passes_over_source else frozenset()
    having = _having_clauses(lf, lexicon)
    negated = {i for i, clause in enumerate(lf.clauses) if getattr(clause, "negated", False)}
    transitive = {entity.clause for entity in lf.entities if entity.role == "dobj"} if keys.object_key else set()
    result = []
    for entity in lf.entities:
        attached = "@np" if keys.noun_attached_key else ""
        if entity.role == "npp":
            key = f"{entity.prep}{attached}"
        elif entity.role == "dobj" and entity.clause in having:
            key = f"{lexicon.having_preposition}{attached}"
        elif entity.prep is not None:
            key = entity.prep + ("+obj" if entity.clause in transitive else "")
        else:
            key = None
        if entity.clause in negated and keys.negation_key:
            key = f"not:{key or 'dobj'}"
        result.append((key, tuple(entity.modifiers), (entity.head,) if entity.head else ()))
    if not keys.last_phrase_key:
        return result
    # Commands end with where things go ("..., then push it to the blue room"): the last
    # phrase with words gets its own key, ``|last``.
    for n in range(len(result) - 1, -1, -1):
        key, modifiers, head = result[n]
        entity = lf.entities[n]
        if entity.role == "vpp" and entity.prep in passed_over:
            continue
        if keys.last_passes_over_negated and entity.clause in negated:
            continue
        if modifiers or head:
            result[n] = (f"{key or 'dobj'}|last", modifiers, head)
            break
    return result


def _having_clauses(lf: LogicalForm, lexicon: Lexicon) -> set[int]:
    """Indices of the clauses of ``lf`` that describe a noun phrase by what it holds: a relative
    (``that``, ``which``, ...) or participial (``-ing``) clause about it whose verb is a verb of having
    (none when the word files name no preposition such a clause reads as)."""
    if lexicon.having_preposition is None:
        return set()
    return {i for i, clause in enumerate(lf.clauses)
            if clause.subject is not None and clause.verb in lexicon.having_verbs and not clause.negated
            and (clause.connective == "ing" or "REL" in lexicon.listed(clause.connective or ""))}


def backoff_key(key: str) -> str:
    """The key a preposition key backs off to: the same preposition without the marks of a clause
    with a direct object and of the last phrase (``onto+obj|last`` -> ``onto``, ``dobj|last`` ->
    ``<dobj>``); a negated or noun-attached phrase keeps its mark (``not:to``, ``to@np``)."""
    base = key.removesuffix("|last").replace("+obj", "")
    return DIRECT_OBJECT if base == "dobj" else base


def is_negated_key(key: str) -> bool:
    """Whether a preposition key is a phrase of a negated clause (``not:to``, ``not:dobj|last``, or one
    training never saw: ``NEGATED_PREP``)."""
    return key.startswith("not:") or key == NEGATED_PREP


def bare_preposition(key: str) -> str | None:
    """The preposition a phrase's key was made from, without the marks of its clause, place and
    attachment (``to+obj|last``, ``to@np``, ``not:to`` -> ``to``); None for a direct object."""
    bare = key.removeprefix("not:").removesuffix("|last").replace("+obj", "").removesuffix("@np")
    return None if bare in ("dobj", DIRECT_OBJECT) else bare


def backoff_prep_ids(vocab: Vocabulary) -> list[int]:
    """Per preposition key of ``vocab`` (by index), the index of the key it backs off to
    (:func:`backoff_key`); a key whose back-off key the vocabulary lacks backs off to itself."""
    return [vocab.prep_id(base) if (base := backoff_key(p)) in vocab.preps else n for n, p in enumerate(vocab.preps)]


def is_referring(modifiers: Sequence[str], head: Sequence[str], lexicon: Lexicon | None = None) -> bool:
    """Whether a noun phrase can *name* an object for the mention model: one with a head noun
    ("the door"), or whose modifiers include a colour word ("to orange") or an open-class word the
    lexicon (default: :func:`domain_lexicon`) does not list ("to periwinkle"). Judged on the words as
    written, before the vocabulary reads unseen ones as ``<unk>``. Closed-class modifiers alone ("on
    right", "straight", "a little") may still align with an object and be generated by it, but
    name none: before, any "on right" could stand for the star, so in a layout with a toy "go
    through door on right into blue room" read as moving it. The parse model's ``mention_phrases="any"``
    switches it off (every phrase with words names). Measured: ABLATIONS.md."""
    lexicon = lexicon or domain_lexicon()
    return bool(head) or any(lexicon.is_colour(w) or not lexicon.listed(w) for w in modifiers)
