"""Vocabularies: the words commands use and the semantic tokens words may mean.

Semantic tokens are what the language models generate words from: the names
of lifted tasks (``toyToRoom``), of colour and shape PFs (``roomIsRed``), of
object classes (``CLASS:room``) and the catch-all ``NULL`` that explains
words with no meaning in the domain ("the", "please"). Index 0 of the word
vocabulary is ``<unk>``: a word never seen in training gets only the prior's
share of every token's distribution.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

__all__ = ["Vocabulary", "NULL", "UNK", "NO_ROLE", "OTHER_PREP", "DIRECT_OBJECT", "class_token", "is_task_role"]

NULL = "NULL"
UNK = "<unk>"
NO_ROLE = "none"
OTHER_PREP = "<other>"
DIRECT_OBJECT = "<dobj>"


def class_token(cls: str) -> str:
    return f"CLASS:{cls}"


def is_task_role(role: str) -> bool:
    """A role of the task's own variables (``toyInRoom.0``), not a bystander's or none."""
    return role != NO_ROLE and not role.startswith("other:")


@dataclass
class Vocabulary:
    """Two index maps: words (``<unk>`` first) and semantic tokens (``NULL`` first)."""

    words: list[str] = field(default_factory=lambda: [UNK])
    tokens: list[str] = field(default_factory=lambda: [NULL])
    # What a noun phrase may align with (index 0: nothing) and the prepositions
    # that introduce noun phrases (index 0: unseen preposition, 1: direct object).
    roles: list[str] = field(default_factory=lambda: [NO_ROLE])
    preps: list[str] = field(default_factory=lambda: [OTHER_PREP, DIRECT_OBJECT])

    def __post_init__(self) -> None:
        self._word_index = {w: i for i, w in enumerate(self.words)}
        self._token_index = {t: i for i, t in enumerate(self.tokens)}
        self._role_index = {r: i for i, r in enumerate(self.roles)}
        self._prep_index = {p: i for i, p in enumerate(self.preps)}
        if self.words[:1] != [UNK] or self.tokens[:1] != [NULL]:
            raise ValueError("a vocabulary starts with <unk> among words and NULL among tokens")

    @staticmethod
    def _intern(items: list[str], index: dict[str, int], new: Iterable[str]) -> None:
        for item in new:
            if item not in index:
                index[item] = len(items)
                items.append(item)

    def add_words(self, words: Iterable[str]) -> None:
        self._intern(self.words, self._word_index, words)

    def add_tokens(self, tokens: Iterable[str]) -> None:
        self._intern(self.tokens, self._token_index, tokens)

    def add_roles(self, roles: Iterable[str]) -> None:
        self._intern(self.roles, self._role_index, roles)

    def add_preps(self, preps: Iterable[str]) -> None:
        self._intern(self.preps, self._prep_index, preps)

    def role_id(self, role: str) -> int:
        """Index of a role; a role training never saw aligns like nothing."""
        return self._role_index.get(role, 0)

    def prep_id(self, prep: str | None) -> int:
        if prep is None:
            return 1
        return self._prep_index.get(prep, 0)

    def word_id(self, word: str) -> int:
        return self._word_index.get(word, 0)

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
        }

    @classmethod
    def from_json(cls, data: dict) -> "Vocabulary":
        return cls(list(data["words"]), list(data["tokens"]), list(data["roles"]), list(data["preps"]))
