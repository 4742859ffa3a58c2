"""Every notebook executes without error in quick mode (GROUNDLANG_QUICK=1) and shows at least one figure."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

NOTEBOOKS = Path(__file__).resolve().parent.parent / "notebooks"

_missing = [m for m in ("nbclient", "nbformat", "ipykernel", "matplotlib_inline") if importlib.util.find_spec(m) is None]
needs_jupyter = pytest.mark.skipif(
    bool(_missing), reason=f"notebook tests need {', '.join(_missing)} (pip install groundlang[notebooks])"
)


def _runner():
    sys.path.insert(0, str(NOTEBOOKS))
    try:
        import run_notebooks
    finally:
        sys.path.remove(str(NOTEBOOKS))
    return run_notebooks


def _paths() -> list[Path]:
    return sorted(NOTEBOOKS.glob("[0-9][0-9]_*.ipynb"))


def test_notebooks_are_committed_without_outputs():
    paths = _paths()
    assert {p.stem[:2] for p in paths} >= {"01", "02", "04"}
    for path in paths:
        nb = json.loads(path.read_text(encoding="utf-8"))
        for cell in nb["cells"]:
            if cell["cell_type"] == "code":
                assert cell["outputs"] == [] and cell["execution_count"] is None, f"{path.name}: outputs not stripped"


@needs_jupyter
@pytest.mark.slow
@pytest.mark.parametrize("path", _paths(), ids=lambda p: p.stem)
def test_notebook_runs_in_quick_mode(path):
    nb = _runner().run_notebook(path, quick=True, timeout=300)
    assert _runner().figure_count(nb) >= 1
    errors = [o for c in nb.cells for o in c.get("outputs", []) if o.get("output_type") == "error"]
    assert errors == []
