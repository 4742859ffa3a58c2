"""Task discovery from scratch: lifted tasks found in demonstrations, with no task library (the paper's TA).

For each distinct demonstration (instances that share an initial state and
actions are one piece of behavioural evidence), MLIRL fits non-negative
weights over every grounded position PF of the layout; the *top* features
(weight >= ``weight_margin`` x the largest, true when the demonstrator
stopped) and their conjunctions of up to ``max_conjuncts`` atoms are the
candidate goals. Each candidate goal is *lifted*: objects become typed
variables (agent ``A``, toy ``T``, room ``R``, door ``D``; one object, one
variable), so goals of different instances with the same structure are one
candidate lifted task.

Which lifted tasks form the library is decided by a two-part code length
(minimum description length), summed over the distinct demonstrations::

    J(library) = sum_i max_{L in library} [ max_T log P(B_i | T) - log |G_L(S_i)| ]
                 - D log |library| - atom_cost * (goal atoms in the library)

``log P(B_i | T)`` is the behaviour likelihood of demonstration ``i`` under
grounding ``T`` (the planner's Boltzmann policy with a terminate action,
:func:`groundlang.inference.likelihoods.behaviour_likelihood_table`);
``G_L(S_i)`` are the groundings of ``L`` not already true in the initial
state (clingo, :func:`groundlang.model.tasks.candidate_tasks`), so naming one
costs ``log |G_L|``; naming the task costs ``log |library|`` per
demonstration, and writing a task down costs ``atom_cost`` per goal atom
(default ``log 5``: one of five position predicates). This is what breaks
near-ties that MLIRL weights alone leave open: a toy that ends on a door cell
inside a room makes ``toyInDoor`` and ``toyInRoom`` weigh the same, but the
path is far more probable under "toy into the room", and that structure is
shared with the other toy demonstrations. Conjunctions that add an incidental
atom (the agent next to the toy it just pushed) gain a fraction of a nat and
pay for more groundings and a longer task. The library maximising ``J`` is
found by exhaustive search over subsets (up to ``max_tasks`` tasks), or by
backward elimination when there are too many candidates.

Colour and shape PFs never enter a lifted task here: what tells objects
apart is left to the binding constraints (the words). The report records,
per demonstration, the smallest colour/shape conjunction that singles out
each bound object in its initial state (``roomIsGreen``; nothing for a lone
toy; ``None`` when no colour/shape PF can, e.g. for doors).
"""

from __future__ import annotations

import logging
import math
import os
from dataclasses import dataclass, field, replace
from itertools import combinations
from typing import Sequence

import numpy as np

from groundlang.inference.library_search import select_library
from groundlang.inference.library_text import library_text, write_library
from groundlang.inference.likelihoods import behaviour_likelihood_table
from groundlang.inference.mlirl import mlirl
from groundlang.inference.planning import TaskSettings
from groundlang.logic.atoms import Atom
# lifted_key is part of discovery's public surface (tests and notebooks import it from here).
from groundlang.inference.lifting import lift_goal, lifted_key, singling_out, structure_key, task_name  # noqa: F401
from groundlang.logic.program import Source
from groundlang.logic.tasks import GroundedTask, LiftedTask, TaskLibrary, format_lifted_task

__all__ = ["DISCOVERY_IRL", "DiscoverySettings", "DemonstrationReport", "Discovery", "discover_tasks",
           "lift_goal", "lifted_key", "structure_key", "task_name", "singling_out", "write_library"]

logger = logging.getLogger(__name__)

# Same MLIRL settings as ``groundlang irl``: non-negative weights with a sparsity prior let the
# whole path, not only where it stopped, pick the proposition that was wanted.
DISCOVERY_IRL = dict(temperature=0.5, l1=0.1, nonnegative=True)


