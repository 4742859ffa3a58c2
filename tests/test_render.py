"""Pictures (groundlang.render): ASCII drawings and matplotlib images."""

from __future__ import annotations

import io
import re
import subprocess
from pathlib import Path
import sys

import numpy as np
import pytest

from groundlang.corpus import example_corpus_path, parse_state, read_instance, read_state_file
from groundlang.model.world import get_palette
from groundlang.render import ascii_state, glyph, draw_state, save_picture, trajectory_positions

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
EXAMPLES = example_corpus_path()


def test_ascii_small_state(fixtures):
    text = ascii_state(read_state_file(fixtures / "small.state", "sokoban"))
    assert text == (
        "#########\n"
        "#ggg#rrr#\n"
        "#gAg+rrr#\n"
        "#ggg#rrr#\n"
        "#########\n"
        "legend: # wall, + door, A agent0\n"
        "  g room0 (green)\n"
        "  r room1 (red)"
    )


def test_ascii_two_toys_north_up(fixtures):
    rows = ascii_state(read_state_file(fixtures / "two_toys.state", "sokoban2")).splitlines()
    assert rows[1] == "#bbb#yBy#"  # y = 3: the basket at (6, 3)
    assert rows[2] == "#bbb+CAy#"  # y = 2: chair (5, 2), agent (6, 2)
    assert "  C block0 (red chair)" in rows
    assert "  B block1 (green basket)" in rows


def test_ascii_colliding_shape_initials_use_digits():
    s = parse_state("room,5,0,5,5,0 block,12,0,1,1 block,10,3,3,3 agent,2,2", "sokoban")  # star, smiley
    rows = ascii_state(s).splitlines()
    assert rows[2] == "#gg1g#"
    assert rows[3] == "#gAgg#"
    assert rows[4] == "#0ggg#"
    assert "  0 block0 (yellow star)" in rows and "  1 block1 (red smiley)" in rows


def test_ascii_legend_says_which_object_hides_a_door():
    """The star and the agent drawn on door cells had hidden their "+", and looked as if in a wall."""
    s = parse_state("room,1,0,4,4,0 room,5,4,4,8,0 door,4,2,4,2 block,12,0,4,2 agent,2,2", "sokoban")
    rows = ascii_state(s).splitlines()
    assert rows[2] == "#bAbSggg#" and "  S block0 (yellow star, on a door)" in rows
    assert rows[rows.index("  S block0 (yellow star, on a door)") - 1] == "legend: # wall, + door, A agent0"
    moved = ascii_state(s.with_positions(np.array([[4, 2], [2, 2]]))).splitlines()
    assert moved[2] == "#bSbAggg#"
    assert "legend: # wall, + door, A agent0 (on a door)" in moved and "  S block0 (yellow star)" in moved


def test_every_palette_shape_has_a_glyph():
    from groundlang.logic.palette_files import palette_names

    shapes = [s for name in palette_names() for s in get_palette(name).shapes]
    glyphs = {s: glyph(s, get_palette(name)) for name in palette_names() for s in get_palette(name).shapes}
    assert set(shapes) == set(glyphs) and all(len(g) == 1 for g in glyphs.values())
    assert len(set(glyphs.values())) == len(set(shapes))  # every shape drawn differently
    assert glyph("mug", get_palette("sokoban")) == "M"  # a shape the palette draws no glyph for


def test_trajectory_positions(fixtures):
    inst = read_instance(fixtures / "sokoban" / "star2green_0.txt", "sokoban")
    pos = trajectory_positions(inst.states)
    assert pos.shape == (3, 2, 2)
    assert pos[:, 1].tolist() == [[5, 2], [4, 2], [3, 2]]
    assert trajectory_positions(pos.tolist()).tolist() == pos.tolist()
    assert trajectory_positions(None).shape == (0, 1, 2)
    with pytest.raises(ValueError, match="shape"):
        trajectory_positions([[1, 2]])


