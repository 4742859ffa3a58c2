"""A layout beyond what a model reads or plans in (more objects than the mention model sums over, more moving
objects than a state's key holds) is refused in one line naming its file, wherever it is read."""

from __future__ import annotations

import re
from pathlib import Path

from groundlang.cli import main
from groundlang.corpus import example_corpus_path

EXAMPLES = example_corpus_path()
# Seventeen more blocks in a red room, clear of its doors and of the path walked: novel_a's, the example corpus's.
IN_NOVEL_A = [(x, y) for y in (1, 2, 3) for x in (1, 2, 3, 6, 7, 8)][:17]
IN_EXAMPLES = [(x, y) for y in (5, 7, 8) for x in range(6, 12)][:17]


def _crowded(line: str, cells) -> str:
    return line.strip() + "".join(f" block,1,1,{x},{y}" for x, y in cells)


def test_follow_names_the_state_file_of_too_many_objects_to_read(tmp_path, capsys, learner):
    state = tmp_path / "crowded.state"
    state.write_text(_crowded((EXAMPLES / "novel_a.state").read_text(), IN_NOVEL_A) + "\n", encoding="utf-8")
    model = learner.save(tmp_path / "model")
    assert main(["--quiet", "follow", "--model", str(model), "--env", str(state), "--palette", "sokoban",
                 "go to the red room"]) == 2
    err = capsys.readouterr().err
    assert re.match(rf"groundlang follow: error: {re.escape(str(state))}: \d+ objects a command could name in one "
                    "layout", err)
    assert err.count("\n") == 1


def _corpus_with_a_crowded_layout(tmp_path) -> tuple[Path, Path]:
    """A corpus folder of one example file whose states carry 17 more blocks, and that file."""
    source = EXAMPLES / "agent2blue_0.txt"
    lines = source.read_text(encoding="utf-8").splitlines()
    folder = tmp_path / "corpus"
    folder.mkdir()
    (folder / source.name).write_text("\n".join(lines[:2] + [_crowded(line, IN_EXAMPLES) for line in lines[2:] if line.strip()])
                                      + "\n", encoding="utf-8")
    (folder / "agent2red_0.txt").write_text((EXAMPLES / "agent2red_0.txt").read_text(encoding="utf-8"), encoding="utf-8")
    return folder, folder / source.name


def test_train_names_the_demonstration_file_whose_layout_cannot_be_keyed(tmp_path, capsys):
    """It said "19 moving objects in a layout of 59 cells: ..." and no file."""
    folder, source = _corpus_with_a_crowded_layout(tmp_path)
    assert main(["--quiet", "train", str(folder), "--palette", "sokoban", "-o", str(tmp_path / "m")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"groundlang train: error: {source}: ") and "cannot be keyed in 64 bits" in err
    assert not Path(tmp_path / "m").exists()


def test_check_warns_of_the_layouts_train_may_not_key(tmp_path, capsys):
    """check said nothing of such a layout; train then stopped at it. A warning, not a failure: where the toys a
    likelihood must move fit a key, train reads the layout in a relevance abstraction."""
    folder, source = _corpus_with_a_crowded_layout(tmp_path)
    assert main(["--quiet", "check", str(folder), "--palette", "sokoban"]) == 0
    out, err = capsys.readouterr()
    assert "layouts whose states cannot all be keyed: 1\n" in out
    listed = [line.strip() for line in out.splitlines() if "cannot be keyed in 64 bits" in line]
    assert len(listed) == 1 and listed[0].startswith(f"{source}: 19 moving objects")
    assert err.strip() == ("groundlang check: warning: 1 layouts whose states cannot all be keyed in 64 bits; train "
                           "refuses a demonstration there where its likelihood needs every object to move")


def test_check_of_layouts_that_can_be_keyed_says_nothing_of_keys(capsys):
    assert main(["--quiet", "check", str(EXAMPLES), "--palette", "sokoban"]) == 0
    assert "keyed" not in capsys.readouterr().out
