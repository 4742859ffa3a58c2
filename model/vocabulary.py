"""Vocabularies: the words commands use and the semantic tokens words may mean.

Semantic tokens are what the language models generate words from: the names
of lifted tasks (``toyToRoom``), of colour and shape PFs (``roomIsRed``), of
object classes (``CLASS:room``) and the catch-all ``NULL`` that explains
words with no meaning in the domain ("the", "please"). Index 0 of the word
vocabulary is ``<unk>``: a word never seen in training gets only the prior's
share of every token's distribution. Crowd-sourced commands are typed in a
hurry: a word seen once that is one edit from exactly one common word
("orage", "whlite") is read as that word, and so is an unknown word at test
time that is one edit from exactly one known word.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field

from groundlang.grammar.lexicon import Lexicon
from groundlang.model.domain_words import domain_lexicon

__all__ = ["Vocabulary", "NULL", "UNK", "NO_ROLE", "OTHER_PREP", "DIRECT_OBJECT", "NEGATED_PREP", "class_token", "is_task_role"]

NULL = "NULL"
UNK = "<unk>"
NO_ROLE = "none"
OTHER_PREP = "<other>"
DIRECT_OBJECT = "<dobj>"
# The key of a phrase of a negated clause whose own key (``not:onto``) training never saw: a negated phrase
# training never saw is read as one, not as any unseen preposition (``prep_id``).
NEGATED_PREP = "<not>"


def class_token(cls: str) -> str:
    return f"CLASS:{cls}"


def is_task_role(role: str) -> bool:
    """A role of the task's own variables (``toyInRoom.0``), not a bystander's or none."""
    return role != NO_ROLE and not role.startswith("other:")


# An unknown word this long or longer, met in use, is read as a known word one edit away when
# exactly one known word of this length or longer is ("gren" as "green"; three-letter words have
# too many neighbours). Words the grammar's lexicon lists in disjoint categories stay apart ("back"
# and "black").
MIN_SPELLING_LENGTH = 4
# Nor is a word longer than this: its one-edit neighbours number about 54 per letter, each as long as the
# word, so the search would take memory in the square of its length (a pasted run of letters is not a typo
# of a word people type in a command).
MAX_SPELLING_LENGTH = 40
# In training, a rare word is read as a common one from five letters only, as before this rule had a
# length for use: a training alias changes what the model learns, not only how one command reads
# ("moves" read as "move" merges two words' counts). Kept, not re-chosen: ABLATIONS.md.
MIN_TRAINING_SPELLING_LENGTH = 5
_LETTERS = "abcdefghijklmnopqrstuvwxyz"


def _one_edit(word: str) -> set[str]:
    """Every string one deletion, transposition, substitution or insertion away from ``word``."""
    splits = [(word[:i], word[i:]) for i in range(len(word) + 1)]
    deletes = {a + b[1:] for a, b in splits if b}
    transposes = {a + b[1] + b[0] + b[2:] for a, b in splits if len(b) > 1}
    replaces = {a + c + b[1:] for a, b in splits if b for c in _LETTERS}
    inserts = {a + c + b for a, b in splits for c in _LETTERS}
    return (deletes | transposes | replaces | inserts) - {word}


def _neighbours(word: str, known: Callable[[str], bool], lexicon: Lexicon,
                shortest: int = MIN_SPELLING_LENGTH) -> str | None:
    """The one word one edit from ``word`` that ``known`` accepts, or None (none, or several);
    words shorter than ``shortest`` letters are neither read as others nor read into."""
    if not shortest <= len(word) <= MAX_SPELLING_LENGTH or not word.isalpha():
        return None
    # Hurried typing keeps the first letter; an edit there makes other words ("reach", "peach").
    found = {w for w in _one_edit(word) if w[0] == word[0] and len(w) >= shortest and known(w)}
    if len(found) != 1:
        return None
    meant = found.pop()
    # Two words the grammar's lexicon lists with no category in common are two words ("while" and
    # "white", "three" and "there", "block" and "black"), not a typo of one another.
    mine, theirs = lexicon.listed(word), lexicon.listed(meant)
    return None if mine and theirs and mine.isdisjoint(theirs) else meant


@dataclass
class Vocabulary:
    """Two index maps: words (``<unk>`` first) and semantic tokens (``NULL`` first)."""

    words: list[str] = field(default_factory=lambda: [UNK])
    tokens: list[str] = field(default_factory=lambda: [NULL])
    # What a noun phrase may align with (index 0: nothing) and the prepositions
    # that introduce noun phrases (index 0: unseen preposition, 1: direct object, 2: an unseen negated one in a
    # vocabulary built since it existed).
    roles: list[str] = field(default_factory=lambda: [NO_ROLE])
    preps: list[str] = field(default_factory=lambda: [OTHER_PREP, DIRECT_OBJECT, NEGATED_PREP])
    # Misspellings read as another word of the vocabulary ("whlite" -> "white").
    aliases: dict[str, str] = field(default_factory=dict)
    # The lifted tasks, in library order: what the parse model's per-task tables are indexed by.
    tasks: list[str] = field(default_factory=list)
    # The roles a noun phrase may align with in each lifted task's interpretations
    # (model.interpretations.alignable_roles); a task missing here (a vocabulary built by
    # hand) is taken to offer every role.
    task_roles: dict[str, tuple[str, ...]] = field(default_factory=dict)
    # The word the domain's schema names a token by ("CLASS:door" -> "door", "toyIsChair" -> "chair"):
    # what a language model with ``schema_names`` lets a token say.
    names: dict[str, str] = field(default_factory=dict)
    # Which family of names each is one of (a class, a colour, a shape): a family's names are people's
    # words, or not, together (a palette's colour names may not be what people call its colours).
    name_families: dict[str, str] = field(default_factory=dict)
    # The tokens a head noun says (a class, a toy's shape) -> the class of the things they name: their
    # names are words for kinds of things, a shape's a word for a kind of toy.
    kinds: dict[str, str] = field(default_factory=dict)
    # The words the grammar lists (not saved with the vocabulary: the learner sets the one it parses
    # with): two listed words with no category in common are not a misspelling of one another.
    lexicon: Lexicon = field(default_factory=domain_lexicon, repr=False, compare=False)

    def __post_init__(self) -> None:
        # Each list is an index of text: anything else (a list from an edited file) is not hashed first.
        for what, items in (("words", self.words), ("tokens", self.tokens), ("roles", self.roles),
                            ("preps", self.preps), ("tasks", self.tasks)):
            strange = [x for x in items if not isinstance(x, str)][:1]  # a list: None is one to find
            if strange:
                raise ValueError(f"a vocabulary's {what} are text; found {strange[0]!r:.40}")
        self._word_index = {w: i for i, w in enumerate(self.words)}
        self._token_index = {t: i for i, t in enumerate(self.tokens)}
        self._role_index = {r: i for i, r in enumerate(self.roles)}
        self._prep_index = {p: i for i, p in enumerate(self.preps)}
        self._task_index = {t: i for i, t in enumerate(self.tasks)}
        self._spelling: dict[str, int] = {}  # unknown word -> index it is read as
        if self.words[:1] != [UNK] or self.tokens[:1] != [NULL]:
            raise ValueError("a vocabulary starts with <unk> among words and NULL among tokens")
        # The indices the model reads by number: no role (0), an unseen preposition (0), the direct object (1).
        if self.roles[:1] != [NO_ROLE] or self.preps[:2] != [OTHER_PREP, DIRECT_OBJECT]:
            raise ValueError(f"a vocabulary starts with {NO_ROLE} among roles and {OTHER_PREP}, {DIRECT_OBJECT} "
                             "among prepositions")
        # Each list is an index: an entry twice would give two rows one name.
        for what, items, index in (("words", self.words, self._word_index), ("tokens", self.tokens, self._token_index),
                                   ("roles", self.roles, self._role_index), ("preps", self.preps, self._prep_index),
                                   ("tasks", self.tasks, self._task_index)):
            if len(index) != len(items):
                twice = next(x for k, x in enumerate(items) if index[x] != k)
                raise ValueError(f"a vocabulary's {what} name each entry once; {twice!r} is there twice")
        # The maps are read where a word is looked up, long after loading: one that is not text to text is
        # refused here ("aliases": {"red": 5} broke spelling correction with a TypeError at follow).
        for what, mapping in (("aliases", self.aliases), ("names", self.names),
                              ("name_families", self.name_families), ("kinds", self.kinds)):
            if not isinstance(mapping, dict) or not all(isinstance(k, str) and isinstance(v, str)
                                                        for k, v in mapping.items()):
                raise ValueError(f"a vocabulary's {what} map text to text")
        # A task's roles index the rows of its alignment table: a task or a role the lists do not hold
        # would size the tables otherwise than the globals trained with them.
        for task, own in self.task_roles.items():
            if not all(isinstance(r, str) for r in own):
                raise ValueError(f"a vocabulary's task_roles give {task!r} roles that are not text")
            if task not in self._task_index:
                raise ValueError(f"a vocabulary's task_roles name {task!r}, which is not one of its tasks")
            stray = next((r for r in own if r not in self._role_index), None)
            if stray is not None:
                raise ValueError(f"a vocabulary's task_roles give {task!r} the role {stray!r}, which is not one "
                                 "of its roles")

    @staticmethod
    def _intern(items: list[str], index: dict[str, int], new: Iterable[str]) -> None:
        for item in new:
            if item not in index:
                index[item] = len(items)
                items.append(item)

    def add_words(self, words: Iterable[str]) -> None:
        self._intern(self.words, self._word_index, words)
        self._spelling.clear()

    def add_tokens(self, tokens: Iterable[str]) -> None:
        self._intern(self.tokens, self._token_index, tokens)

    def add_roles(self, roles: Iterable[str]) -> None:
        self._intern(self.roles, self._role_index, roles)

    def add_preps(self, preps: Iterable[str]) -> None:
        self._intern(self.preps, self._prep_index, preps)

    def add_tasks(self, tasks: Iterable[str], roles: Mapping[str, Iterable[str]] | None = None) -> None:
        """Lifted task names; each is also a semantic token (its words). ``roles``: per task, the
        roles a noun phrase may align with in its interpretations (also added as roles)."""
        tasks = list(tasks)
        self._intern(self.tasks, self._task_index, tasks)
        self.add_tokens(tasks)
        for task, own in (roles or {}).items():
            self.task_roles[task] = tuple(own)
            self.add_roles(own)

    def offers_role(self, task: str, role: str) -> bool:
        """Whether an interpretation of lifted ``task`` can offer ``role`` to a noun phrase (a "go
        somewhere" command has no toy to move). True for every role of a task :attr:`task_roles`
        does not list."""
        offered = self.task_roles.get(task)
        return offered is None or role in offered

    def task_id(self, task: str) -> int:
        """Index of a lifted task among :attr:`tasks`; a task the vocabulary never saw is an error."""
        try:
            return self._task_index[task]
        except KeyError:
            raise ValueError(
                f"lifted task {task!r} is not in the vocabulary (it knows {', '.join(self.tasks) or 'none'}): "
                "train with the task library the model is used with"
            ) from None

    def role_id(self, role: str) -> int:
        """Index of a role; a role training never saw aligns like nothing."""
        return self._role_index.get(role, 0)

    def prep_id(self, prep: str | None) -> int:
        if prep is None:
            return 1
        if prep not in self._prep_index and prep.startswith("not:"):
            return self._prep_index.get(NEGATED_PREP, 0)  # a vocabulary saved before it existed: unseen
        return self._prep_index.get(prep, 0)

    def word_id(self, word: str) -> int:
        """Index of a word. A misspelling (see :meth:`read_misspellings`) reads as its word;
        an unknown word of ``MIN_SPELLING_LENGTH`` letters or more one edit away from
        exactly one known word ("orage") reads as that word; any other unknown word is ``<unk>``."""
        word = self.aliases.get(word, word)
        index = self._word_index.get(word)
        if index is not None:
            return index
        if word not in self._spelling:
            found = _neighbours(word, lambda w: w in self._word_index and w not in self.aliases, self.lexicon)
            self._spelling[word] = self._word_index[found] if found else 0
        return self._spelling[word]

    def read_misspellings(self, counts: Mapping[str, int], rare: int = 1, common: int = 3) -> dict[str, str]:
        """Read each word seen at most ``rare`` times as the one word seen at least ``common``
        times one edit away ("whlite" as "white"), if there is exactly one; returns the new aliases."""
        new = {}
        for word, n in counts.items():
            if n <= rare and word not in self.aliases:
                found = _neighbours(word, lambda w: counts.get(w, 0) >= common, self.lexicon,
                                    MIN_TRAINING_SPELLING_LENGTH)
                if found:
                    new[word] = found
        self.aliases.update(new)
        self._spelling.clear()
        return new

    def token_names(self) -> list[int]:
        """Per token, the index of the word :attr:`names` names it by, or -1 (no name, or a word the
        vocabulary lacks)."""
        return [self._word_index.get(self.names.get(t, ""), -1) if t in self.names else -1 for t in self.tokens]

    @property
    def families(self) -> list[str]:
        """The families of names (:attr:`name_families`), in order of first appearance."""
        return list(dict.fromkeys(self.name_families.values()))

    def token_families(self) -> list[int]:
        """Per token, the index of its family of names in :attr:`families`, or -1 (a token with no name)."""
        index = {f: n for n, f in enumerate(self.families)}
        return [index[self.name_families[t]] if n >= 0 and t in self.name_families else -1
                for t, n in zip(self.tokens, self.token_names())]

    def other_kinds(self) -> list[tuple[int, int]]:
        """``(token, word)`` indices where a named token does not say the word, by mutual exclusivity:
        the word names a kind (:attr:`kinds`) that is not the token's own nor, for a class, one of its
        kinds ("chair" is not a word for a room nor for a colour; it is one for a toy)."""
        kind_names = {self.names[t]: cls for t, cls in self.kinds.items() if t in self.names}
        out = []
        for t, token in enumerate(self.tokens):
            if token not in self.names:
                continue
            own = self.kinds.get(token) if token == class_token(self.kinds.get(token, "")) else None
            for word, cls in kind_names.items():
                if word != self.names[token] and cls != own and word in self._word_index:
                    out.append((t, self._word_index[word]))
        return out

    def token_id(self, token: str) -> int:
        """Index of a semantic token; tokens unknown to training map to NULL."""
        return self._token_index.get(token, 0)

    def has_token(self, token: str) -> bool:
        return token in self._token_index

    def to_json(self) -> dict:
        return {
            "words": list(self.words),
            "tokens": list(self.tokens),
            "roles": list(self.roles),
            "preps": list(self.preps),
            "aliases": dict(sorted(self.aliases.items())),
            "tasks": list(self.tasks),
            "task_roles": {task: list(roles) for task, roles in self.task_roles.items()},
            "names": dict(self.names),
            "name_families": dict(self.name_families),
            "kinds": dict(self.kinds),
        }

    @classmethod
    def from_json(cls, data: dict, lexicon: Lexicon | None = None) -> "Vocabulary":
        """A vocabulary from :meth:`to_json`; ``lexicon``: the words the grammar lists (default:
        :func:`domain_lexicon`), which the JSON does not hold."""
        return cls(list(data["words"]), list(data["tokens"]), list(data["roles"]), list(data["preps"]),
                   dict(data.get("aliases", {})), list(data.get("tasks", [])),
                   {task: tuple(roles) for task, roles in data.get("task_roles", {}).items()},
                   dict(data.get("names", {})), dict(data.get("name_families", {})),
                   dict(data.get("kinds", {})), lexicon or domain_lexicon())