@dataclass(frozen=True)
class DiscoverySettings:
    """Knobs of :func:`discover_tasks` (see the module docstring for the score they enter)."""

    weight_margin: float = 0.5  # top features: weight >= margin * largest weight
    max_conjuncts: int = 2  # candidate goals: conjunctions of up to this many top features
    atom_cost: float = math.log(5)  # nats per goal atom written into the library
    max_tasks: int = 4  # largest library the search considers
    # Restrict each lifted variable by the colour/shape PFs that single out its object in every
    # demonstration the task explains (restrict/3 facts). Off by default: the paper's lifted tasks
    # keep those PFs as parameters (P1(t), P2(r)), which the binding constraints are; a restriction
    # learned from one star demonstration would forbid the same task for the moon.
    restrict: bool = False
    irl: dict = field(default_factory=lambda: dict(DISCOVERY_IRL))
    task: TaskSettings = TaskSettings()  # behaviour likelihood settings (part of the cache key)

    def __post_init__(self):
        if not 0.0 < self.weight_margin <= 1.0:
            raise ValueError(f"weight_margin must be in (0, 1], got {self.weight_margin}")
        if self.max_conjuncts < 1 or self.max_tasks < 1:
            raise ValueError(f"max_conjuncts and max_tasks must be >= 1, "
                             f"got {self.max_conjuncts} and {self.max_tasks}")


@dataclass(frozen=True)
class DemonstrationReport:
    """What discovery found for one distinct demonstration (shared by ``instances``).

    ``weights``: MLIRL weight of every position PF, largest first; ``top_features``: those that
    became candidate goal atoms. ``scores``: per candidate lifted task, ``max_T log P(B | T) -
    log |G_L|`` (-inf when it has no grounding here). ``task``/``grounding``/``log_likelihood``:
    the library task that explains the demonstration best, its best grounding and that grounding's
    behaviour log-likelihood (None/None/-inf when nothing in the library applies).
    ``singled_out``: per variable, the smallest colour/shape conjunction true of its object that no
    other object of its class satisfies (``()`` when no other object exists, None when none does).
    """

    instances: tuple[str, ...]
    num_states: int
    weights: tuple[tuple[Atom, float], ...]
    top_features: tuple[tuple[Atom, float], ...]
    mlirl_log_likelihood: float
    scores: tuple[tuple[str, float], ...]
    task: str | None = None
    grounding: GroundedTask | None = None
    log_likelihood: float = -math.inf
    singled_out: tuple[tuple[str, tuple[Atom, ...] | None], ...] = ()

    def to_json(self) -> dict:
        return {
            "instances": list(self.instances),
            "states": self.num_states,
            "top_features": {str(a): round(w, 6) for a, w in self.top_features},
            "mlirl_log_likelihood": self.mlirl_log_likelihood,
            "scores": {n: (s if math.isfinite(s) else None) for n, s in self.scores},
            "task": self.task,
            "goal": None if self.grounding is None else self.grounding.goal_text,
            "log_likelihood": self.log_likelihood if math.isfinite(self.log_likelihood) else None,
            "singled_out": {v: (None if c is None else [str(a) for a in c]) for v, c in self.singled_out},
        }


@dataclass(frozen=True)
class Discovery:
    """Result of :func:`discover_tasks`: the library (loaded back from its own ASP text) and the reports."""

    library: TaskLibrary
    tasks: tuple[LiftedTask, ...]
    candidates: tuple[LiftedTask, ...]
    demonstrations: tuple[DemonstrationReport, ...]
    score: float
    text: str  # the library as commented ASP, as write_library writes it
    alternatives: tuple[tuple[tuple[str, ...], float], ...] = ()  # best libraries and their J, best first

    def report_for(self, instance: str) -> DemonstrationReport:
        """The report of the demonstration an instance (by name) belongs to; KeyError if none."""
        for r in self.demonstrations:
            if instance in r.instances:
                return r
        raise KeyError(f"no demonstration has an instance named {instance!r}")

    def to_json(self) -> dict:
        explained = {t.name: [r.instances[0] for r in self.demonstrations if r.task == t.name] for t in self.tasks}
        return {
            "lifted_tasks": [{"name": t.name, "task": str(t), "variables": {v.name: v.cls for v in t.variables},
                              "goal": [[p, list(a)] for p, a in t.goal], "demonstrations": explained[t.name]}
                             for t in self.tasks],
            "score": self.score,
            "alternatives": [{"tasks": list(names), "score": s} for names, s in self.alternatives],
            "demonstrations": [r.to_json() for r in self.demonstrations],
        }


