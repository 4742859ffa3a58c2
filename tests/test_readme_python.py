"""The README's Python examples run as written (each ```python block, in a folder of its own where the
project's ``tests/`` folder is at hand for the paths they name)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
BLOCKS = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(encoding="utf-8"), re.DOTALL)


def test_the_readme_has_python_examples():
    assert len(BLOCKS) >= 2


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_a_readme_python_example_runs(index, tmp_path):
    (tmp_path / "tests").symlink_to(ROOT / "tests")
    done = subprocess.run([sys.executable, "-c", BLOCKS[index]], cwd=tmp_path, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    # what the comments say it prints, where they give a value
    for line in BLOCKS[index].splitlines():
        said = re.search(r"print\((.*)\)\s+# (.+)$", line)
        if said and "..." not in said.group(2) and ":" not in said.group(2):
            assert said.group(2).strip() in done.stdout, (line, done.stdout)
