"""Every notebook executes without error in quick mode (GROUNDLANG_QUICK=1) and shows at least one figure;
the notebooks build_notebooks.py generates are committed exactly as it writes them."""

from __future__ import annotations

import difflib
import importlib.util
import json
import sys
from functools import lru_cache
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


@lru_cache(maxsize=None)
def _builder():
    """notebooks/build_notebooks.py as a module, loaded from its path (nothing is written)."""
    spec = importlib.util.spec_from_file_location("_groundlang_build_notebooks", NOTEBOOKS / "build_notebooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_builder_builds_notebooks_01_02_04():
    assert {name[:2] for name in _builder().NOTEBOOKS} == {"01", "02", "04"}


@pytest.mark.parametrize("name", sorted(_builder().NOTEBOOKS))
def test_committed_notebook_is_the_builders_output(name):
    """A generated notebook edited by hand fails here: edit the cells in build_notebooks.py and rebuild."""
    pytest.importorskip("nbformat")
    expected = _builder().notebook_text(name)
    path = NOTEBOOKS / f"{name}.ipynb"
    committed = path.read_text(encoding="utf-8")
    if committed != expected:
        diff = "".join(list(difflib.unified_diff(
            committed.splitlines(keepends=True), expected.splitlines(keepends=True),
            f"{path.name} (committed)", f"{path.name} (build_notebooks.py)"))[:60])
        pytest.fail(f"{path.name} differs from what notebooks/build_notebooks.py writes; put the change in "
                    f"the builder's cells and run `python notebooks/build_notebooks.py`:\n{diff}")


def test_builder_keeps_ids_of_numbered_cells_around_fixed_ones():
    pytest.importorskip("nbformat")
    build = _builder().build
    nb = build("07_x", [("md", "a"), ("code", "b", "inserted"), ("md", "c")])
    assert [c.id for c in nb.cells] == ["07-00", "inserted", "07-01"]
    with pytest.raises(ValueError, match="duplicate"):
        build("07_x", [("md", "a"), ("md", "b", "07-00")])


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