# ---------------------------------------------------------------- the pipeline


@dataclass
class _Demo:
    instance: object  # a representative instance (initial_state, states, actions)
    names: tuple[str, ...]
    num_states: int = 0
    weights: tuple = ()
    top: tuple = ()
    mlirl_ll: float = math.nan
    goals: list = field(default_factory=list)  # candidate grounded goals (tuples of Atoms)


def _object_classes(layout) -> dict[str, str]:
    return {name: cls for cls, name, _ in layout.objects}


def _peers(layout, obj: str) -> list[str]:
    """The other objects of ``obj``'s class in ``layout``."""
    classes = _object_classes(layout)
    return [p for p, c in classes.items() if c == classes[obj] and p != obj]


def _group(instances: Sequence) -> list[_Demo]:
    """Instances sharing (initial state, actions), first-seen order."""
    groups: dict[tuple, _Demo] = {}
    for i, inst in enumerate(instances):
        key = (inst.initial_state, tuple(int(a) for a in inst.actions))
        name = getattr(inst, "name", None) or f"instance{i}"
        if key in groups:
            groups[key].names += (name,)
        else:
            groups[key] = _Demo(inst, (name,))
    return list(groups.values())


def _fit_top_features(demo: _Demo, settings: DiscoverySettings, pfs: TaskLibrary | None = None) -> None:
    """MLIRL over every position PF (``pfs``'s too); keep the top features true at the end as candidate goal
    atoms."""
    from groundlang.model.features import feature_matrix, position_atoms
    from groundlang.model.pf_tables import library_pf_tables
    from groundlang.model.relevance import state_space_for
    from groundlang.model.statespace import trajectory_indices

    inst = demo.instance
    # the exact space, or where it does not fit the toys the demonstration moves (the others as walls)
    space = state_space_for(inst.initial_state, demonstrations=[inst.states])
    tables = library_pf_tables(space.layout, pfs)
    atoms = position_atoms(space.layout, tables)
    features = feature_matrix(space, atoms, tables).numpy()
    states = trajectory_indices(space, list(inst.states))
    actions = [int(a) for a in inst.actions]
    fit = mlirl(space.next_state, features, [(states, actions)], **settings.irl)
    order = np.argsort(-fit.weights, kind="stable")
    demo.num_states = space.num_states
    demo.weights = tuple((atoms[j], float(fit.weights[j])) for j in order)
    demo.mlirl_ll = fit.log_likelihood
    largest = float(fit.weights.max()) if len(atoms) else 0.0
    final, initial = features[states[-1]] > 0.5, features[states[0]] > 0.5
    top = [j for j in order if largest > 0 and fit.weights[j] >= settings.weight_margin * largest and final[j]]
    demo.top = tuple((atoms[j], float(fit.weights[j])) for j in top)
    for k in range(1, min(settings.max_conjuncts, len(top)) + 1):  # no subset has more than len(top)
        for subset in combinations(top, k):
            if not all(initial[j] for j in subset):
                demo.goals.append(tuple(atoms[j] for j in subset))
    if not demo.goals:
        logger.warning("discovery: demonstration of %s has no candidate goal (no weighted PF that became true)",
                       demo.names[0])


def _candidate_tasks(demos: list[_Demo]) -> list[LiftedTask]:
    """The lifted structures of every demonstration's candidate goals, each once, named readably."""
    candidates: dict[tuple, LiftedTask] = {}
    for demo in demos:
        classes = _object_classes(demo.instance.initial_state.layout)
        for goal in demo.goals:
            key = structure_key([(a.predicate, a.args) for a in goal], classes)
            if key in candidates:
                continue
            lifted = lift_goal(goal, classes)
            taken = {t.name for t in candidates.values()}
            name, n = lifted.name, 1
            while name in taken:  # e.g. one room for toy and agent, or two rooms: same predicates
                n += 1
                name = f"{lifted.name}{n}"
            candidates[key] = replace(lifted, name=name)
    return list(candidates.values())