def test_draw_state_with_trajectory(fixtures):
    inst = read_instance(fixtures / "sokoban" / "star2green_0.txt", "sokoban")
    ax = draw_state(inst.initial_state, trajectory=inst.states, title="push")
    lines = ax.get_lines()
    agent_path = lines[0]
    assert agent_path.get_xdata().tolist() == [6, 5, 4]
    assert np.asarray(lines[1].get_xdata()).tolist() == [5, 4, 3]  # the star's path
    texts = [t.get_text() for t in ax.texts]
    assert glyph("star", get_palette("sokoban")) in texts and "A" in texts
    assert ax.get_title() == "push"
    image = ax.get_images()[0].get_array()
    assert image.shape == (5, 9, 3)
    assert np.allclose(image[0, 0], (0.18, 0.18, 0.2))  # wall corner
    assert image[2, 2, 1] > image[2, 2, 0]  # green room floor is greenish


def test_save_picture_png_atomic(fixtures, tmp_path):
    inst = read_instance(fixtures / "sokoban2" / "chair2blue_0.txt", "sokoban2")
    out = save_picture(tmp_path / "chair.png", inst.initial_state, trajectory=inst.states, title=inst.command)
    data = out.read_bytes()
    assert data.startswith(PNG_MAGIC)
    assert len(data) > 5000
    assert [p.name for p in tmp_path.iterdir()] == ["chair.png"]
    svg = save_picture(tmp_path / "s.svg", inst.initial_state)
    assert svg.read_text().lstrip().startswith("<?xml")
    with pytest.raises(ValueError, match="not supported"):
        save_picture(tmp_path / "x.bmp", inst.initial_state)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["chair.png", "s.svg"]



def _read_fifo(path):
    """A FIFO at ``path`` and a thread reading it whole into the returned list."""
    import os
    import threading

    os.mkfifo(path)
    read: list[bytes] = []
    threading.Thread(target=lambda: read.append(path.read_bytes()), daemon=True).start()
    return read


def test_a_picture_is_written_into_a_fifo_not_over_it(fixtures, tmp_path):
    """``show --out FIFO`` replaced the FIFO once the atomic write left it alone, the PNG writer then said
    "File or stream is not seekable" without a path: the picture is drawn in memory, then written."""
    import stat
    import time

    state = read_state_file(fixtures / "small.state", "sokoban")
    read = _read_fifo(tmp_path / "picture.png")
    save_picture(tmp_path / "picture.png", state)
    for _ in range(100):
        if read:
            break
        time.sleep(0.05)
    assert read and read[0].startswith(PNG_MAGIC)
    assert stat.S_ISFIFO((tmp_path / "picture.png").lstat().st_mode)
    assert [p.name for p in tmp_path.iterdir()] == ["picture.png"]

def test_render_import_does_not_load_matplotlib():
    code = "import sys, groundlang.render, groundlang.corpus; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def _pushed_star(fixtures):
    """The first push of star2green_0: the agent ends on the star's start cell, the star one cell west."""
    inst = read_instance(fixtures / "sokoban" / "star2green_0.txt", "sokoban")
    states = inst.states[:2]
    assert (states[-1].positions[0] == inst.initial_state.positions[1]).all()
    return inst.initial_state, states


def test_the_legend_names_every_object_by_id_and_in_words(fixtures):
    start, states = _pushed_star(fixtures)
    ax = draw_state(start, trajectory=states)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == [
        "agent0 at the start", "agent0's path", "agent0 at the end (lower left)",
        "block0 (yellow star) at the start", "block0's path", "block0 at the end (small, upper right)",
        "room0 (green)", "room1 (red)", "door", "wall",
    ]
    # the rooms' ids are written in them too: two rooms of one colour are told apart
    assert {"room0", "room1"} <= {t.get_text() for t in ax.texts}


def test_without_a_trajectory_the_legend_has_no_start_or_end(fixtures):
    state = read_state_file(fixtures / "small.state", "sokoban")
    ax = draw_state(state)
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["agent0", "room0 (green)", "room1 (red)",
                                                                   "door", "wall"]
    assert draw_state(state, legend=False).get_legend() is None


