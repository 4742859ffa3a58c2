"""Word categories for command parsing, and the semantic-model hook.

The parser knows no meanings, only syntax: closed-class words (determiners,
prepositions, conjunctions, pronouns, auxiliaries) and the common verbs and
nouns of the domain are listed; every other word is guessed from its suffix
and position. A word may carry several categories ("left" is an adverb, an
adjective and a noun); the grammar decides which one a reading uses.

``SemanticLexicon`` is the paper's semantic model (LWFG's Phi_i constraints):
words mapped to domain propositional functions with probabilities, learned
later by the joint model and handed to ``parse``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

# Lexical categories (the grammar's terminals are sets of these).
CATEGORIES = (
    "ADJ", "ADV", "AUX", "COLOR", "COMMA", "CONJ", "DET", "GER", "MEASURE",
    "NEG", "NOUN", "NUM", "PREP", "PRON", "REL", "SUB", "TO", "VERB",
)

DETERMINERS = frozenset(
    "the a an this that these those your my his her its their our another some any each every all "
    "no both either neither such".split()
)
PREPOSITIONS = frozenset(
    "to into in from through thru throught toward towards onto on at of with by inside outside near past "
    "above below behind under over between across along around within without via beside besides beyond "
    "underneath beneath upon against out up down off like than unto till until next".split()
)
# Prepositions that also stand alone as adverbial particles ("go up", "push it down", "stop just inside").
PARTICLES = frozenset("up down out in inside outside over around back along off through across past below above behind".split())
CONJUNCTIONS = frozenset("and n & or / but then nor plus".split())
SUBORDINATORS = frozenset("until till when while once where if because before after so as whilst unless whereas".split())
RELATIVES = frozenset("that which who where".split())
PRONOUNS = frozenset(
    "it you him her them me us i he she they yourself itself himself herself themselves myself one "
    "there re here".split()
)
AUXILIARIES = frozenset("would will should can could must may might do does did shall have has had".split())
NEGATIONS = frozenset("not don't dont never doesn't didn't can't cant won't wont shouldn't n't no".split())
# Prepositions that negate the gerund clause they introduce: "without going into the tan room".
NEGATING_PREPOSITIONS = frozenset({"without"})
# Prepositions whose verb-attached phrase says where a motion starts or what goes along with the mover
# ("go from the blue room ...", "... and go to the beige room with the star"), never where it ends.
SOURCE_AND_COMITATIVE_PREPOSITIONS = frozenset({"from", "with"})
NUMBERS = frozenset(
    "one two three four five six seven eight nine ten first second third fourth fifth last couple few "
    "several many next half".split()
)
ADVERBS = frozenset(
    "up down left right forward forwards backward backwards straight diagonally diagonaly directly back "
    "north south east west northeast northwest southeast southwest upward upwards downward downwards "
    "just slightly then please again also still only even clockwise counterclockwise away ahead "
    "there here around over immediately first completely fully actually quickly slowly carefully "
    "inside outside all very much far closer further farther now finally afterwards later".split()
)
# Hue names: they compound when written solid, as they do hyphenated ("blue-green", "bluegreen").
HUES = frozenset(
    "green orange red blue tan teal beige brown yellow turquoise cyan pink peach white cream creme "
    "grey gray olive salmon gold black magenta purple violet maroon navy aqua lime khaki".split()
)
COLOURS = HUES | frozenset(
    "golden tangerine greenish bluish reddish orangey orangish yellowish brownish pinkish whitish "
    "flesh skin sand sandy light dark deep pale bright".split()
)
NOUNS = frozenset(
    "room rooms star block blocks toy object door doors doorway doorways entryway entrance exit opening "
    "openings area areas box section space square rectangle tile spot place floor carpet color colour "
    "wall side corner middle center centre top bottom edge path passage passageway hallway threshold "
    "enclosure background chair bag backpack basket moon circle smiley thing direction way front end "
    "body foot line point shape star bit step steps times time gap".split()
)
MEASURES = frozenset("way steps step times time bit direction".split())
ADJECTIVES = frozenset(
    "big large small little long longer short shorter lower upper next other far near opposite same "
    "open center middle left right top bottom straight shortest least possible big gold happy "
    "inner outer entire whole".split()
)
TO_WORDS = frozenset({"to"})

# Verbs of the domain, by lemma; inflected forms are derived below.
VERB_LEMMAS = frozenset(
    "go move push take bring walk enter exit leave put drag carry get head cross proceed start stop stand "
    "face approach grab pick round knock bump shift transfer tranfser reach see keep turn look use "
    "position remain stay pass set step be have make follow navigate travel run return come lead end "
    "forget pull slide place deliver steer drive hold cut continue stay wait arrive smile land locate "
    "find guide escort roll kick shove nudge send steer head crosses circle bring fetch collect "
    "relocate".split()
)
IRREGULAR = {
    "went": "go", "gone": "go", "goes": "go", "took": "take", "taken": "take", "brought": "bring",
    "left": "leave", "got": "get", "gotten": "get", "came": "come", "ran": "run", "held": "hold",
    "led": "lead", "saw": "see", "seen": "see", "kept": "keep", "made": "make", "is": "be", "are": "be",
    "am": "be", "was": "be", "were": "be", "been": "be", "'re": "be", "'s": "be", "'m": "be",
    "has": "have", "had": "have", "found": "find", "stood": "stand", "put": "put", "set": "set",
    "cut": "cut", "thru": "through",
}
# Forms that act as auxiliaries as well as main verbs ("are facing", "is positioned").
AUX_VERBS = frozenset("is are am was were be been 're 's 'm have has had do does did".split())


_LONGEST_HUE = max(map(len, HUES))


def split_compound_colour(word: str) -> tuple[str, ...]:
    """A colour compound written solid split into its hues ("bluegreen" -> ("blue", "green")), as the
    tokeniser splits a hyphenated one; any other word is itself. Both parts must be hues, so words
    that merely start with one ("tangerine", "redo") are left whole."""
    # A longer word cannot be two hues; without this bound a 1 MB "word" took minutes of slicing.
    if word not in COLOURS and len(word) <= 2 * _LONGEST_HUE:
        for cut in range(3, len(word) - 2):
            if word[:cut] in HUES and word[cut:] in HUES:
                return word[:cut], word[cut:]
    return (word,)


def _inflections(lemma: str) -> dict[str, str]:
    """Regular forms of a verb lemma: -s, -ed, -ing, with the usual spelling changes."""
    forms = {lemma: lemma}
    stem = lemma[:-1] if lemma.endswith("e") and not lemma.endswith("ee") else lemma
    forms[stem + "ing"] = lemma
    consonant_y = len(lemma) >= 2 and lemma[-1] == "y" and lemma[-2] not in "aeiou"
    if lemma.endswith("e"):
        forms[lemma + "d"] = lemma  # move -> moved
    elif consonant_y:
        forms[lemma[:-1] + "ied"] = lemma  # carry -> carried
    else:
        forms[lemma + "ed"] = lemma  # push -> pushed
    if consonant_y:
        forms[lemma[:-1] + "ies"] = lemma
    else:
        forms[lemma + ("es" if lemma.endswith(("s", "sh", "ch", "x")) else "s")] = lemma
    if len(lemma) >= 3 and lemma[-1] in "pgtbm" and lemma[-2] in "aeiou" and lemma[-3] not in "aeiou":
        forms[lemma + lemma[-1] + "ing"] = lemma  # stop -> stopping
        forms[lemma + lemma[-1] + "ed"] = lemma
    return forms


VERB_FORMS: dict[str, str] = {}
for _lemma in sorted(VERB_LEMMAS):
    VERB_FORMS.update(_inflections(_lemma))
VERB_FORMS.update(IRREGULAR)
VERB_FORMS.pop("thru", None)


def lemma(word: str) -> str:
    """Lemma of a verb form ("pushing" -> "push"); other words are returned unchanged."""
    return VERB_FORMS.get(word, word)


def listed_categories(word: str) -> frozenset[str]:
    """Categories the lexicon lists for ``word``; empty for a word it does not know (no guessing)."""
    return frozenset(_closed_categories(word))


def _closed_categories(word: str) -> set[str]:
    cats: set[str] = set()
    table = (
        (DETERMINERS, "DET"), (PREPOSITIONS, "PREP"), (CONJUNCTIONS, "CONJ"), (SUBORDINATORS, "SUB"),
        (RELATIVES, "REL"), (PRONOUNS, "PRON"), (AUXILIARIES, "AUX"), (NEGATIONS, "NEG"), (NUMBERS, "NUM"),
        (ADVERBS, "ADV"), (COLOURS, "COLOR"), (NOUNS, "NOUN"), (MEASURES, "MEASURE"), (ADJECTIVES, "ADJ"),
        (TO_WORDS, "TO"), (AUX_VERBS, "AUX"),
    )
    for words, cat in table:
        if word in words:
            cats.add(cat)
    if word in PARTICLES:
        cats.add("ADV")
    if word in VERB_FORMS:
        cats.add("GER" if word.endswith("ing") else "VERB")
        if word.endswith("ed"):
            cats.add("ADJ")  # past participles modify nouns: "orange-floored room", "colored room"
    if word == ",":
        cats = {"COMMA"}
    if word == "left":
        cats.discard("VERB")  # "left" is far more often a direction than the past of "leave"
    return cats


def guess_categories(word: str, first: bool = False) -> frozenset[str]:
    """Categories of a word: listed ones if known, else an open-class guess by suffix and position.

    ``first``: the word opens a clause, where an unknown word may be an imperative verb.
    Never empty: anything not recognisable is a noun or an adjective (open class).
    """
    known = _closed_categories(word)
    if known:
        return frozenset(known)
    if not any(ch.isalpha() for ch in word):
        return frozenset({"NUM"}) if any(ch.isdigit() for ch in word) else frozenset({"ADJ", "NOUN"})
    if word.endswith("ly") and len(word) > 4:
        return frozenset({"ADV"})
    if word.endswith("ing") and len(word) > 5:
        return frozenset({"GER", "ADJ", "NOUN"})
    if word.endswith(("ed", "ish", "ey", "ful", "ous", "ive", "al", "ic", "est", "er")) and len(word) > 4:
        return frozenset({"ADJ", "NOUN"})
    guess = {"ADJ", "NOUN"}
    if first:
        guess.add("VERB")
    return frozenset(guess)


@dataclass(frozen=True)
class SemanticLexicon:
    """Words mapped to domain propositional functions with probabilities (the semantic model).

    ``meanings[word][pf]`` is P(pf | word). Probabilities of a word need not sum to one: the remainder
    is the probability that the word keeps its uninstantiated reading (``P1(room1, green)``).
    Raises ValueError for negative probabilities or a word whose probabilities sum above one.
    """

    meanings: Mapping[str, Mapping[str, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        normalised: dict[str, dict[str, float]] = {}
        for word, pfs in self.meanings.items():
            total = 0.0
            for pf, prob in pfs.items():
                if not (prob >= 0.0) or math.isinf(prob):
                    raise ValueError(f"semantic lexicon: word {word!r}, PF {pf!r}: probability {prob} is not >= 0")
                total += prob
            if total > 1.0 + 1e-6:
                raise ValueError(f"semantic lexicon: word {word!r}: probabilities sum to {total:.4f} > 1")
            normalised[word.lower()] = {pf: float(p) for pf, p in pfs.items() if p > 0.0}
        object.__setattr__(self, "meanings", normalised)

    def choices(self, word: str) -> list[tuple[str | None, float]]:
        """(pf, probability) alternatives for a word; ``None`` is the uninstantiated reading.

        Unknown words give ``[(None, 1.0)]``.
        """
        pfs = self.meanings.get(word.lower())
        if not pfs:
            return [(None, 1.0)]
        out: list[tuple[str | None, float]] = sorted(pfs.items(), key=lambda kv: -kv[1])
        rest = 1.0 - sum(pfs.values())
        if rest > 1e-9:
            out.append((None, rest))
        return out
