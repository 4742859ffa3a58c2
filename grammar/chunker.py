"""Chunk-level fallback for word sequences the grammar cannot parse.

Reads the tagged words left to right: a verb opens a clause, a run of determiners, modifiers and
nouns forms a noun phrase (its last noun is the head; a run without one is headless), and the
preposition before a noun phrase is kept. Never fails: any sequence gives at least one clause.
"""

from __future__ import annotations

from .phrases import NP, PP, VP

# The preposition of a verb's second bare noun phrase ("give the robot the star"): none was said.
UNSAID_PREPOSITION = "_"
_NP_CATS = frozenset({"DET", "NUM", "ADJ", "COLOR", "NOUN", "MEASURE", "GER"})
_BREAK_CATS = frozenset({"COMMA", "CONJ", "SUB", "REL"})


def _is_verb(cats: frozenset[str], clause_start: bool, in_np: bool) -> bool:
    if not ({"VERB", "GER"} & cats):
        return False
    if cats <= {"VERB", "GER", "AUX", "ADJ", "SERIAL"}:  # SERIAL: a verb that may stand before another
        return True
    # a word that may also be a noun ("exit", "step") is a verb only where a clause may start
    return clause_start and not in_np


def chunk(words: list[str], cats: list[frozenset[str]]) -> tuple[VP, ...]:
    """Clauses of verbs with noun phrases and the prepositions before them. ``len(words) == len(cats)``."""
    clauses: list[VP] = []
    verb: str | None = None
    negated = False
    obj: NP | None = None
    comps: list = []
    adverbs: list[str] = []
    prep: str | None = None
    np_words: list[tuple[str, frozenset[str]]] = []
    clause_start = True

    def flush_np() -> None:
        nonlocal np_words, obj, prep
        if not np_words:
            return
        det = np_words[0][0] if "DET" in np_words[0][1] and len(np_words) > 1 else None
        body = [w for w, _ in (np_words[1:] if det else np_words)]
        body_cats = [c for _, c in (np_words[1:] if det else np_words)]
        if body and "NOUN" in body_cats[-1] | ({"NOUN"} if "MEASURE" in body_cats[-1] else set()):
            np = NP(det=det, mods=tuple(body[:-1]), head=body[-1])
        elif body and body_cats[-1] & {"PRON"}:
            np = NP(det=det, mods=tuple(body[:-1]), pron=body[-1])
        else:
            np = NP(det=det, mods=tuple(body))
        if prep is not None:
            comps.append(PP(prep, np))
        elif obj is None:
            obj = np
        else:
            comps.append(PP(UNSAID_PREPOSITION, np))  # a second bare noun phrase: related to the verb, relation unknown
        np_words = []
        prep = None

    def flush_clause() -> None:
        nonlocal verb, negated, obj, comps, adverbs, prep
        flush_np()
        if verb is not None or obj is not None or comps:
            clauses.append(VP(verb=verb, negated=negated, obj=obj, comps=tuple(comps), adverbs=tuple(adverbs)))
        verb, negated, obj, comps, adverbs, prep = None, False, None, [], [], None

    for word, c in zip(words, cats):
        if c & _BREAK_CATS and not c & _NP_CATS:
            flush_np()
            clause_start = True
            continue
        if _is_verb(c, clause_start, bool(np_words)):
            flush_clause()
            verb = word
            clause_start = False
            continue
        if "NEG" in c or ("AUX" in c and not c & _NP_CATS):
            negated = negated or "NEG" in c
            continue
        if "PRON" in c and not c & _NP_CATS:
            flush_np()
            np_words = [(word, c)]
            flush_np()
            clause_start = False
            continue
        if c & _NP_CATS and not (c & {"PREP", "TO"} and not np_words and "NOUN" not in c):
            np_words.append((word, c))
            clause_start = False
            continue
        if c & {"PREP", "TO"}:
            flush_np()
            prep = word
            clause_start = False
            continue
        if "ADV" in c:
            flush_np()
            adverbs.append(word)
            continue
        flush_np()  # anything else ends a noun phrase; the word stays in the logical form's words
    flush_clause()
    if not clauses:
        clauses.append(VP(adverbs=tuple(w for w, c in zip(words, cats) if "ADV" in c)))
    return tuple(clauses)