def test_end_markers_are_drawn_over_start_markers_smaller_and_off_centre(fixtures):
    from groundlang.render import END_OFFSET

    start, states = _pushed_star(fixtures)
    ax = draw_state(start, trajectory=states)
    star = glyph("star", get_palette("sokoban"))
    start_x, start_y = start.positions[1]
    end_x, end_y = states[-1].positions[1]
    toy_start = next(t for t in ax.texts if t.get_text() == star and t.get_position() == (start_x, start_y))
    toy_end = next(t for t in ax.texts if t.get_text() == star and t.get_position() != (start_x, start_y))
    assert toy_end.get_position() == (end_x + END_OFFSET, end_y + END_OFFSET)
    assert toy_end.get_fontsize() < toy_start.get_fontsize() and toy_end.get_zorder() > toy_start.get_zorder()
    # the agent ends on the star's start cell: its cross sits off the star's centre and above it
    agent_end = next(line for line in ax.get_lines() if line.get_marker() == "X")
    assert (agent_end.get_xdata()[0], agent_end.get_ydata()[0]) == (start_x - END_OFFSET, start_y - END_OFFSET)
    assert agent_end.get_zorder() > toy_start.get_zorder()
    agent_start = next(line for line in ax.get_lines() if line.get_marker() == "o")
    assert agent_end.get_zorder() > agent_start.get_zorder() and agent_end.get_markersize() < agent_start.get_markersize()


def test_picture_titles_quote_the_command_and_give_the_goal_in_words_with_its_ids():
    from groundlang.render import picture_title

    assert picture_title("take the star to the red room", "the yellow star in the red room",
                         "toyInRoom(block0, room2)") == (
        "\u201ctake the star to the red room\u201d\n"
        "\u2192 the yellow star in the red room \u2014 toyInRoom(block0, room2)")
    assert picture_title("go", "", "agentInRoom(agent0, room1)", "reached").endswith(
        "\u2192 agentInRoom(agent0, room1): reached")


def test_without_matplotlib_pictures_are_refused_in_one_line_and_the_rest_runs(tmp_path):
    """matplotlib is the optional ``plot`` extra: without it ``--out`` says what to install before any work,
    and the commands that draw nothing run (the subprocess hides matplotlib as an uninstalled package)."""
    from pathlib import Path
    example = Path(__file__).parent.parent / "groundlang" / "examples" / "star2red_0.txt"
    hide = "import sys; sys.modules['matplotlib'] = None; from groundlang.cli import main; sys.exit(main(sys.argv[1:]))"
    picture = tmp_path / "star.png"
    done = subprocess.run([sys.executable, "-c", hide, "--quiet", "show", str(example), "--palette", "sokoban",
                           "--out", str(picture)], capture_output=True, text=True)
    assert done.returncode == 2 and done.stdout == "" and not picture.exists()
    assert done.stderr == (f"groundlang show: error: {picture}: drawing a picture needs matplotlib, an optional "
                           "extra: pip install 'groundlang[plot]' (in a clone: pip install -e '.[plot]')\n")
    done = subprocess.run([sys.executable, "-c", hide, "--quiet", "show", str(example), "--palette", "sokoban"],
                          capture_output=True, text=True)
    assert done.returncode == 0 and "command: push the star into the red room" in done.stdout, done.stderr
    done = subprocess.run([sys.executable, "-c", hide, "--quiet", "tasks", str(example), "--palette", "sokoban"],
                          capture_output=True, text=True)
    assert done.returncode == 0 and "toyToRoom" in done.stdout, done.stderr


@pytest.mark.parametrize("drawn", ["^", "~", "a^", "$%", "\\"])
def test_a_palettes_glyph_of_mathtext_characters_is_drawn(tmp_path, drawn):
    """``^`` and ``~`` are accents in mathtext, which wanted an argument: the picture failed with a parser's
    message naming no palette."""
    pytest.importorskip("matplotlib")
    from groundlang.logic import palettes

    source = (Path(str(palettes.__path__[0])) / "sokoban.lp").read_text()
    mine = tmp_path / "glyphs.lp"
    said = 'glyph(star, "%s")' % drawn.replace("\\", "\\\\")  # an ASP string: a backslash is written twice
    mine.write_text(re.sub(r'glyph\(star, "[^"]*"\)', lambda _: said, source))
    state = parse_state("room,5,0,5,5,0 block,12,0,1,1 agent,2,2", str(mine))
    assert glyph("star", state.layout.palette) == drawn
    out = save_picture(tmp_path / "g.png", state)
    assert Path(out).read_bytes()[:8] == PNG_MAGIC


