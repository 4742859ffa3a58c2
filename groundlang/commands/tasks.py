"""``groundlang tasks FILE --palette NAME [--library LP] [--json]``: lifted tasks, groundings, constraints,
the unary PFs that describe each object (colours, shapes, spatial PFs where the agent stands), the
relations by which one object may describe another ("the room with the chair"), and every PF of two
or more objects that holds."""

from __future__ import annotations

import argparse
from importlib.resources import files as resources

from groundlang.bdm import DEFAULT_PALETTE
from groundlang.commands import (input_path, LIBRARY_NAMES, PALETTE_HELP, check_state_file, is_burlap_state_file, json_text,
                                 library_path, positive_seconds, renumbering_note, words_beside_checked)
from groundlang.corpus import file_names, read_initial_state


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "tasks", help="list lifted tasks and their groundings and binding constraints in a file's initial state"
    )
    p.add_argument("file", type=input_path, metavar="FILE", help="a corpus file (*.txt) or a one-line .state file (either "
                   "format: a state in the corpus's format, or a BURLAP state line as Williams et al. write them)")
    p.add_argument("--palette", help=PALETTE_HELP + "; required but for a BURLAP state line (default williams2018)")
    p.add_argument("--library", metavar="LP", action="append", type=library_path,
                   help="task library .lp file (repeatable; default: groundlang's tasks.lp, or for a BURLAP "
                   "state line the williams2018 domain)" + LIBRARY_NAMES)
    p.add_argument("--allow-scripts", action="store_true",
                   help="let library files run #script blocks (only for files you trust)")
    p.add_argument("--time-limit", type=positive_seconds, default=10.0, metavar="SECONDS",
                   help="stop grounding/solving the library after this long (default 10)")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from groundlang.logic.groundings import MAX_ENUMERATED_ATOMS
    from groundlang.logic.program import AspTimeout
    from groundlang.logic.tasks import TaskLibrary
    from groundlang.model.interpretations import object_names
    from groundlang.model.pf_tables import library_pf_tables, tabulation_refusal
    from groundlang.logic.classes import domain_classes
    from groundlang.model.tasks import candidate_tasks, check_library_at, object_descriptions, object_relations
    from groundlang.model.world import object_class

    check_state_file(args.file, "tasks")
    burlap = is_burlap_state_file(args.file)
    if args.palette is None and not burlap:
        raise ValueError(f"{args.file}: --palette is required for a state in the corpus's format "
                         "(e.g. --palette sokoban)")
    # A grounding's binding constraints are every conjunction of its objects' property PFs: listed while a
    # language model could enumerate them, beyond that the largest alone (the rest are its subsets).
    listed = 2 ** MAX_ENUMERATED_ATOMS
    state = read_initial_state(args.file, args.palette or DEFAULT_PALETTE)
    renumbered = file_names(args.file)  # the layout's name -> the file's, where they differ
    files = args.library or ([str(resources("groundlang.logic") / "domains" / "williams2018.lp")] if burlap else None)
    library = words_beside_checked(TaskLibrary.load(files, allow_scripts=args.allow_scripts, time_limit=args.time_limit))
    try:
        candidates = candidate_tasks(state, library)
    except AspTimeout as exc:  # a layout too large to ground in time: the file it came from is the one to look at
        raise AspTimeout(f"{args.file}: {exc}") from None
    by_name = object_descriptions(state, library)
    # The layout's order (rooms, doors, toys), as the corpus writes a state, not the names' alphabetical order.
    described = {obj: by_name[obj] for obj in object_names(state) if obj in by_name}
    # What words may say of an object through another (related/4 of groundings.lp; the language model's
    # relational descriptions), written as the PF's atom: "block0: toyInRoom(block0, room2)".
    # Only objects of the classes commands name as things (toys) describe another, as in the model.
    related = object_relations(state, library)
    describing = domain_classes().mentioned
    by_relation = {obj: atoms for obj in object_names(state) if obj in related
                   and (atoms := [f"{pf}({', '.join((obj, other) if index == 0 else (other, obj))})"
                                  for pf, index, other in related[obj] if object_class(other) in describing])}
    # Relations (toyInRoom, a user's agentNextToToy, ...) as the PF tables planning uses say they hold.
    # A layout too large to tabulate still lists its tasks; a library's mistake found in tabulating it is
    # refused (it had been listed as "not listed", exit 0, as if the layout were too large).
    untabulated, holding = tabulation_refusal(state.layout), []
    if untabulated is None:
        check_library_at(state, library, args.file)
        holding = [a for a in library_pf_tables(state.layout, library).holding(state.positions) if len(a.args) > 1]
    relations = {obj: atoms for obj in object_names(state) if (atoms := [a for a in holding if obj in a.args])}
    if args.json:
        out = {
            "lifted_tasks": library.names,
            "groundings": [
                {
                    "task": g.task,
                    "goal": g.goal_text,
                    # every conjunction while they are few; beyond, the largest (the rest are its subsets)
                    "constraints": [[str(a) for a in c.atoms]
                                    for c in (constraints if constraints.count <= listed else constraints[:1])],
                    "constraint_count": constraints.count,
                }
                for g, constraints in candidates
            ],
            "descriptions": {obj: {cls: list(pfs) for cls, pfs in by_class.items()}
                             for obj, by_class in described.items()},
            "described_by_relation": by_relation,
            "relations": {obj: [str(a) for a in atoms] for obj, atoms in relations.items()},
            "file_names": renumbered,
        }
        print(json_text(out, indent=1))
        return 0
    print(f"lifted tasks ({len(library.tasks)}):")
    for t in library.tasks:
        print(f"  {t}")
    if note := renumbering_note(renumbered):
        print(note)
    print(f"groundings in the initial state of {args.file} ({len(candidates)}):")
    for g, constraints in candidates:
        print(f"  {g.task}: {g.goal_text}")
        for c in (constraints if constraints.count <= listed else constraints[:1]):
            print(f"      {c}")
        if constraints.count > listed:
            print(f"      ... {constraints.count:,} in all: every conjunction of the first's atoms")
    print(f"unary PFs of each object in the initial state, by class ({len(described)} object{'s' * (len(described) != 1)}):")
    for obj, by_class in described.items():
        print(f"  {obj}: " + "; ".join(f"{cls} {', '.join(pfs)}" for cls, pfs in by_class.items()))
    print(f"relations that may describe an object by another, in the initial state ({len(by_relation)} object{'s' * (len(by_relation) != 1)}):")
    for obj, atoms in by_relation.items():
        print(f"  {obj}: " + ", ".join(atoms))
    if untabulated:
        print(f"PFs of two or more objects: not listed ({untabulated})")
        return 0
    print(f"PFs of two or more objects in the initial state, by object ({len(holding)} "
          "facts):")
    for obj, atoms in relations.items():
        print(f"  {obj}: " + ", ".join(map(str, atoms)))
    return 0