def _score_table(demos: list[_Demo], library: TaskLibrary, settings: DiscoverySettings, cache_dir, progress):
    """``(scores [D, L], best [D] of {task index: (log-likelihood, grounding)})`` for the library's tasks.

    ``scores[i, j] = max_T log P(B_i | T) - log |G_j(S_i)|`` over the groundings clingo enumerates
    (-inf where task ``j`` has none).
    """
    from groundlang.model.tasks import candidate_tasks

    index = {t.name: j for j, t in enumerate(library.tasks)}
    groundings = [candidate_tasks(d.instance.initial_state, library) for d in demos]
    rows = behaviour_likelihood_table([d.instance for d in demos], [[g.goal for g, _ in row] for row in groundings],
                                      settings.task, cache_dir=cache_dir, progress=progress, library=library)
    scores = np.full((len(demos), len(library.tasks)), -math.inf)
    best: list[dict[int, tuple[float, GroundedTask]]] = []
    for i, (row, lls) in enumerate(zip(groundings, rows)):
        per_task: dict[int, list[tuple[float, GroundedTask]]] = {}
        for (g, _), ll in zip(row, lls):
            per_task.setdefault(index[g.task], []).append((float(ll), g))
        best.append({})
        for j, items in per_task.items():
            best[i][j] = max(items, key=lambda item: item[0])  # first of equals: enumeration order
            scores[i, j] = best[i][j][0] - math.log(len(items))
    return scores, best


def discover_tasks(instances: Sequence, settings: DiscoverySettings = DiscoverySettings(),
                   cache_dir: str | os.PathLike | None | bool = None, progress: bool = False,
                   pfs: TaskLibrary | None = None) -> Discovery:
    """Discover a task library from demonstrations alone (no labels, no words, no library).

    ``instances``: objects with ``initial_state``, ``states``, ``actions`` and optionally ``name``
    (e.g. ``groundlang.corpus.Instance``); identical (initial state, actions) pairs count once.
    ``cache_dir``: behaviour-likelihood cache root (False: none), see inference.likelihoods.
    ``pfs``: a library whose colour and shape PFs (pfs.lp's and its own families, as clingo describes
    each initial state) tell objects apart in the reports and the restrictions, and whose own position PFs
    are candidate goals beside pfs.lp's; default pfs.lp's. It declares no tasks.
    Returns a :class:`Discovery`; its library is loaded back from the commented ASP text.
    Raises ValueError when there are no instances, no candidate goal, or no library of at most
    ``max_tasks`` tasks covers every demonstration that has one.
    """
    if not instances:
        raise ValueError("discover_tasks needs at least one instance")
    if pfs is not None and pfs.tasks:
        raise ValueError(f"{pfs.program.user_names}: declares tasks ({', '.join(pfs.names)}); discovery takes "
                         "PFs from it, not tasks")
    demos = _group(instances)
    logger.debug("discovery: %d instances, %d distinct demonstrations", len(instances), len(demos))
    # Before any MLIRL work: a PF file that fails on an environment is reported at once.
    attributes = [_attributes(demo, pfs) for demo in demos]
    for demo in demos:
        _fit_top_features(demo, settings, pfs)
    lifted = _candidate_tasks(demos)
    if not lifted:
        raise ValueError("no demonstration yields a candidate goal: nothing can be discovered")
    # beside the PF files, whose position PFs may be candidates' goals
    candidates = TaskLibrary([Source("<discovery candidates>", "".join(format_lifted_task(t) for t in lifted)),
                              *(pfs.sources if pfs else ())], **({"time_limit": pfs.time_limit} if pfs else {}))
    scores, best = _score_table(demos, candidates, settings, cache_dir, progress)
    sizes = np.array([len(t.goal) for t in candidates.tasks])
    usable = np.isfinite(scores).any(axis=1)
    ranked = select_library(scores[usable], sizes, settings.atom_cost, settings.max_tasks) if usable.any() else []
    if not ranked:
        raise ValueError(f"no library of at most {settings.max_tasks} candidate tasks explains every "
                         "demonstration that has a candidate goal")
    chosen, score = ranked[0]
    reports = []
    for i, demo in enumerate(demos):
        report = DemonstrationReport(demo.names, demo.num_states, demo.weights, demo.top, demo.mlirl_ll,
                                     tuple((t.name, float(scores[i, j])) for j, t in enumerate(candidates.tasks)))
        applicable = [j for j in chosen if np.isfinite(scores[i, j])]
        if applicable:
            j = max(applicable, key=lambda j: scores[i, j])
            ll, g = best[i][j]
            layout = demo.instance.initial_state.layout
            picked = tuple((v, singling_out(layout, o, _peers(layout, o), attributes[i])) for v, o in g.binding)
            report = replace(report, task=candidates.tasks[j].name, grounding=g, log_likelihood=ll,
                             singled_out=picked)
        reports.append(report)
    tasks = tuple(candidates.tasks[j] for j in chosen)
    if settings.restrict:
        tasks = tuple(_restricted(t, reports, demos, attributes) for t in tasks)
    text = library_text(tasks, reports, score, settings, len(instances), pfs)
    # Loaded back beside the PF files its restrictions may name, so that they are checked now.
    library = TaskLibrary([Source("<discovered tasks>", text), *(pfs.sources if pfs else ())],
                          **({"time_limit": pfs.time_limit} if pfs else {}))
    logger.info("discovery: library %s (score %.3f)", ", ".join(t.name for t in tasks), score)
    alternatives = tuple((tuple(candidates.tasks[j].name for j in subset), s) for subset, s in ranked)
    return Discovery(library, library.tasks, candidates.tasks, tuple(reports), score, text, alternatives)


