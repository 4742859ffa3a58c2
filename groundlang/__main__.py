"""``python -m groundlang``: the ``groundlang`` command, for an environment whose scripts are not on the path."""

from groundlang.cli import run

if __name__ == "__main__":
    run()
