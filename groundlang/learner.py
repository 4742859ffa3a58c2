"""The public API: learn word meanings from commands with demonstrations, then follow commands.

    learner = Learner(language_model="parse").fit(corpus)
    learner.posterior("take the star to the red room", state).table()
    result = learner.follow("take the star to the red room", state)
    learner.update("go to the purple room", state, goal="agentInRoom(agent0, room1)")  # one more example
    learner.save("model/"); Learner.load("model/")
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Sequence
from pathlib import Path

import torch

from groundlang.grammar.parser import parse
from groundlang.clarify import AnswerError, answer_text, choose, clear_choice, competing, question, unknown_words
from groundlang.confidence import given_achievable, group_goals, held_goals_success, out_of_reach, unachievable_goals
from groundlang.held_question import answer_held, follow_or_ask
from groundlang.goal_plans import WorldPlans, expected_success_states, goal_holding_at, nearest_of, success_at
from groundlang.inference.end_habits import EndHabits, demonstrated_pairs, known_new_relations
from groundlang.inference.joint import FitResult, fit_globals, local_posteriors, per_parser_reading
from groundlang.inference.planning import TaskSettings
from groundlang.logic.atoms import Atom
from groundlang.logic.storage import as_path
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.domain_words import WordSource, domain_lexicon, extra_words
from groundlang.model.encoding import Batch, Observation
from groundlang.model.interpretations import Interpretation, interpretations
from groundlang.model.language_model_base import word_meanings
from groundlang.model.language_models import BagOfWords, LanguageModel, get_language_model
from groundlang.model.relevance import check_abstraction_possible
from groundlang.model.vocabulary import Vocabulary
from groundlang.model.world import State
from groundlang.learner_state import (check_count, check_fit_arguments, check_model_parts, check_state, check_threshold,
                                       word_sources, check_training_options, learner_from_state, learner_state)
from groundlang.model_io import check_parameter_bound, read_model, write_model
from groundlang.other_starts import HeldShares, check_other_starts, given_other_starts
from groundlang.results import FollowResult, Posterior
from groundlang.training_vocabulary import build_vocabulary, word_files_beside
from groundlang.wording import goal_phrase

__all__ = ["Learner", "Posterior", "FollowResult", "NotFittedError", "AnswerError", "DEFAULT_MIN_CONFIDENCE"]

# follow's default threshold on the CLI: chosen on held-out data (see README, "Knowing when it does not know").
DEFAULT_MIN_CONFIDENCE = 0.7

log = logging.getLogger(__name__)


class NotFittedError(ValueError):
    """A learner was asked to interpret a command before it was trained or loaded."""


class Learner:
    """Learns word meanings from (command, demonstration) pairs and follows new commands.

    ``language_model`` is one of ``bow``, ``ibm2``, ``parse`` (default).
    ``library`` is a :class:`TaskLibrary` (default: the authored one).
    ``cache_dir`` holds behaviour likelihoods (see
    :func:`groundlang.inference.likelihoods.behaviour_log_likelihoods`).
    ``lexicon``: words the parser should know beyond English and the Cleanup World's
    (``logic/cleanup.words``): a word file's path, words by category (``{"NOUN": ["mug"]}``), or a
    list of them; the words are saved with the model. Raises LexiconError (a ValueError) naming file
    and line for a malformed word file. ``em_acceleration``: ``"squarem"`` or ``"none"``, how EM steps
    are chained (:mod:`groundlang.inference.em`; both reach the same MAP).
    """

    def __init__(self, language_model: str | LanguageModel = "parse", library: TaskLibrary | None = None,
                 steps: int = 300, lr: float = 0.1, seed: int = 0, settings: TaskSettings | None = None,
                 cache_dir: str | Path | None = None, lexicon: WordSource | Sequence[WordSource] | None = None,
                 em_acceleration: str = "squarem"):
        check_model_parts(language_model, library)
        self.lm = get_language_model(language_model) if isinstance(language_model, str) else language_model
        self.library = library if library is not None else TaskLibrary.load()
        if not self.library.tasks:  # a file of PFs only (discover --pfs) is a library of none
            raise ValueError(f"{self.library.program.user_names}: the task library declares no task/1; a learner "
                             "needs at least one task to read commands as")
        check_training_options(steps, lr, seed, settings, em_acceleration, cache_dir)
        self.steps = steps
        self.em_acceleration = em_acceleration
        self.lr = lr
        self.seed = seed
        self.settings = settings or TaskSettings()
        self.cache_dir = cache_dir
        # Only the added words are kept apart: they are what a saved model must carry to parse alike.
        # A library's word files (mine.words beside mine.lp) come first, then the words given here.
        own = word_files_beside(self.library)
        given = [] if lexicon is None else word_sources("Learner", lexicon)
        self.lexicon_words: dict[str, list[str]] = extra_words([*own, *given])
        self.word_lexicon = domain_lexicon(self.lexicon_words)
        self.vocab: Vocabulary | None = None
        # The palettes trained on, as {name, colours, shapes}: words were learned for their values only.
        self.palettes: list[dict] | None = None
        self.globals: dict[str, torch.Tensor] | None = None
        self.fit_result: FitResult | None = None
        self.habits: EndHabits | None = None  # what demonstrations left true besides their goals
        # folder -> the content hash of the model this learner read or wrote there (model_io): a save there
        # checks that it is still there
        self.models_seen: dict[Path, str] = {}
        self._interp_cache: dict[tuple[State, bool], list[Interpretation]] = {}
        self._held_shares = HeldShares()  # a command's other starts, read once for all its starts
        self._world = WorldPlans(self.library, self.settings)  # spaces and plans: the world's, not the words'

    def add_words(self, lexicon: WordSource | Sequence[WordSource]) -> "Learner":
        """Let the parser know more words (word files or words by category, as ``Learner(lexicon=...)``),
        e.g. a multiword preposition for a trained model; they are saved with the model. Words the
        vocabulary never saw in training stay unknown to the language model."""
        more = word_sources("add_words", lexicon)
        added = extra_words([self.lexicon_words, *more])
        self.lexicon_words = added
        self.word_lexicon = domain_lexicon(added)
        if self.vocab is not None:
            self.vocab.lexicon = self.word_lexicon
        return self

    # ----------------------------------------------------------------- observing
    def _interpretations(self, state: State, demonstrated: bool = False) -> list[Interpretation]:
        key = (state, demonstrated)
        if key not in self._interp_cache:
            self._interp_cache[key] = interpretations(
                state, self.library, enumerate_constraints=self.lm.enumerates_constraints,
                relation_words=self.lm.relation_words, held_parts=self.lm.held_parts,
                relational=self.lm.relational_descriptions, demonstrated=demonstrated,
                start_role=self.lm.start_role, bystander_roles=self.lm.bystander_roles)
        return self._interp_cache[key]

    def observe(self, instances: Sequence, progress: bool = False) -> list[Observation]:
        """Observations with behaviour likelihoods for training instances (cached on disk): see
        :func:`groundlang.observing.observations`."""
        from groundlang.observing import observations

        return observations(self, instances, progress)

    def _command_observation(self, command: str, state: State, held: bool = False) -> Observation:
        readings = tuple(parse(command, weights=self.lm.parser_weights, word_lexicon=self.word_lexicon))
        return Observation(tuple(readings[0].logical_form.words), readings,
                           tuple(self._interpretations(state, demonstrated=held)))

    # ----------------------------------------------------------------- training
    def _build_vocabulary(self, observations: Iterable[Observation], palettes: Iterable) -> Vocabulary:
        return build_vocabulary(observations, palettes, self.library, self.word_lexicon,
                                relational=self.lm.relational_descriptions, keys=self.lm.phrase_keys(),
                                start_role=self.lm.start_role, by_class=self.lm.bystander_roles,
                                names=self.lm.schema_names)

    def fit(self, instances: Sequence, progress: bool = False, init: dict | None = None,
            observations: list[Observation] | None = None, batch: Batch | None = None) -> "Learner":
        """Train on instances (anything with ``command``, ``initial_state``, ``states``, ``actions``).

        ``observations`` may be passed to reuse behaviour likelihoods computed
        once for several fits, and ``batch`` to reuse their encoding (as
        leave-one-out does with :meth:`Batch.subset`); both require the
        vocabulary they were encoded with to stay in place, as does ``init``,
        which warm-starts the globals.
        """
        instances = check_fit_arguments(instances, self.steps, init)
        if batch is None:
            if observations is None:
                observations = self.observe(instances, progress=progress)
            if init is None or self.vocab is None:
                palettes = sorted({inst.initial_state.layout.palette for inst in instances}, key=lambda p: p.name)
                vocab = self._build_vocabulary(observations, palettes)
                try:
                    check_parameter_bound(vocab)
                except ValueError as exc:
                    raise ValueError(f"the corpus cannot be learned from: {exc} (a model could not be loaded "
                                     "back): fewer distinct words, or a smaller corpus") from None
                self.vocab = vocab
                self.palettes = [p.record() for p in palettes]
                init = None
            batch = self.lm.encode(observations, self.vocab)
        elif self.vocab is None:
            raise ValueError("fit(batch=...) needs the vocabulary the batch was encoded with")
        if init is None and self.lm.starts_from_bag_of_words:
            # (From a flat start "star" was learned as a room word on the crowd corpus.)
            start = fit_globals(batch, BagOfWords(self.lm.word_concentration, schema_names=self.lm.schema_names), self.vocab,
                                steps=self.steps, seed=self.seed, acceleration=self.em_acceleration)
            init = {"phi": start.globals["phi"]}
        self.fit_result = fit_globals(
            batch, self.lm, self.vocab, steps=self.steps, lr=self.lr, seed=self.seed,
            init=init, progress=progress, acceleration=self.em_acceleration,
        )
        self.globals = self.fit_result.globals
        self.habits = EndHabits.learn(demonstrated_pairs(instances), self.library,
                                      known=known_new_relations(instances, self.library))
        return self

    # ----------------------------------------------------------------- using
    def _require_fitted(self) -> None:
        if self.globals is None or self.vocab is None:
            raise NotFittedError("this learner has not been trained: call fit() or Learner.load() first")

    def _check_state(self, method: str, command: str, state: State) -> None:
        """TypeError for arguments of the wrong type; ValueError for a state of a palette not trained on."""
        check_state(self.palettes, method, command, state)

    def words_reading(self, command: str, state: State, held: bool = False):
        """``(observation, [J] probabilities, reading probabilities or None)``: the command's readings and
        interpretations in ``state`` (with ``held``, goals holding there offered too) and the posterior over
        the interpretations from the words alone, conditioned on nothing (:meth:`posterior` conditions it)."""
        obs = self._command_observation(command, state, held)
        batch = self.lm.encode([obs], self.vocab)
        # The interpretation and the reading: the two sites the model enumerates per command.
        probs, structures = local_posteriors(batch, self.lm, self.globals, use_behaviour=False)
        reading_probs = None if structures is None else per_parser_reading(
            structures[0], batch, [r.probability for r in obs.readings])
        return obs, probs[0][: len(obs.interpretations)].double().numpy(), reading_probs

    def posterior(self, command: str, state: State, held: bool = False, other_starts: Sequence[State] = ()) -> Posterior:
        """Posterior over interpretations of ``command`` in ``state`` from the words, given (with the
        language model's ``achievable_goals``, the default) that the goal can be reached from ``state``.
        With ``held`` goals that already hold in ``state`` are offered too, as for a demonstration that
        leaves and comes back, and nothing is conditioned on what can be done: what the words say ("go to
        the blue room" said in it), of which following sets such goals aside (they ask nothing).
        ``other_starts``: the other states the command was given in (a Williams et al. command's other
        layouts); with the language model's ``other_starts``, a reading whose lifted task already holds in
        one of them is weighed down as the words there say it does (:mod:`groundlang.other_starts`).

        TypeError for a non-string command or a non-State state; ValueError when the state's palette
        is not one the model was trained on."""
        self._require_fitted()
        self._check_state("posterior", command, state)
        if not isinstance(held, bool):
            raise TypeError(f"posterior: held must be True or False, not {type(held).__name__}")
        other_starts = check_other_starts("posterior", other_starts)
        obs, probs, reading_probs = self.words_reading(command, state, held)
        space = self._world.space(state)
        masks = self._world.goal_masks(space)
        reach = (0.0, None)
        if self.lm.achievable_goals and not held:
            goals = [i.goal for i in obs.interpretations]
            out = unachievable_goals(set(goals), space, masks=masks)  # once, for both
            reach = out_of_reach(probs, goals, out)
            probs = given_achievable(probs, goals, masks, out)
        if self.lm.other_starts and other_starts and not held:
            # The start itself, given again, says nothing more (its held readings are set aside already).
            probs = given_other_starts(probs, obs.interpretations, [
                self._held_shares.of(self, command, other, f"posterior: other_starts[{k}]")
                for k, other in enumerate(other_starts) if other != state])
        post = Posterior(command, list(obs.interpretations), probs, list(obs.readings), reading_probs,
                         out_of_reach=reach[0], out_of_reach_goal=reach[1])
        post.groups = group_goals(post.goals(), space, self.library, masks)
        return post

    def follow(self, command: str, state: State, max_steps: int = 200,
               min_confidence: float | None = None, other_starts: Sequence[State] = ()) -> FollowResult:
        """Interpret ``command`` in ``state``, plan for the most probable grounded goal and act; with the
        language model's ``expected_success`` (the default), plan to end where the goals of the whole
        posterior most probably hold (:func:`groundlang.goal_plans.expected_success_states`).

        ``max_steps``: a positive integer. The state space is sized (and refused when no method can
        plan in it) before the command is interpreted, which on a large layout is the slow part; where
        the whole world is too large, the plan is made in the goal's relevance abstraction
        (:mod:`groundlang.model.relevance`) and ends, reason "scenery", before any move that would
        push a toy the abstraction holds still.
        With ``min_confidence`` (0 to 1), a reading less confident than that is not acted on:
        the result has ``abstained=True``, the ``question`` to ask, its ``choices`` and the
        ``unknown_words`` that left the words undecided; :meth:`clarify` takes the answer. It asks too where the
        words most probably ask, as surely, for what already holds (``already_true``), or say only what not to
        do (no choices): :mod:`groundlang.held_question`. ``other_starts``: the other states the command
        was given in (see :meth:`posterior`); they weigh the reading acted on, while whether what already
        holds is meant, and an answer to a question (:meth:`clarify`), are read in ``state`` alone."""
        check_count("follow", "max_steps", max_steps)
        check_threshold("follow", "min_confidence", min_confidence)
        self._require_fitted()
        self._check_state("follow", command, state)
        check_abstraction_possible(state)
        other_starts = check_other_starts("follow", other_starts)
        held = self.posterior(command, state, held=True) if min_confidence or self.lm.held_goals_confidence else None
        return follow_or_ask(command, state, held, min_confidence, self.library,
                             lambda: self._follow(command, state, max_steps, min_confidence, held, other_starts))

    def _follow(self, command: str, state: State, max_steps: int, min_confidence, held,
                other_starts: tuple[State, ...] = ()) -> FollowResult:
        post = self.posterior(command, state, other_starts=other_starts)
        ending = self.ending(post, state)
        # Planned before deciding: the confidence is read where the plan ends (plans are the world's, kept).
        if ending:  # where what was meant most probably holds, and the goal the nearest such state satisfies
            _, masks, goals, target, goal = ending
            acted = self._act(command, state, post, goal, max_steps, target, (goals, masks, post.best_goal))
        else:
            acted = self._act(command, state, post, post.best_goal, max_steps)
        if acted.success is not None and self.lm.held_goals_confidence:
            acted.success = held_goals_success(held, acted.success, acted.final_state, self.library)
        # Not where nothing can be done: no reading is within reach, so no answer could help.
        if min_confidence is not None and acted.confidence < min_confidence and acted.reason != "unreachable":
            choices = competing(post.goal_groups())
            unknown = unknown_words(post.readings, self._knows)
            return FollowResult(command, post, post.best_goal, [state], [], False, "abstained", abstained=True,
                                question=question(choices, unknown, state, self.library),
                                choices=choices, unknown_words=unknown, success=acted.success)
        return acted

    def ending(self, post: Posterior, state: State):
        """Where following ``post``'s command from ``state`` ends, with the language model's
        ``expected_success``: ``(space, goal masks, post.goals(), target [S] bool over space, the goal
        said to be acted on)`` (:func:`groundlang.goal_plans.expected_success_states`, weighed by the end
        habits with ``end_habits``); None where it plans for ``post.best_goal`` alone."""
        if not self.lm.expected_success:
            return None
        # Where the world fits, the space goals are compared in; else the most probable goal's relevance
        # abstraction, where its plan is made: the sample of placements goals are compared in tells them
        # apart but not how far its states are, and the abstraction's distances are a plan's.
        space = self._world.space(state, post.best_goal)
        masks, goals = self._world.goal_masks(space), post.goals()
        found = expected_success_states(goals, masks, self.lm.step_cost, self.habits if self.lm.end_habits else None,
                                        moved_toys=self.lm.moved_toys, made_true=self.lm.habits_made_true,
                                        bound=self.lm.bound_habits, habit_prior=self.lm.habit_prior)
        return None if found is None else (space, masks, goals, *found)

    def clarify(self, result: FollowResult, answer: str | int, max_steps: int = 200) -> FollowResult:
        """Act on the choice ``answer`` names among an abstained ``result``'s ``choices``: a number
        from 1 (an int, or its digits), words ("the green one") or, to a question of one choice, a yes.
        Raises AnswerError when it names none or several, its subclass Declined where it declines ("no"; to
        whether what already holds is meant, a no returns ``result.otherwise``); TypeError for wrong types."""
        answer = answer_text(answer, result)
        check_count("clarify", "max_steps", max_steps)
        if not result.abstained:
            raise ValueError("clarify() takes a result that abstained; this one acted already")
        state = result.states[0]
        self._require_fitted()  # a numeric answer never reads the words, but acting is this model's
        self._check_state("clarify", result.command, state)
        if any(a.predicate not in self.library.goal_relations for c in result.choices for a in c.goals[0]):
            raise ValueError("clarify: the result's choices are goals of another task library than this learner's "
                             "(answer it with the learner whose follow() made it)")
        if result.already_true:  # yes: nothing to do; no: the rest of the reading ("no, the blue room": its answer)
            return answer_held(result, answer, self.library, self.word_lexicon, lambda r, w: self.clarify(r, w, max_steps))
        chosen = choose(answer, result.choices, state, self.library,
                        read=lambda text, choices: clear_choice(
                            dict(self.posterior(f"{result.command}, {text}", state).goals()), choices,
                            before=dict(result.posterior.goals())), lexicon=self.word_lexicon)
        return self._act(result.command, state, result.posterior, chosen.goal, max_steps)

    def update(self, command: str, state: State, demonstration=None, goal=None) -> "Learner":
        """Fold one more example into the trained model, without refitting: ``command`` in ``state``
        with a ``demonstration`` (actions, or their words) and/or the ``goal`` it means (a goal
        string, a tuple of Atoms, or a :class:`GoalGroup` such as an abstained result's choice).
        New words join the vocabulary; see :mod:`groundlang.update`. Returns the learner.

        ValueError when neither is given, the goal is not one of the state's, or the state's
        palette is not the model's; TypeError for arguments of the wrong type."""
        from groundlang.update import update_learner

        return update_learner(self, command, state, demonstration=demonstration, goal=goal)

    def _knows(self, word: str) -> bool:
        return self.vocab is not None and self.vocab.word_id(word) != 0

    def _act(self, command: str, state: State, post: Posterior, goal: tuple[Atom, ...], max_steps: int,
             ending=None, goal_masks=None) -> FollowResult:
        """Plan for ``goal``, or to end in a state of ``ending`` (:meth:`WorldPlans.act`; ``goal_masks``: the
        posterior's goals, where they hold over the space of the ending, and the goal whose space it is)."""
        over = None if goal_masks is None else goal_masks[2]
        states, actions, reached, reason = self._world.act(state, goal, max_steps, ending, over)
        success = None
        if ending is not None:
            goals, masks, _ = goal_masks
            end = masks.space.index_of(states[-1])  # a plan moves within the space it was made in
            if reached:
                # Every state of ``ending`` is worth the same and the plan may end in any of them, not only
                # where ``goal`` holds: the goal said to be acted on is the one that holds where it ends.
                goal = goal_holding_at(goals, masks, end) or goal
            if self.lm.success_confidence:
                # Stopped short (max_steps, scenery): where the plan was going; the confidence is in the reading.
                success = success_at(goals, masks, end if reached else nearest_of(ending, masks.space))
        elif self.lm.expected_success and self.lm.success_confidence:  # one goal (an answer's, or none in reach)
            success = self._world.success_where(post.goals(), state, post.best_goal, states[-1])
        return FollowResult(command, post, goal, list(states), list(actions), reached, reason,
                            goal_words=goal_phrase(goal, state, self.library), success=success)

    def alignments(self, command: str, state: State, interpretation: int | None = None) -> list:
        """Which object each noun phrase names: :func:`groundlang.alignments.phrase_alignments`."""
        from groundlang.alignments import phrase_alignments

        return phrase_alignments(self, command, state, interpretation)

    def lexicon(self, top: int = 3) -> dict[str, list[tuple[str, float]]]:
        """Each known word's most probable meanings, ``P(token | word)``: tokens no training interpretation
        offered are left out (:func:`groundlang.model.language_model_base.word_meanings`)."""
        check_count("lexicon", "top", top)  # a slice would have taken -1 as "all but the last"
        self._require_fitted()
        return word_meanings(self.globals, self.vocab, top)

    # ----------------------------------------------------------------- persistence
    def state_dict(self) -> dict:
        """The trained model as plain values: JSON-ready settings, vocabulary, words, palettes and task
        library (as ASP text), and ``globals``, its tensors by name (:mod:`groundlang.learner_state`).
        NotFittedError before training."""
        if self.globals is None or self.vocab is None:
            raise NotFittedError("cannot save a learner that has not been trained")
        return learner_state(self)

    @classmethod
    def from_state_dict(cls, state: dict, where: str = "state_dict") -> "Learner":
        """The learner :meth:`state_dict` describes; without ``globals`` in ``state`` it has its
        vocabulary but no tensors yet (a loader reads them once it knows their shapes). ``where`` names
        the source in messages. KeyError, TypeError or ValueError for malformed values."""
        return learner_from_state(cls, state, where)

    def save(self, directory: str | Path) -> Path:
        """Write the model to ``directory`` as JSON and tensors (see :mod:`groundlang.model_io`). Over a
        folder this learner read a model from or saved one to, only if that still holds the model it read or
        wrote there: ValueError, and nothing written, when another run saved over it meanwhile."""
        directory = as_path(directory, "Learner.save: directory")
        try:
            here = directory.resolve()
        except (OSError, RuntimeError):  # a symlink loop: write_model says what is wrong with the folder
            here = None
        written, content = write_model(self.state_dict(), directory, replacing=self.models_seen.get(here))
        self.models_seen[written.resolve()] = content
        return written

    @classmethod
    def load(cls, directory: str | Path) -> "Learner":
        """Read a model :meth:`save` wrote; ModelFormatError on anything amiss."""
        return read_model(as_path(directory, "Learner.load: directory"), cls.from_state_dict)