def _attributes(demo: _Demo, pfs: TaskLibrary | None):
    """Object -> its ``(colour/shape PF name, term)`` pairs in the demonstration's initial state:
    pfs.lp's families, or every family ``pfs`` declares (clingo's ``described/3``)."""
    from groundlang.model.tasks import attribute_pfs, object_descriptions

    state = demo.instance.initial_state
    if pfs is None:
        return attribute_pfs(state, TaskLibrary.load())

    if not object_descriptions(state, pfs):  # pfs.lp alone describes every room by its colour
        raise ValueError(f"{pfs.program.user_names}: describes no object of the initial state of {demo.names[0]} "
                         "(does a constraint leave that environment without an answer set?)")
    return attribute_pfs(state, pfs)


def _restricted(task: LiftedTask, reports, demos, attributes) -> LiftedTask:
    """``task`` restricted, per variable, by what singles out its object in every demonstration it explains.

    The restriction is the smallest conjunction of colour/shape PFs true of the object in every one
    of them and of none of its peers (same class) in any: a yellow star beside a moon and a red star
    beside a moon give ``toyIs(star)``, though each alone is told apart by its colour first. Among
    conjunctions of one size the first wins, in the order of the first demonstration's PFs (colour
    PFs, then shape PFs, each by name). A variable whose object had no peers in some demonstration,
    or cannot be told apart from them in all by PFs it always has, is left free (the room of
    toy-to-room, reached in rooms of every colour).
    """
    index = {d.names: i for i, d in enumerate(demos)}
    explained = [r for r in reports if r.task == task.name]
    restrictions = []
    for var in task.variables:
        cases = []  # per demonstration: the object's PFs (name -> term) and its peers' PF-name sets
        for r in explained:
            if not dict(r.singled_out).get(var.name):  # () no peers, None no distinguishing PFs
                cases = []
                break
            i = index[r.instances]
            obj = r.grounding.object_of(var.name)
            peers = [{name for name, _ in attributes[i].get(p, ())}
                     for p in _peers(demos[i].instance.initial_state.layout, obj)]
            cases.append((dict(attributes[i].get(obj, ())), peers))
        shared = [name for name in (cases[0][0] if cases else ()) if all(name in own for own, _ in cases)]
        restrictions += [(var.name, cases[0][0][name]) for name in _smallest_exclusion(shared, cases)]
    return replace(task, restrictions=tuple(restrictions)) if restrictions else task


def _smallest_exclusion(names: Sequence[str], cases) -> tuple[str, ...]:
    """The first smallest subset of ``names`` that no peer of any case has all of; () if none."""
    for k in range(1, len(names) + 1):
        for subset in combinations(names, k):
            if not any(set(subset) <= peer for _, peers in cases for peer in peers):
                return subset
    return ()
