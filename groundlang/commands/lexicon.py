"""``groundlang lexicon MODEL_DIR``: each word's most probable meanings.

The table gives each word its meanings, most probable first, as the model's
semantic tokens (``roomIsRed``, ``toyToRoom``, ``CLASS:room``, ``NULL``);
below it each token shown is explained once, in words read from the domain's
schema (:func:`groundlang.wording.token_meanings`), so a reader need not know
the names. ``--json`` prints ``{word: [[token, probability], ...]}`` only.

A relation is learned by the parse model as what its preposition says of the lifted task
(``P(preposition | L)``), not as a preposition word's token: the table ends with each preposition's
most probable lifted tasks, ``P(L | preposition)`` under a uniform prior over L
(:func:`groundlang.model.prepositions.preposition_tasks`); ``--prepositions`` prints that table alone.
"""

from __future__ import annotations

import argparse
import unicodedata

from groundlang.commands import as_typed, input_path, json_text, positive_int


def register(subparsers) -> None:
    p = subparsers.add_parser("lexicon", help="print the learned meanings of words")
    p.add_argument("model", type=input_path, metavar="MODEL_DIR", help="a folder written by 'groundlang train'")
    p.add_argument("--top", type=positive_int, default=3, help="meanings per word (default 3)")
    p.add_argument("--words", nargs="*", metavar="WORD", help="only these words (default: every word the model knows)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object {word: [[meaning, probability], ...]} instead of a table")
    p.add_argument("--prepositions", action="store_true",
                   help="the prepositions' table only: the lifted tasks each says, P(task | preposition) (the parse "
                        "model's; with --json, {preposition: [[task, probability], ...]})")
    p.set_defaults(func=run)


# The table's column headings.
WORD_HEADING, MEANINGS_HEADING = "word", "meanings, most probable first"


def _schemas(learner) -> list:
    """The schemas of the palettes the model was trained on (a model saved without them: the default's)."""
    from groundlang.logic.schema import domain_schema
    from groundlang.model.palette import Palette
    from groundlang.training_vocabulary import palette_schema

    if not learner.palettes:
        return [domain_schema(learner.library)]
    return [palette_schema(learner.library, Palette.from_record(p)) for p in learner.palettes]


def _columns(text: str) -> int:
    """The screen columns ``text`` takes: a wide (CJK) character two, a combining mark none."""
    return sum(0 if unicodedata.combining(c) else 2 if unicodedata.east_asian_width(c) in "WF" else 1 for c in text)


def _padded(text: str, width: int) -> str:
    return text + " " * max(0, width - _columns(text))


def _print_prepositions(prepositions: dict, learner) -> None:
    if not prepositions:
        if not hasattr(learner.lm, "preposition_concentration"):
            why = f"the model's language model, {learner.lm.name}, has none"
        elif learner.lm.preposition_concentration is None:
            why = "its preposition_concentration is off"
        else:
            why = "none of the prepositions asked was seen in training"
        print(f"no preposition table: {why}")
        return
    width = max(16, *(_columns(p) + 1 for p in prepositions))  # multiword ones: to_the_right_side_of
    print(f"{'preposition':<{width}} lifted tasks it says, most probable first")
    for prep, tasks in prepositions.items():
        print(f"{_padded(prep, width)} {', '.join(f'{t} {q:.2f}' for t, q in tasks)}")


def _as_read(words: str, word_lexicon) -> list[tuple[str, str]]:
    """(the words as typed, the word read) for each word of ``words`` as a command reads them: "crimson" is
    read as red, "east of" as "right of" ("next to" stays spaced), "took" as take. Where the tokeniser's own splits
    (hyphens, clitics, colour compounds) leave no one-to-one line between the two, each word is its label."""
    from groundlang.grammar.parser import tokenise, typed_words

    tokens = [t for t in tokenise(words, word_lexicon) if any(c.isalnum() for c in t)]
    unlabelled = [(t.replace("_", " "), t.replace("_", " ")) for t in tokens]
    pieces = [(piece, typed) for typed in typed_words(words) if any(c.isalnum() for c in typed)
              for piece in word_lexicon.read_as(typed)]
    out, i = [], 0
    for token in tokens:
        parts = token.split("_")
        chunk = pieces[i:i + len(parts)]
        if [piece for piece, _ in chunk] != parts:
            return unlabelled
        i += len(parts)
        out.append((" ".join(dict.fromkeys(typed for _, typed in chunk)), " ".join(parts)))
    out = unlabelled if len({label for label, _ in out}) < len(set(out)) else out  # one typed word, two rows
    # a verb's forms are read as its lemma, as a command's verb is ("took" is take): it had been "unknown"
    return [(label, word if " " in word else word_lexicon.lemma(word)) for label, word in out]


