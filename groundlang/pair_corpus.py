"""Training instances from a corpus of (start, end) pairs (Williams et al. 2018, ``.bdm``).

Such a corpus shows no trajectory, so a pair becomes evidence in one of two ways (``demonstrations``):

- ``"end-state"`` (the default): a :class:`PairInstance`, whose behaviour term is the likelihood of its
  end state under each grounded task (``inference.end_states``): no planning while training.
- ``"shortest-plan"``: a corpus :class:`~groundlang.corpus.Instance` whose demonstration is a shortest
  plan from the start to exactly the end state (``pair_tasks.shortest_actions``; of several shortest
  plans the first in a fixed order), scored by MLIRL's behaviour likelihood like a recorded one.

Which is better was measured on a development split (ABLATIONS.md). End-state evidence is computed
once per distinct pair and kept in the cache folder (``inference.evidence_cache``). A pair too large
to enumerate is scored, with end-state evidence, in the relevance abstraction where the toys it moves
move (``inference.shared_meaning``); one too large even for that, or in a layout whose PFs are too large
to tabulate (``pf_tables.check_table_size``), is skipped and counted; one whose end
state cannot be reached from its start is an inconsistent demonstration (an error naming file and
line, or skipped with ``skip_inconsistent``), and so is one whose start state admits no task of the
library (every grounding impossible or already true): it can be evidence of no reading.
"""

from __future__ import annotations

import hashlib
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from groundlang.bdm import DEFAULT_PALETTE, Command, bdm_files, read_bdm
from groundlang.corpus import CorpusError, InconsistentDemonstration, Instance
from groundlang.inference.end_states import EndStateNoise
from groundlang.inference.evidence_cache import EvidenceCache
from groundlang.logic.storage import as_path
from groundlang.logic.tasks import TaskLibrary
from groundlang.model.relevance import STATE_SOURCE, abstraction_bound, exact_fits, reading_states, relevant_toys
from groundlang.model.state_search import StateKeyError
from groundlang.model.statespace import StateSpaceError
from groundlang.model.tasks import candidate_tasks
from groundlang.model.world import State, replay
from groundlang.model.pf_tables import tabulation_refusal
from groundlang.pair_tasks import REACHABILITY_MAX_STATES, shortest_actions

__all__ = ["PairInstance", "PairedCommand", "PairCorpus", "LAYOUTS", "read_pair_corpus", "training_instances", "held_out_by_text",
           "text_position", "fold_of_text", "DEMONSTRATIONS"]

DEMONSTRATIONS = ("end-state", "shortest-plan")
# How a command's pairs in several layouts are used: as one instance of one lifted meaning, or each as
# an instance of its own (the baseline). Shared needs end-state evidence (no trajectories to multiply).
LAYOUTS = ("shared", "separate")


@dataclass(frozen=True)
class PairInstance:
    """One (start, end) pair of a command, as a training instance without a trajectory."""

    path: Path
    line: int  # of the start state
    command: str
    initial_state: State
    final_state: State
    actions: None = None  # no demonstration: the learner scores the end state (inference.end_states)
    evidence: tuple = field(default=(), compare=False, repr=False)  # inference.shared_meaning.LayoutEvidence

    @property
    def name(self) -> str:
        return f"{Path(self.path).name}:{self.line}"


@dataclass(frozen=True)
class PairedCommand:
    """A command with its usable (start, end) pairs, each in its own layout: one training instance whose
    interpretations are read in the first pair's layout and whose behaviour term multiplies the pairs'
    under one lifted meaning (``inference.shared_meaning``)."""

    path: Path
    line: int  # of the command
    command: str
    pairs: tuple[tuple[State, State], ...]
    actions: None = None
    evidence: tuple = field(default=(), compare=False, repr=False)  # one LayoutEvidence per pair

    @property
    def initial_state(self) -> State:
        return self.pairs[0][0]

    @property
    def final_state(self) -> State:
        return self.pairs[0][1]

    @property
    def name(self) -> str:
        return f"{Path(self.path).name}:{self.line}"


@dataclass
class PairCorpus:
    """The commands of one or more ``.bdm`` files, in file order."""

    paths: list[Path]
    commands: list[Command]

    def __len__(self) -> int:
        return len(self.commands)


