"""``groundlang irl FILE --palette NAME [--library LP ...] [--json]``: MLIRL on one demonstration over every
grounded position PF.

The features are all grounded position PFs of the file's initial state
(agentInRoom, toyInRoom, agentInDoor, toyInDoor, agentTouchingToy, and those of ``--library`` files); the
reward they define is paid on terminating (see
:mod:`groundlang.inference.mlirl`), so the largest weight names the
proposition the demonstrator most wanted to hold when it stopped. Prints the
weights largest first, the log-likelihood, the number of states and the
seconds taken. The table has a heading and says each proposition in words
beside its atom ("the star in the red room" next to ``toyInRoom(block0,
room0)``), the words read from the file's initial state as ``follow`` reads
goals (:mod:`groundlang.wording`). ``--json`` prints one object
``{"weights": {"toyInRoom(block0, room2)": 1.9, ...}, "words": {"toyInRoom(block0,
room2)": "the yellow star in the red room", ...}, "log_likelihood": ...,
"states": ..., "seconds": ...}`` (keys in the same order, atoms written as
groundlang names them: compare with labels after ``parse_atom``).
"""

from __future__ import annotations

import argparse
import time

from groundlang.commands import LIBRARY_NAMES, PALETTE_HELP, input_path, json_text, library_given, library_path


def register(subparsers) -> None:
    p = subparsers.add_parser("irl", help="fit reward weights over position PFs to one file's demonstration (MLIRL)")
    p.add_argument("file", type=input_path, metavar="FILE", help="one corpus file (command, actions, states)")
    p.add_argument("--palette", required=True, help=PALETTE_HELP)
    p.add_argument("--library", metavar="LP", action="append", type=library_path,
                   help="task library .lp file (repeatable): its position PFs are features too (default: "
                        "groundlang's)" + LIBRARY_NAMES)
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    p.set_defaults(func=run)


def fit_file(path, palette, library=None) -> dict:
    """MLIRL on one file over the position PFs of ``library`` (a TaskLibrary; None: the package's); returns the
    --json object (weights ordered largest first)."""
    from groundlang.corpus import read_instance
    # The settings task discovery uses (one demonstration: non-negative weights with a sparsity prior
    # let the whole path pick the proposition; a fixed temperature keeps it from driving T to 0).
    from groundlang.inference.discovery import DISCOVERY_IRL
    from groundlang.inference.mlirl import mlirl
    from groundlang.logic.tasks import TaskLibrary
    from groundlang.model.features import feature_matrix, position_atoms
    from groundlang.model.pf_tables import library_pf_tables
    from groundlang.model.relevance import state_space_for
    from groundlang.model.statespace import trajectory_indices
    from groundlang.wording import goal_phrase

    start = time.perf_counter()
    library = library or TaskLibrary.load()  # its PFs are the features; the words of objects are read from it
    instance = read_instance(path, palette)
    space = state_space_for(instance.initial_state, demonstrations=[instance.states])
    tables = library_pf_tables(space.layout, library)
    atoms = position_atoms(space.layout, tables)
    features = feature_matrix(space, atoms, tables)
    states = trajectory_indices(space, list(instance.states))
    fit = mlirl(space.next_state, features, [(states, [int(a) for a in instance.actions])], **DISCOVERY_IRL)
    ranked = sorted(zip(atoms, fit.weights.tolist()), key=lambda aw: -aw[1])
    return {
        "weights": {str(a): round(w, 6) for a, w in ranked},
        "words": {str(a): goal_phrase((a,), instance.initial_state, library) for a, _ in ranked},
        "ranking": [str(a) for a in _break_near_ties(space, ranked, states, instance.actions, tables)],
        "log_likelihood": fit.log_likelihood,
        "temperature": fit.temperature,
        "states": space.num_states,
        "seconds": time.perf_counter() - start,
    }


# The table's column headings (the weight is the reward paid for the atom holding on termination).
WEIGHT_HEADING, WORDS_HEADING, ATOM_HEADING = "weight", "proposition", "atom"

# Weights within this fraction of the largest count as tied.
NEAR_TIE = 0.05


def _break_near_ties(space, ranked, states, actions, tables) -> list:
    """Atoms by weight, with near-ties at the top ordered by the behaviour likelihood of each as a goal.

    Propositions that first become true together at the end of one
    demonstration (a toy pushed onto a door cell inside the goal room) get
    nearly equal weights; the likelihood of "make this atom true, then stop"
    over the whole path still tells them apart, as the joint model's
    behaviour term does.
    """
    from groundlang.inference.planning import task_log_likelihood
    from groundlang.model.features import goal_mask

    top = ranked[0][1]
    tied = [a for a, w in ranked if top > 0 and w >= (1 - NEAR_TIE) * top]
    if len(tied) < 2:
        return [a for a, _ in ranked]
    moves = [int(a) for a in actions]
    score = {a: task_log_likelihood(space, goal_mask(space, (a,), tables), states, moves) for a in tied}
    return sorted(tied, key=lambda a: -score[a]) + [a for a, _ in ranked if a not in score]


def run(args: argparse.Namespace) -> int:
    from groundlang.wording import DASH

    result = fit_file(args.file, args.palette, library_given(args))
    if args.json:
        print(json_text(result))
        return 0
    words = result["words"]
    best = result["ranking"][0]
    print(f"most likely goal: {words[best]} {DASH} {best}")
    print()
    # Columns a person scans: the weight, the proposition in words, then its atom for the ids.
    said = max(len(WORDS_HEADING), *(len(w) for w in words.values()))
    print(f"{WEIGHT_HEADING:>8}  {WORDS_HEADING:<{said}}  {ATOM_HEADING}")
    for atom, weight in result["weights"].items():
        print(f"{weight:8.3f}  {words[atom]:<{said}}  {atom}")
    print()
    print(f"log-likelihood: {result['log_likelihood']:.4f}")
    print(f"temperature: {result['temperature']:.4f}")
    print(f"states: {result['states']}")
    print(f"seconds: {result['seconds']:.2f}")
    return 0
