"""``groundlang domain [--palette NAME|FILE] [--library LP ...] [--json]``: the schema a domain's ASP declares."""

from __future__ import annotations

import argparse

from groundlang.commands import LIBRARY_NAMES, PALETTE_HELP, json_text, library_path, positive_seconds


def register(subparsers) -> None:
    p = subparsers.add_parser("domain", help="print the domain's schema: classes, palette, PFs by class, tasks")
    p.add_argument("--palette", default="sokoban", help=PALETTE_HELP + " (default: sokoban)")
    p.add_argument("--library", metavar="LP", action="append", type=library_path,
                   help="task library .lp file (repeatable; default: groundlang's tasks.lp)" + LIBRARY_NAMES)
    p.add_argument("--allow-scripts", action="store_true",
                   help="let library files run #script blocks (only for files you trust)")
    p.add_argument("--time-limit", type=positive_seconds, default=10.0, metavar="SECONDS",
                   help="stop grounding/solving the library after this long (default 10)")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from groundlang.logic.tasks import TaskLibrary
    from groundlang.commands import words_beside_checked
    from groundlang.model.palette import check_attribute_clash, get_palette
    from groundlang.model.pf_tables import check_declarations
    from groundlang.training_vocabulary import palette_schema

    library = words_beside_checked(TaskLibrary.load(args.library, allow_scripts=args.allow_scripts,
                                                    time_limit=args.time_limit))
    palette = get_palette(args.palette)  # checked as every other command checks it
    check_attribute_clash(palette, library.grounding_program)
    check_declarations(library, palette)  # what no layout could tabulate, refused here as train refuses it
    schema = palette_schema(library, palette)
    if args.json:
        print(json_text({
            "classes": list(schema.classes),
            "movable": sorted(schema.movable),
            "palette": {"name": schema.palette, "values": {a: list(v) for a, v in schema.values.items()}},
            "pfs": [{"name": d.name, "class": d.pf_class, "part": schema.roles.part(d.pf_class),
                     "signature": list(d.signature), "term": d.term} for d in schema.pfs.values()],
            "tasks": [str(t) for t in schema.tasks],
            "phrases": library.phrases,
        }, indent=1))
        return 0
    print(schema.describe())
    if library.phrases:  # phrase/2: how the library says its PFs read
        print(f"phrases ({len(library.phrases)}):")
        print("\n".join(f"  {name}: {words!r}" for name, words in sorted(library.phrases.items())))
    return 0