def read_pair_corpus(path: str | Path, palette=DEFAULT_PALETTE, any_name: bool = False) -> PairCorpus:
    """Every command of a ``.bdm`` file, or of the ``.bdm`` files of a folder (sorted by name); with
    ``any_name`` (the format said), a file of any name, or a folder's ``.txt`` files where it has no
    ``.bdm`` file (:func:`groundlang.bdm.bdm_files`)."""
    paths = bdm_files(as_path(path, "read_pair_corpus: path"), any_name)
    if not paths:
        raise CorpusError(f"{path}: no .bdm file there (a .bdm file or a folder of them"
                          f"{'; with --format williams2018 also a file of any name or a folder of .txt files' if any_name else ''})")
    return PairCorpus(paths, [c for p in paths for c in read_bdm(p, palette)])


def held_out_by_text(commands: list[Command], fraction: float,
                     tuning: bool = False) -> tuple[list[Command], list[Command]]:
    """A development split disjoint by command text: a text is held out when its hash (SHA-256 of the
    lower-cased, stripped text) falls in the first ``fraction`` of the range, so every copy of a text
    lands on one side, and the split is the same on every machine and for every corpus order.

    With ``tuning``, a split to choose mechanisms on that leaves the development split unseen: the texts
    in the next ``fraction`` of the range are held out and those beyond it trained on; the development
    split's commands are in neither (``fraction`` below one half)."""
    if not 0 < fraction < 1:
        raise ValueError(f"held-out fraction {fraction}: expected a number strictly between 0 and 1")
    if tuning and not fraction < 0.5:
        raise ValueError(f"held-out fraction {fraction}: a tuning split holds out the next {fraction} of the "
                         "texts after the development split's, so it must be below 0.5")

    low, high = (fraction, 2 * fraction) if tuning else (0.0, fraction)
    where = [text_position(c.text) for c in commands]
    train = [c for c, x in zip(commands, where) if x >= high]
    test = [c for c, x in zip(commands, where) if low <= x < high]
    return train, test


def text_position(text: str) -> float:
    """Where a command's text falls in [0, 1): the first 8 bytes of the SHA-256 of the lower-cased,
    stripped text. Every split by text cuts this range, so each copy of a text lands on one side."""
    digest = hashlib.sha256(text.strip().lower().encode("utf-8")).digest()
    return int.from_bytes(digest[:8], "big") / 2**64


def fold_of_text(text: str, folds: int, beyond: float = 0.0) -> int | None:
    """The fold (0 to ``folds - 1``) that holds out ``text`` in a ``folds``-fold split by text: fold ``k``
    holds out the texts whose position falls in ``[k / folds, (k + 1) / folds)``, so with five folds fold 0
    is ``held_out_by_text(commands, 0.2)``'s held-out side and fold 1 the tuning split's.

    With ``beyond`` (a development split's fraction), the folds cut only the range from ``beyond`` on, in
    equal parts, and a text before it is in no fold (None): cross-validation that never reads that split."""
    if folds < 2:
        raise ValueError(f"{folds} folds: a split by text needs at least 2")
    if not 0 <= beyond < 1:
        raise ValueError(f"beyond={beyond}: expected a fraction in [0, 1)")
    x = text_position(text)
    if beyond:
        if x < beyond:
            return None
        return next(k for k in range(folds) if x < beyond + (k + 1) * (1 - beyond) / folds or k == folds - 1)
    # Compared with the same quotients held_out_by_text's bounds are (0.2, 2 * 0.2 == 2 / 5), not floor(x * k),
    # whose rounding could put a text on the boundary into another fold than the held-out split does.
    return next(k for k in range(folds) if x < (k + 1) / folds)


@dataclass
class TrainingPairs:
    """What :func:`training_instances` made of a corpus, and what it left out (command, pair, why)."""

    instances: list = field(default_factory=list)
    commands: list[int] = field(default_factory=list)  # the command index of each instance
    skipped: list[tuple[Command, object, str]] = field(default_factory=list)

    def skipped_by(self, reason: str) -> int:
        return sum(1 for _, _, why in self.skipped if why == reason)

    def skipped_counts(self) -> dict[str, int]:
        """Reason -> how many pairs were skipped for it."""
        return dict(Counter(why for _, _, why in self.skipped))


def skipped_text(counts: dict[str, int]) -> str:
    """Skipped pairs as the CLI says them ("3 too large to tabulate, 1 unreachable"); "" for none."""
    return ", ".join(f"{n} {why}" for why, n in sorted(counts.items()))