def test_every_printable_ascii_glyph_is_drawable_mathtext():
    pytest.importorskip("matplotlib")
    from matplotlib.mathtext import MathTextParser

    from groundlang.render import _mathtext

    parser = MathTextParser("agg")
    for code in range(33, 127):
        parser.parse(_mathtext(chr(code)))  # raises for a glyph mathtext cannot draw


def test_ascii_rooms_of_one_initial_are_told_apart():
    """Two red rooms had both been drawn 'r' (the legend naming both): letters in order where initials collide."""
    from groundlang.bdm import parse_bdm_state

    def line(first: str, second: str) -> str:
        return ("{agent0 (agent): [x: {2} y: {2} ] , door0 (door): [top: {4} left: {2} bottom: {4} right: {2} ] , "
                "door1 (door): [top: {4} left: {6} bottom: {4} right: {6} ] , "
                f"room0 (room): [top: {{4}} left: {{0}} bottom: {{0}} right: {{8}} colour: {{{first}}} ] , "
                f"room1 (room): [top: {{8}} left: {{0}} bottom: {{4}} right: {{4}} colour: {{{second}}} ] , "
                "room2 (room): [top: {8} left: {4} bottom: {4} right: {8} colour: {green} ] , }")

    same = ascii_state(parse_bdm_state(line("red", "red"))[0]).splitlines()
    assert same[:9] == ["#########", "#bbb#ccc#", "#bbb#ccc#", "#bbb#ccc#", "##+###+##",
                        "#aaaaaaa#", "#aAaaaaa#", "#aaaaaaa#", "#########"]
    assert same[-3:] == ["  a room0 (red)", "  b room1 (red)", "  c room2 (green)"]
    apart = ascii_state(parse_bdm_state(line("red", "blue"))[0])
    assert "  r room0 (red)\n  b room1 (blue)\n  g room2 (green)" in apart and "#bbb#ggg#" in apart


def test_a_glyph_or_a_title_with_dollar_signs_is_drawn_as_written(tmp_path):
    """``glyph(ball, "$^$")`` had been read as matplotlib mathtext: a one-line error naming neither, after the
    text picture; ``"$x$"`` drawn as math."""
    pytest.importorskip("matplotlib")
    source = (Path(__file__).parents[1] / "logic" / "palettes" / "sokoban.lp").read_text(encoding="utf-8")
    palette_file = tmp_path / "dollars.lp"
    palette_file.write_text(source + 'value(shape, 5, ball).\nglyph(ball, "$^$").\n', encoding="utf-8")
    palette = get_palette(str(palette_file))
    state = parse_state("room,1,0,4,4,0 block,12,5,2,2 agent,1,1", palette)
    assert glyph("ball", palette) == "$^$"
    for suffix, title in ((".png", "go to the $x$ room"), (".svg", "go to the $^$ room, $\\frac{$")):
        out = save_picture(tmp_path / f"d{suffix}", state, title=title)  # "$^$" is no mathtext: it had failed
        assert out.stat().st_size > 0


def test_a_posterior_chart_of_a_command_with_dollar_signs_is_drawn(learner):
    pytest.importorskip("matplotlib")
    from groundlang.animation import posterior_bar_chart

    post = learner.posterior("go to the $^$ red room", read_state_file(EXAMPLES / "novel_a.state", "sokoban"))
    for kind in ("goals", "readings"):
        ax = posterior_bar_chart(post, kind=kind)
        ax.figure.savefig(io.BytesIO(), format="png")  # drawing is where mathtext would have failed
        assert ax.get_title().startswith("'go to the")
