"""A command given in several start states at once asks for what holds in none of them.

Following sets aside a goal that already holds where the command is given: it asks for nothing. A
command may come with more than one start state (Williams et al. 2018 give each command three
layouts, the demonstrations it was written for); what it asks for then holds in none of them, so a
reading whose lifted task already holds in another of its start states is not what it asks either.
In the training pairs of that corpus a task's side of a block ("left of the chair") never holds in
any of the command's start states, while the other side does in 97 of the 161 commands showing left
of: a worker's side-less "next to the red chair" was written for demonstrations that ended left of
it, from starts of which one stood right of it.

Which object a lifted task binds is the words' business in each layout ("the red chair" is block1 in
one, block0 in the next), so the rule is read through the posterior there: in each other start state
``s_j``, the probability under the words that a reading of lifted task ``T`` already holds,

    h_j(T) = sum_{i of task T, goal holding in s_j} P(i | words, s_j) / sum_{i of task T} P(i | words, s_j),

and each reading of task ``T`` where the command is followed is weighed by ``prod_j (1 - h_j(T))``
(renormalised; unchanged where every reading would be ruled out). The language model's
``other_starts`` setting turns it off.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np

from groundlang.model.interpretations import Interpretation, NoTaskError
from groundlang.model.world import State
from groundlang.results import LAYOUT_ERRORS

__all__ = ["held_shares", "HeldShares", "given_other_starts", "check_other_starts"]

logger = logging.getLogger(__name__)


def check_other_starts(method: str, other_starts) -> tuple[State, ...]:
    """``other_starts`` as a tuple of States; TypeError for anything else (a single State, a string)."""
    if isinstance(other_starts, (State, str, bytes)) or not isinstance(other_starts, Sequence):
        raise TypeError(f"{method}: other_starts must be a sequence of States (the command's other start states), "
                        f"not {type(other_starts).__name__}")
    for k, other in enumerate(other_starts):
        if not isinstance(other, State):
            raise TypeError(f"{method}: other_starts[{k}] is a {type(other).__name__}, expected a State")
    return tuple(other_starts)


def held_shares(learner, command: str, state: State, where: str = "other_starts") -> dict[str, float]:
    """``{lifted task: h(T)}`` for ``command`` said in ``state``: the share of each lifted task's posterior
    mass, from the words alone, on readings whose goal already holds there (the module docstring). Empty
    where the state admits no reading or its layout cannot be read (too large to tabulate): it then says
    nothing, and a warning says so. ValueError, naming ``where``, for a state of a palette the learner was
    not trained on."""
    try:
        learner._check_state(where, command, state)  # a layout too large to tabulate: before grounding
        obs, p, _ = learner.words_reading(command, state, held=True)
    except (NoTaskError, *LAYOUT_ERRORS) as exc:
        logger.warning("%s: set aside, it says nothing of what the command asks: %s", where, exc)
        return {}
    held: dict[str, float] = {}
    total: dict[str, float] = {}
    for interp, share in zip(obs.interpretations, p):
        total[interp.lifted] = total.get(interp.lifted, 0.0) + float(share)
        if interp.task.holds_wholly:
            held[interp.lifted] = held.get(interp.lifted, 0.0) + float(share)
    return {task: min(1.0, mass / total[task]) for task, mass in held.items() if total[task] > 0}


class HeldShares:
    """:func:`held_shares` of one command's start states, kept while the learner follows that command with the
    model it has: following a command from each of its three starts, the other two given, reads each start once,
    not twice. Forgotten at another command or when the model changes (refitted, updated, words added,
    settings changed): the learner's parts are compared by identity, its settings by value."""

    # At most this many start states kept (a command is given in a few; a caller may give one in many).
    KEPT = 16

    def __init__(self) -> None:
        self._read_with: tuple = ()
        self._shares: dict[State, dict[str, float]] = {}

    def of(self, learner, command: str, state: State, where: str) -> dict[str, float]:
        read_with = (command, repr(learner.lm.settings()), learner.globals, learner.vocab, learner.word_lexicon,
                     learner.library)
        if len(read_with) != len(self._read_with) or not all(map(_same, read_with, self._read_with)):
            self._read_with, self._shares = read_with, {}
        if state not in self._shares:
            if len(self._shares) >= self.KEPT:
                self._shares.clear()
            self._shares[state] = held_shares(learner, command, state, where)
        return self._shares[state]


def _same(a, b) -> bool:
    """Texts (the command, the settings) by value; the model's parts by identity (each kept alive here, so
    another object cannot take its place at the same address)."""
    return a == b if isinstance(a, str) else a is b


def given_other_starts(probabilities: np.ndarray, interps: Sequence[Interpretation],
                       shares: Sequence[dict[str, float]]) -> np.ndarray:
    """``probabilities`` (one per reading of ``interps``) weighed by the chance that each reading's lifted task
    holds in none of the other start states (``shares``: :func:`held_shares` of each), renormalised;
    unchanged where nothing is ruled out or everything would be."""
    weight = np.ones(len(interps))
    lifted = [interp.lifted for interp in interps]
    for share in shares:
        if share:
            weight *= np.array([1.0 - share.get(task, 0.0) for task in lifted])
    weighed = np.asarray(probabilities, dtype=float)[: len(interps)] * weight
    total = float(weighed.sum())
    if total <= 0 or np.all(weight == 1.0):
        return probabilities
    return weighed / total
