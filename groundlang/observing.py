"""Training instances as the joint model observes them: readings, interpretations and behaviour likelihoods."""

from __future__ import annotations

from collections.abc import Sequence

from groundlang.inference.likelihoods import behaviour_likelihood_table
from groundlang.inference.parse_cache import ParseCache
from groundlang.inference.shared_meaning import end_state_behaviour
from groundlang.model.encoding import Observation
from groundlang.model.interpretations import NoTaskError, without_unbroken_held_parts
from groundlang.model.pf_tables import TabulationError, library_pf_tables, program_digest
from groundlang.model.tasks import check_position_pfs
from groundlang.training_vocabulary import unlisted_schema_words

__all__ = ["observations"]


def observations(learner, instances: Sequence, progress: bool = False) -> list[Observation]:
    """What ``learner`` (a :class:`~groundlang.learner.Learner`) trains on: each instance's readings of its
    command, its interpretations in its initial state, and the likelihood of its behaviour under each. The
    behaviour is a demonstration (MLIRL's likelihood, cached on disk) or a (start, end) pair (the end
    state's likelihood, :mod:`groundlang.inference.end_states`); one corpus is of one kind. Words the
    palettes' schemas name that the learner's word file lacks are added to it first."""
    palettes = {inst.initial_state.layout.palette: None for inst in instances}
    words = unlisted_schema_words(learner.library, palettes, learner.word_lexicon)
    if any(words.values()):
        learner.add_words(words)
    _check_users_position_pfs(learner.library, instances)
    shown = [getattr(inst, "actions", None) is not None for inst in instances]
    interps = []
    for inst in instances:
        try:
            interps.append(learner._interpretations(inst.initial_state, demonstrated=all(shown)))
        except NoTaskError as exc:  # one state of many: say whose (corpus readers leave most such out)
            raise NoTaskError(f"{_where(inst)}: {exc}") from None
    if not any(shown):  # (start, end) pairs: end states' likelihoods (inference.end_states, shared_meaning)
        behaviour = end_state_behaviour(instances, interps, learner.library)
    elif all(shown):
        goals = [sorted({i.goal for i in group}) for group in interps]
        table = behaviour_likelihood_table(
            instances, goals, learner.settings, cache_dir=learner.cache_dir, progress=progress, library=learner.library
        )
        by_goal = [dict(zip(g, row)) for g, row in zip(goals, table)]
        behaviour = [[float(lookup[i.goal]) for i in group] for lookup, group in zip(by_goal, interps)]
    else:
        raise ValueError("observe: instances with demonstrations and (start, end) pairs without them "
                         "cannot be mixed in one corpus")
    if all(shown) and learner.lm.held_parts:
        tables = [library_pf_tables(inst.initial_state.layout, learner.library) for inst in instances]
        interps, behaviour = without_unbroken_held_parts(interps, behaviour, [i.states for i in instances], tables)
        if (empty := next((inst for inst, group in zip(instances, interps) if not group), None)) is not None:
            # Every task the state admits already holds there and the demonstration never breaks it.
            raise NoTaskError(f"{_where(empty)}: no task of the library is carried out by this demonstration: every "
                              "goal the start state admits holds there already and along the demonstration")
    out = []
    parsed: dict[str, tuple] = {}  # a text said again is parsed once
    parses = ParseCache(learner.cache_dir)
    for inst, group, values in zip(instances, interps, behaviour):
        if inst.command not in parsed:
            parsed[inst.command] = parses.readings(inst.command, learner.lm.parser_weights, learner.word_lexicon)
        readings = parsed[inst.command]
        out.append(
            Observation(
                tuple(readings[0].logical_form.words),
                readings,
                tuple(group),
                tuple(values),
            )
        )
    parses.report()
    return out


def _check_users_position_pfs(library, instances: Sequence) -> None:
    """A library's goal PF that reads where another object is would be learned from tables that say
    otherwise than its groundings (``model.tasks.check_position_pfs``, as ``tasks`` checks it): refused
    at the first start state of each layout, naming its file and line. The package's own PFs are not
    checked (their tests do), nor a layout too large to tabulate (training says so where it needs it)."""
    if program_digest(library.tabulation_program) is None:
        return
    first = {}
    for inst in instances:
        first.setdefault(inst.initial_state.layout, inst)
    for layout, inst in first.items():
        try:
            tables = library_pf_tables(layout, library)
        except TabulationError:
            continue
        try:
            check_position_pfs(inst.initial_state, library, tables)
        except TabulationError as exc:
            raise TabulationError(f"{_where(inst)}: {exc}") from None


def _where(inst) -> str:
    return f"{inst.path}, line {inst.line}" if hasattr(inst, "line") else str(inst.path)