def _as_known(word: str, vocab) -> str:
    """The known word the model reads ``word`` as: itself, or the word a misspelling is one edit from ("gren" as
    green, :meth:`Vocabulary.word_id`), as following reads it; a word it cannot place stays itself."""
    index = vocab.word_id(word) if " " not in word else 0
    return vocab.words[index] if index else word


def run(args: argparse.Namespace) -> int:
    from groundlang.learner import Learner
    from groundlang.model.prepositions import preposition_tasks
    from groundlang.grammar.parser import utf8_fault
    from groundlang.wording import token_meanings

    learner = Learner.load(args.model)
    rows: dict[str, str] = {}  # each row's label (the word as asked) -> the word it is read as
    if args.words == []:  # "--words $(cat empty-file)": showing every word would answer another question
        raise ValueError("--words: no word given; give the words to show, e.g. --words red room (or leave out "
                         "--words for every word)")
    if args.words is not None:  # read as a command is: "RED" is red, "chair." chair; "next to" stays spaced, as
        for w in args.words:  # a preposition's row sends it to the preposition table
            if fault := utf8_fault(w):  # its bytes would split the word where they stand
                raise ValueError(f"--words {as_typed(w)}: it {fault}")
            labelled = _as_read(w, learner.word_lexicon)
            if not labelled:
                raise ValueError(f"--words {w!r}: no word in it; give the words to show, e.g. --words red room")
            for label, token in labelled:  # a word file's synonym ("crimson", "east of") labels its word's row
                rows.setdefault(label, _as_known(token, learner.vocab))
        args.words = list(dict.fromkeys(rows.values()))
    prepositions = learned = preposition_tasks(learner.globals, learner.vocab, top=args.top)
    if args.words:  # a multiword preposition is one token: "next to" is next_to
        asked = {"_".join(w.split()) for w in args.words}
        prepositions = {p: tasks for p, tasks in prepositions.items() if p in asked}
    if args.prepositions:
        if args.json:
            print(json_text({p: [[t, q] for t, q in tasks] for p, tasks in prepositions.items()}))
        else:
            _print_prepositions(prepositions, learner)
        return 0
    lexicon = learner.lexicon(top=args.top)
    if not args.words:
        rows = {w: w for w in lexicon}
    if args.json:  # keyed as asked: {"crimson": ...} for a synonym of red
        print(json_text({label: [[t, p] for t, p in lexicon.get(w, [])] for label, w in rows.items()}))
        return 0
    shown_as = {label: label if label == word else f"{label} = {word}" for label, word in rows.items()}
    width = max([16, *(_columns(shown) + 1 for shown in shown_as.values())])  # "biggest = largest" fits its column
    print(f"{WORD_HEADING:<{width}} {MEANINGS_HEADING}")
    for label, word in rows.items():
        meanings = lexicon.get(word, [])
        preposition = "_".join(word.split()) in prepositions  # learned in the preposition table below
        # "corner" unknown alone, yet read inside the learned preposition to_the_corner_of
        within = sorted(p for p in learned if word in p.split("_"))
        text = (", ".join(f"{token} {p:.2f}" for token, p in meanings)
                or ("(a preposition: see the table below)" if preposition
                    else f"(unknown word alone; learned within {', '.join(within[:3])})" if within
                    else "(unknown word)"))
        print(f"{_padded(shown_as[label], width)} {text}")  # "crimson = red": read as red
    if prepositions:  # relations are learned there, not as a preposition word's tokens above
        print()
        _print_prepositions(prepositions, learner)
    # Each name once, in the order the table first shows it: the table stays compact and scannable.
    explained = token_meanings((t for w in rows.values() for t, _ in lexicon.get(w, [])), _schemas(learner),
                                learner.library.phrases)
    if explained:
        width = max(len(t) for t in explained)
        print("\nwhat the meanings are:")
        for token, text in explained.items():
            print(f"  {token:<{width}}  {text}")
    return 0
