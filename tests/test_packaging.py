"""What an install carries: every folder of the source tree that holds Python or data files is a package
``pyproject.toml`` lists (an editable install finds a missing one anyway; a wheel leaves it out)."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).parent.parent


def _setuptools() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]


def _source_packages() -> set[str]:
    """Each package name and the folders under its directory that hold files an install needs."""
    out = set()
    for name, folder in _setuptools()["package-dir"].items():
        root = ROOT / folder
        for path in [root, *(p for p in root.rglob("*") if p.is_dir())]:
            if path.name == "__pycache__" or any(part.startswith(".") for part in path.relative_to(ROOT).parts):
                continue
            if any(f.suffix in (".py", ".lp", ".words", ".lark", ".state", ".txt", ".csv") for f in path.iterdir()):
                out.add(".".join([name, *path.relative_to(root).parts]))
    return out


def test_every_source_folder_is_a_listed_package():
    listed = set(_setuptools()["packages"])
    missing = _source_packages() - listed
    assert not missing, f"pyproject.toml's packages leave out {sorted(missing)}"
    assert "groundlang.commands" in listed  # the CLI's subcommands: a wheel without them cannot start


def test_every_listed_package_is_a_folder():
    dirs = _setuptools()["package-dir"]
    for package in _setuptools()["packages"]:
        head = next(name for name in sorted(dirs, key=len, reverse=True) if package == name or package.startswith(name + "."))
        folder = ROOT / dirs[head] / Path(*package.removeprefix(head).strip(".").split(".") if package != head else ())
        assert folder.is_dir(), package
