"""Execute every notebook of this folder with nbclient, in quick mode (GROUNDLANG_QUICK=1), failing on error.

    python notebooks/run_notebooks.py [NAME ...] [--full] [--timeout SECONDS]

The .ipynb files are executed; they are written from the percent-format .py
beside them (``make notebooks``), and tests/test_notebooks.py checks the two agree.
Each notebook runs in a fresh kernel in a temporary working directory (files
it writes do not land in the repository) and must show at least one figure.
The notebooks on disk are not modified. Exit code 0 when all pass, 1 otherwise.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


class NotebookFailure(RuntimeError):
    """A notebook raised, timed out, or showed no figure."""


def notebooks(names=None) -> list[Path]:
    """The numbered notebooks of this folder (``NN_*.ipynb``), sorted; ``names`` filters by stem or prefix."""
    paths = sorted(p for p in HERE.glob("[0-9][0-9]_*.ipynb"))
    if names:
        paths = [p for p in paths if any(p.stem == n or p.stem.startswith(n) for n in names)]
    return paths


def figure_count(nb) -> int:
    """Image outputs (PNG or SVG) of an executed notebook."""
    return sum(
        1
        for cell in nb.cells if cell.cell_type == "code"
        for out in cell.get("outputs", [])
        if any(k in out.get("data", {}) for k in ("image/png", "image/svg+xml"))
    )


def run_notebook(path: Path, quick: bool = True, timeout: int = 600):
    """Execute one notebook; returns the executed notebook. Raises NotebookFailure."""
    import nbformat
    from nbclient import NotebookClient
    from nbclient.exceptions import CellExecutionError, CellTimeoutError

    nb = nbformat.read(path, as_version=4)
    env_before = os.environ.get("GROUNDLANG_QUICK")
    # The kernel inherits the environment of the process that starts it.
    os.environ["GROUNDLANG_QUICK"] = "1" if quick else "0"
    os.environ.setdefault("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    try:
        with tempfile.TemporaryDirectory(prefix=f"{path.stem}-") as workdir:
            client = NotebookClient(nb, timeout=timeout, kernel_name="python3",
                                    resources={"metadata": {"path": workdir}})
            try:
                client.execute()
            except (CellExecutionError, CellTimeoutError) as exc:
                raise NotebookFailure(f"{path.name}: {exc}") from None
    finally:
        if env_before is None:
            os.environ.pop("GROUNDLANG_QUICK", None)
        else:
            os.environ["GROUNDLANG_QUICK"] = env_before
    if figure_count(nb) == 0:
        raise NotebookFailure(f"{path.name}: ran, but showed no figure; every notebook must show at least one")
    return nb


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", help="notebook stems or prefixes (default: all)")
    parser.add_argument("--full", action="store_true", help="run without quick mode")
    parser.add_argument("--timeout", type=int, default=600, help="seconds per cell")
    args = parser.parse_args(argv)
    paths = notebooks(args.names)
    if not paths:
        print(f"no notebooks matching {args.names} in {HERE}", file=sys.stderr)
        return 1
    failed = 0
    for path in paths:
        start = time.perf_counter()
        try:
            nb = run_notebook(path, quick=not args.full, timeout=args.timeout)
        except NotebookFailure as exc:
            failed += 1
            print(f"FAIL {path.name} ({time.perf_counter() - start:.1f} s)\n{exc}", file=sys.stderr)
            continue
        print(f"ok   {path.name} ({time.perf_counter() - start:.1f} s, {figure_count(nb)} figures)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
