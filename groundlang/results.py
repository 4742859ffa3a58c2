"""What the learner returns: its posterior over readings of a command, and what following it did."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from groundlang.confidence import GoalGroup, most_probable_first
from groundlang.logic.atoms import Atom, format_goal
from groundlang.model.interpretations import Interpretation
from groundlang.model.mentions import MentionLimitError
from groundlang.model.pf_tables import TabulationError
from groundlang.model.state_search import StateSpaceError
from groundlang.model.world import Action, State

__all__ = ["Posterior", "FollowResult", "LAYOUT_ERRORS"]

# What following raises for the layout rather than the command: more objects than the mention model reads, a state
# space no method builds, PF tables too large. Whoever read the layout names its file.
LAYOUT_ERRORS = (MentionLimitError, StateSpaceError, TabulationError)


@dataclass
class Posterior:
    """Posterior over interpretations (L, T, C) of one command in one state, from its words alone.

    Fields:
        command: the command as given.
        interpretations: every (L, T, C) candidate of the state.
        probabilities: ``[J]`` their posterior probabilities (sum 1).
        readings: the grammar's readings of the command; ``reading_probabilities``: ``[R]``
            their posterior (parse language model only, else None).
        groups: goals merged when they hold in the same states of the layout, most probable
            first (:func:`groundlang.confidence.group_goals`); None when no state space was
            consulted, and then every goal is its own group.

        out_of_reach: how much of the words' posterior, before it was conditioned on an achievable goal
            (the language model's ``achievable_goals``), lay on goals no state the agent can reach
            satisfies; ``out_of_reach_goal`` the most probable of those (None where there is none). 0 also
            where nothing can be said out of reach: ``achievable_goals`` off, or a relevance abstraction or
            a sample of placements instead of the enumerated layout.

    ``confidence`` is the probability of the goal acted on (:attr:`best_goal`), ``margin``
    its lead over the next goal that differs in the world.
    """

    command: str
    interpretations: list[Interpretation]
    probabilities: np.ndarray  # [J]
    readings: list = field(default_factory=list)  # grammar Readings
    reading_probabilities: np.ndarray | None = None  # [R] posterior over readings
    groups: list[GoalGroup] | None = None
    out_of_reach: float = 0.0
    out_of_reach_goal: tuple[Atom, ...] | None = None

    def __post_init__(self) -> None:
        # A model whose tables pass the loader's checks (finite numbers of the right shapes) may still not
        # be probabilities (zeros, negatives): a NaN here would make every confidence NaN, and NaN < 0.7 is
        # false, so it would act. Refused where it shows.
        if not np.isfinite(np.asarray(self.probabilities, dtype=float)).all():
            raise ValueError(f"the model gives no posterior for {self.command!r}: its probabilities are not "
                             "finite numbers (tables that are not distributions: a damaged or edited model)")

    def ranked(self) -> list[tuple[float, Interpretation]]:
        order = np.argsort(-self.probabilities, kind="stable")
        return [(float(self.probabilities[j]), self.interpretations[j]) for j in order]

    def goals(self) -> list[tuple[tuple[Atom, ...], float]]:
        """Marginal posterior over grounded goals (T), summed over constraints, most probable first."""
        totals: dict[tuple[Atom, ...], float] = {}
        for p, interp in zip(self.probabilities, self.interpretations):
            totals[interp.goal] = totals.get(interp.goal, 0.0) + float(p)
        return most_probable_first(list(totals.items()), lambda kv: kv[1])

    def goal_groups(self) -> list[GoalGroup]:
        """:attr:`groups`, or one group per goal when the layout was not consulted."""
        if self.groups is not None:
            return self.groups
        return [GoalGroup((g,), p) for g, p in self.goals()]

    def lifted_tasks(self) -> dict[str, float]:
        totals: dict[str, float] = {}
        for p, interp in zip(self.probabilities, self.interpretations):
            totals[interp.lifted] = totals.get(interp.lifted, 0.0) + float(p)
        return dict(sorted(totals.items(), key=lambda kv: -kv[1]))

    @property
    def best_goal(self) -> tuple[Atom, ...]:
        """The goal acted on: the most probable goal of the most probable group."""
        return self.goal_groups()[0].goal

    @property
    def confidence(self) -> float:
        """Posterior probability of :attr:`best_goal`, goals with the same outcome counted as one."""
        return self.goal_groups()[0].probability

    @property
    def margin(self) -> float:
        """:attr:`confidence` less the probability of the next goal that differs in the world."""
        groups = self.goal_groups()
        return groups[0].probability - (groups[1].probability if len(groups) > 1 else 0.0)

    def table(self, top: int = 10) -> str:
        """A plain-text table of the ``top`` most probable interpretations (``top`` at least 1)."""
        if isinstance(top, bool) or not isinstance(top, (int, np.integer)) or top < 1:
            raise ValueError(f"table(top={top!r}): top is how many rows to show, a whole number of at least 1")
        rows = [(p, interp.lifted, format_goal(interp.goal),
                 " ∧ ".join(str(a) for a in interp.constraint.atoms) or "(none)") for p, interp in self.ranked()[:top]]
        # columns as wide as their widest entry: a goal of two atoms is wider than any fixed width
        task_w = max([22, *(len(r[1]) for r in rows)])
        goal_w = max([40, *(len(r[2]) for r in rows)])
        lines = [f"{'prob':>7}  {'task':<{task_w}} {'goal':<{goal_w}} constraints"]
        lines += [f"{p:7.4f}  {task:<{task_w}} {goal:<{goal_w}} {constraint}" for p, task, goal, constraint in rows]
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (f"Posterior({self.command!r}, best_goal={format_goal(self.best_goal)!r}, "
                f"confidence={self.confidence:.3f}, margin={self.margin:.3f}, "
                f"{len(self.interpretations)} interpretations)")


@dataclass(repr=False)
class FollowResult:
    """What :meth:`Learner.follow` did: its reading of the command and the plan it executed.

    Fields:
        command: the command as given.
        posterior: the :class:`Posterior` the goal was chosen from.
        goal: the goal planned for (the best goal, or the one an answer chose).
        states: the states visited, the initial state first (only it when the learner abstained).
        actions: the actions executed (none when it abstained).
        reached: whether ``goal`` holds in the last state.
        reason: why execution stopped: ``goal``, ``max_steps``, ``unreachable``, or ``abstained``.
        abstained: True when confidence was below ``min_confidence`` and nothing was done.
        question: what to ask the user then ("Which room do you mean: ...?"); "" otherwise.
        choices: the competing goals (:class:`GoalGroup`) the question offers, most probable first;
            :meth:`Learner.clarify` takes an answer naming one.
        unknown_words: words of the command's noun phrases the model never learned.
        goal_words: ``goal`` in words ("the yellow star in the red room").
        success: the posterior probability that what was meant holds where following ends (or would
            end, when it abstained), reached or not, ``sum_g P(g | words) [s satisfies g]``; None where
            following planned for one goal alone (the language model's ``success_confidence`` or
            ``expected_success`` off, or no goal of the posterior within reach).
        already_true: the question asks whether the goal, which holds at the start, is what is meant
            (:mod:`groundlang.held_question`); ``posterior`` is then the words' reading with such goals offered.
        otherwise: for such a question, the result of following the rest of the reading (acted on or
            abstained), which a no to it takes; None where nothing else can be done.
        held_reading: ``(goal, probability)`` where the words most probably ask for a goal that holds at the
            start, asked about or not (read where follow had a threshold); None otherwise.
    """

    command: str
    posterior: Posterior
    goal: tuple[Atom, ...]
    states: list[State]
    actions: list[Action]
    reached: bool
    reason: str
    abstained: bool = False
    question: str = ""
    choices: list[GoalGroup] = field(default_factory=list)
    unknown_words: tuple[str, ...] = ()
    goal_words: str = ""
    success: float | None = None
    already_true: bool = False
    otherwise: FollowResult | None = None
    held_reading: tuple[tuple[Atom, ...], float] | None = None

    @property
    def final_state(self) -> State:
        return self.states[-1]

    @property
    def confidence(self) -> float:
        """How likely acting so does what was meant: :attr:`success` where known, else the posterior
        probability of the goal acted on (``Posterior.confidence``)."""
        return self.posterior.confidence if self.success is None else self.success

    def __repr__(self) -> str:
        if self.abstained:
            return f"FollowResult({self.command!r}, abstained, confidence={self.confidence:.3f}, question={self.question!r})"
        return (f"FollowResult({self.command!r}, goal={format_goal(self.goal)!r}, reached={self.reached}, "
                f"reason={self.reason!r}, {len(self.actions)} actions, confidence={self.confidence:.3f})")