@reading_states()  # each pair named in the log lines of the spaces sized for it
def training_instances(commands: list[Command], library: TaskLibrary, demonstrations: str = "end-state",
                       skip_inconsistent: bool = False, max_states: int = REACHABILITY_MAX_STATES,
                       layouts: str = "shared", cache_dir=None) -> TrainingPairs:
    """The instances of ``commands``' pairs (see the module docstring); pairs too large to enumerate are
    skipped as ``"too large"`` (``"too large to tabulate"`` in a layout too large for PF tables), unreachable ones and those whose start state admits no task raise
    InconsistentDemonstration unless ``skip_inconsistent`` (then skipped as ``"unreachable"`` or
    ``"no task"``). With ``layouts="shared"`` (end-state
    evidence only) a command's usable pairs make one :class:`PairedCommand`. End-state evidence is read
    from and written to the cache folder ``cache_dir`` (``inference.evidence_cache``; None: the
    default, False: none)."""
    if demonstrations not in DEMONSTRATIONS:
        raise ValueError(f"demonstrations={demonstrations!r}: expected one of {', '.join(DEMONSTRATIONS)}")
    if layouts not in LAYOUTS:
        raise ValueError(f"layouts={layouts!r}: expected one of {', '.join(LAYOUTS)}")
    if layouts == "shared" and demonstrations != "end-state":
        raise ValueError("layouts='shared' multiplies end-state evidence; with shortest-plan demonstrations "
                         "use layouts='separate'")
    out = TrainingPairs()
    noise = EndStateNoise()
    cache = EvidenceCache(library, noise, cache_dir) if demonstrations == "end-state" else None
    for index, command in enumerate(commands):
        usable = []
        for pair in command.pairs:
            STATE_SOURCE.set(where := f"{command.path}, line {pair.line}")
            if tabulation_refusal(pair.start.layout) is not None:  # before a state is enumerated or it is grounded
                out.skipped.append((command, pair, "too large to tabulate"))
                continue
            if not _fits(pair, demonstrations, max_states):
                out.skipped.append((command, pair, "too large"))
                continue
            if demonstrations == "shortest-plan":
                actions = shortest_actions(pair.start, pair.end, max_states)
                instance = None if actions is None else Instance(
                    Path(f"{command.path}:{pair.line}"), command.text, actions, tuple(replay(pair.start, actions)))
            else:
                try:  # enumerates the pair's states once: the reachability check and the evidence
                    evidence = cache.evidence(pair.start, pair.end, max_states)
                except StateKeyError:  # more moving blocks than a state's key holds: too large, as above
                    out.skipped.append((command, pair, "too large"))
                    continue
                except StateSpaceError:
                    instance = None
                else:
                    instance = PairInstance(command.path, pair.line, command.text, pair.start, pair.end,
                                            evidence=(evidence,))
            if instance is None:
                if not skip_inconsistent:
                    raise InconsistentDemonstration(
                        f"{where}: the end state cannot be reached from the start state "
                        "under the project's dynamics (pass --skip-inconsistent to skip such pairs)",
                        Path(command.path), pair.line, 0)
                out.skipped.append((command, pair, "unreachable"))
                continue
            if not _admits_task(instance, library):
                if not skip_inconsistent:
                    raise InconsistentDemonstration(
                        f"{where}: no task of the library can be carried out from the start "
                        "state (every grounding is impossible or already true), so the pair is evidence of none "
                        "(pass --skip-inconsistent to skip such pairs)", Path(command.path), pair.line, 0)
                out.skipped.append((command, pair, "no task"))
                continue
            usable.append(instance)
        if layouts == "shared" and usable:
            usable = [PairedCommand(command.path, command.line, command.text,
                                    tuple((i.initial_state, i.final_state) for i in usable),
                                    evidence=tuple(e for i in usable for e in i.evidence))]
        out.instances.extend(usable)
        out.commands.extend([index] * len(usable))
    if cache is not None:
        cache.report()
    return out


def _admits_task(instance, library: TaskLibrary) -> bool:
    """Whether some task can be asked in the instance's start state. Training would otherwise stop at
    the first state that admits none (interpretations' NoTaskError), naming no file or line."""
    evidence = getattr(instance, "evidence", ())
    if evidence:  # end-state evidence already holds the start's candidate goals: no second solve
        return bool(evidence[0].goals)
    return bool(candidate_tasks(instance.initial_state, library))


def _fits(pair, demonstrations: str, max_states: int) -> bool:
    """Whether a pair can be scored: its whole state space within ``max_states`` or, for end-state
    evidence, the relevance abstraction in which only the toys the pair moves move (shared_meaning)."""
    if exact_fits(pair.start, max_states):
        return True
    moved = relevant_toys(pair.start, (), [(pair.start, pair.end)])
    return demonstrations == "end-state" and abstraction_bound(pair.start, moved) <= max_states
