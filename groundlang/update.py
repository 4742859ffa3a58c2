"""Learning from one more example: fold a command, with a demonstration or the goal a person named,
into a trained learner without refitting it.

The example becomes one observation, as in training: its interpretations in the state, restricted
to ``goal`` when one is given (the goal a person picked when asked), and the demonstration's
behaviour likelihood under each when one is given. Words the vocabulary never had ("purple") are
added, with word-distribution columns that hold no counts yet; then incremental EM
(:mod:`groundlang.inference.incremental`) adds the example's expected counts to those training left.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from groundlang.confidence import GoalGroup
from groundlang.corpus import Instance
from groundlang.inference.incremental import fold_in, grow_words, word_totals
from groundlang.inference.likelihoods import behaviour_likelihood_table
from groundlang.labels import goal_holds
from groundlang.logic.atoms import Atom, format_goal, parse_goal, shown
from groundlang.model.encoding import Observation
from groundlang.model.vocabulary import Vocabulary
from groundlang.model.world import Action, WorldError, replay

__all__ = ["update_learner", "as_goals", "as_actions"]

# E steps on the new example; it converges in a handful (each only reweighs one command's words).
UPDATE_STEPS = 50


def as_goals(goal) -> tuple[tuple[Atom, ...], ...]:
    """The goals ``goal`` allows: a goal string ("agentInRoom(agent0, room1)"), an Atom, a tuple of
    Atoms (a conjunction), or a :class:`GoalGroup` (any of its goals, which have the same outcome)."""
    if isinstance(goal, GoalGroup):
        if not goal.goals:  # an edited group: it allows nothing
            raise ValueError("update: goal is a GoalGroup of no goals")
        return tuple(goal.goals)
    if isinstance(goal, str):
        try:
            return (parse_goal(goal),)
        except ValueError as exc:
            raise ValueError(f"update: goal {shown(repr(goal), limit=60)} is not a goal ({shown(str(exc), limit=200)})") from None
    if isinstance(goal, Atom):
        return ((goal,),)
    if isinstance(goal, tuple) and goal and all(isinstance(a, Atom) for a in goal):
        return (goal,)
    raise TypeError(f"update: goal must be a goal string, an Atom, a tuple of Atoms or a GoalGroup, "
                    f"got {type(goal).__name__}")


def as_actions(demonstration) -> tuple[Action, ...]:
    """The actions of ``demonstration``: Actions or their words ("north"), or one comma-separated
    string of words as corpus files hold them ("south,south,west")."""
    if isinstance(demonstration, str):
        demonstration = [w for w in demonstration.split(",") if w.strip()]
    elif isinstance(demonstration, (list, tuple)):
        # (a flag, not next(..., None): None is itself an action of the wrong type)
        odd = [a for a in demonstration if not isinstance(a, (Action, str))]
        if odd:
            raise TypeError(f"update: demonstration: each action must be an Action or its word ('north'), got "
                            f"{type(odd[0]).__name__}")
    elif isinstance(demonstration, (bytes, bytearray, Mapping)):  # read by what iterating gives: keys, byte values
        raise TypeError(f"update: demonstration must be a sequence of actions, or a string of their words, "
                        f"not {type(demonstration).__name__}")
    try:
        actions = tuple(a if isinstance(a, Action) else Action.parse(a) for a in demonstration)
    except TypeError:
        raise TypeError(f"update: demonstration must be a sequence of actions, got "
                        f"{type(demonstration).__name__}") from None
    except (AttributeError, WorldError) as exc:
        raise ValueError(f"update: demonstration: {exc}") from None
    if not actions:
        raise ValueError("update: the demonstration has no actions")
    return actions


def update_learner(learner, command: str, state, demonstration: Sequence | str | None = None,
                   goal=None, steps: int = UPDATE_STEPS):
    """Fold one example into ``learner`` in place (see the module docstring); returns the learner.

    ValueError when neither ``demonstration`` nor ``goal`` is given (the words alone teach nothing
    the model does not already believe), when ``goal`` is no interpretation's goal in ``state``, or
    when the learner's word distributions cannot be updated (see :func:`word_totals`)."""
    learner._require_fitted()
    learner._check_state("update", command, state)
    if demonstration is None and goal is None:
        raise ValueError("update: give a demonstration or the goal the command means; the words alone teach nothing")
    obs = learner._command_observation(command, state)
    interps = obs.interpretations
    if goal is not None:
        allowed = set(as_goals(goal))
        interps = tuple(i for i in interps if i.goal in allowed)
        if not interps:
            offered = sorted({format_goal(i.goal) for i in obs.interpretations})
            raise ValueError(f"update: no task of the library has goal {format_goal(next(iter(allowed)))} in this "
                             f"state (its goals: {'; '.join(offered)})")
    behaviour = None
    habits = learner.habits
    if demonstration is not None:
        actions = as_actions(demonstration)
        example = Instance(Path("<update>"), command, actions, replay(state, actions))
        if goal is not None and not any(goal_holds(g, example.final_state, learner.library) for g in {i.goal for i in interps}):
            # with the goal given, the demonstration only weighs its groundings against each other: one that
            # never reaches it would be folded in as if it did
            raise ValueError(f"update: the demonstration ends where goal {format_goal(interps[0].goal)} does not hold; "
                             "give one that reaches it, or the goal alone")
        if habits is not None:  # what the demonstration left true besides its goal
            habits = habits.plus([(example.initial_state, example.final_state)], learner.library)
        goals = sorted({i.goal for i in interps})
        row = behaviour_likelihood_table([example], [goals], learner.settings, cache_dir=learner.cache_dir,
                                         library=learner.library)[0]
        by_goal = dict(zip(goals, row))
        behaviour = tuple(float(by_goal[i.goal]) for i in interps)
    obs = Observation(obs.words, obs.readings, interps, behaviour)

    concentration = learner.lm.word_concentration
    totals = word_totals(learner.globals["phi"], concentration)
    # Only words read as nothing are new: a misspelling of a known word ("gren") stays that word.
    new_words = [w for w in dict.fromkeys(obs.words) if not learner._knows(w)]
    phi, totals = grow_words(learner.globals["phi"], totals, len(new_words), concentration)
    # On a copy, so that a failure leaves the learner as it was.
    vocab = Vocabulary.from_json(learner.vocab.to_json(), learner.word_lexicon)
    vocab.add_words(new_words)
    globals_, _ = fold_in(learner.lm.encode([obs], vocab), learner.lm, vocab,
                          {**learner.globals, "phi": phi}, totals, steps=steps)
    learner.vocab, learner.globals, learner.habits = vocab, globals_, habits
    return learner
