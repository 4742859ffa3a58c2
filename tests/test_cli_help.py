"""Every option of every command says what it does (issue 23: output a person can read)."""

from __future__ import annotations

import argparse

from groundlang.cli import build_parser


def test_every_option_of_every_command_has_help():
    missing = []
    for action in build_parser()._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                missing += [f"{name} {' '.join(a.option_strings) or a.dest}" for a in sub._actions if a.help is None]
    assert missing == []
