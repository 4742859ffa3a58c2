"""Training instances from a corpus of (start, end) pairs (Williams et al. 2018, ``.bdm``).

Such a corpus shows no trajectory, so a pair becomes evidence in one of two ways (``demonstrations``):

- ``"end-state"`` (the default): a :class:`PairInstance`, whose behaviour term is the likelihood of its
  end state under each grounded task (``inference.end_states``): no planning while training.
- ``"shortest-plan"``: a corpus :class:`~groundlang.corpus.Instance` whose demonstration is a shortest
  plan from the start to exactly the end state (``pair_tasks.shortest_actions``; of several shortest
  plans the first in a fixed order), scored by MLIRL's behaviour likelihood like a recorded one.

Which is better was measured on a development split (ABLATIONS.md). A pair whose state space is too
large to enumerate is skipped and counted; one whose end state cannot be reached from its start is an
inconsistent demonstration (an error naming file and line, or skipped with ``skip_inconsistent``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from groundlang.bdm import DEFAULT_PALETTE, Command, bdm_files, read_bdm
from groundlang.corpus import CorpusError, InconsistentDemonstration, Instance
from groundlang.model.statespace import StateSpaceError, check_state_count, enumerate_states
from groundlang.model.world import State, replay
from groundlang.pair_tasks import REACHABILITY_MAX_STATES, shortest_actions

__all__ = ["PairInstance", "PairCorpus", "read_pair_corpus", "training_instances", "DEMONSTRATIONS"]

DEMONSTRATIONS = ("end-state", "shortest-plan")


@dataclass(frozen=True)
class PairInstance:
    """One (start, end) pair of a command, as a training instance without a trajectory."""

    path: Path
    line: int  # of the start state
    command: str
    initial_state: State
    final_state: State
    actions: None = None  # no demonstration: the learner scores the end state (inference.end_states)

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


def read_pair_corpus(path: str | Path, palette=DEFAULT_PALETTE) -> PairCorpus:
    """Every command of a ``.bdm`` file, or of the ``.bdm`` files of a folder (sorted by name)."""
    paths = bdm_files(path)
    if not paths:
        raise CorpusError(f"{path}: no .bdm file there (a .bdm file or a folder of them)")
    return PairCorpus(paths, [c for p in paths for c in read_bdm(p, palette)])


@dataclass
class TrainingPairs:
    """What :func:`training_instances` made of a corpus, and what it left out (command, pair, why)."""

    instances: list = field(default_factory=list)
    commands: list[int] = field(default_factory=list)  # the command index of each instance
    skipped: list[tuple[Command, object, str]] = field(default_factory=list)

    def skipped_by(self, reason: str) -> int:
        return sum(1 for _, _, why in self.skipped if why == reason)


def training_instances(commands: list[Command], demonstrations: str = "end-state", skip_inconsistent: bool = False,
                       max_states: int = REACHABILITY_MAX_STATES) -> TrainingPairs:
    """The instances of ``commands``' pairs (see the module docstring); pairs too large to enumerate are
    skipped as ``"too large"``, unreachable ones raise InconsistentDemonstration unless
    ``skip_inconsistent`` (then skipped as ``"unreachable"``)."""
    if demonstrations not in DEMONSTRATIONS:
        raise ValueError(f"demonstrations={demonstrations!r}: expected one of {', '.join(DEMONSTRATIONS)}")
    out = TrainingPairs()
    for index, command in enumerate(commands):
        for pair in command.pairs:
            try:
                check_state_count(pair.start, max_states)
            except StateSpaceError:
                out.skipped.append((command, pair, "too large"))
                continue
            if demonstrations == "shortest-plan":
                actions = shortest_actions(pair.start, pair.end, max_states)
                instance = None if actions is None else Instance(
                    Path(f"{command.path}:{pair.line}"), command.text, actions, tuple(replay(pair.start, actions)))
            else:
                instance = PairInstance(command.path, pair.line, command.text, pair.start, pair.end)
                if not _reaches(pair.start, pair.end, max_states):
                    instance = None
            if instance is None:
                if not skip_inconsistent:
                    raise InconsistentDemonstration(
                        f"{command.path}, line {pair.line}: the end state cannot be reached from the start state "
                        "under the project's dynamics (pass --skip-inconsistent to skip such pairs)",
                        Path(command.path), pair.line, 0)
                out.skipped.append((command, pair, "unreachable"))
                continue
            out.instances.append(instance)
            out.commands.append(index)
    return out


def _reaches(start: State, end: State, max_states: int) -> bool:
    try:
        enumerate_states(start, max_states=max_states).index_of(end)
    except (StateSpaceError, KeyError, ValueError):
        return False
    return True
