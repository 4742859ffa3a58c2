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


def test_the_log_level_is_groundlangs_own():
    """A run shows groundlang's information, not other libraries' (torch logs its FakeTensor cache
    statistics at INFO when the process exits)."""
    import subprocess
    import sys

    script = ("import logging; from groundlang.cli import main; main(['domain', '--palette', 'sokoban']); "
              "logging.getLogger('torch.other').info('LEAKED'); logging.getLogger('groundlang.x').info('OURS')")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "OURS" in done.stderr and "LEAKED" not in done.stderr
