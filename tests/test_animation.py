"""Animated GIFs of trajectories and posterior bar charts."""

from __future__ import annotations

import numpy as np
import pytest

from groundlang.animation import animate_follow, posterior_bar_chart, save_animation
from groundlang.corpus import example_corpus_path, read_instance
from groundlang.learner import Posterior


@pytest.fixture(scope="module")
def demo():
    return read_instance(example_corpus_path() / "agent2blue_0.txt", "sokoban")


def _durations(im) -> list[int]:
    out = []
    for i in range(im.n_frames):
        im.seek(i)
        out.append(im.info["duration"])
    return out


def test_gif_has_one_frame_per_state_and_pauses_at_the_end(demo, tmp_path):
    PIL = pytest.importorskip("PIL.Image")
    path = save_animation(tmp_path / "demo.gif", demo.states, title=demo.command, fps=4, hold_last=2)
    assert path == tmp_path / "demo.gif"
    assert [p.name for p in tmp_path.iterdir()] == ["demo.gif"]  # no temporary file left behind
    with PIL.open(path) as im:
        # Pillow merges the repeated last frame into one frame shown three times as long.
        assert im.n_frames == len(demo.states) == 6
        assert _durations(im) == [250] * 5 + [750]
        im.seek(0)
        first = np.asarray(im.convert("RGB"))
        im.seek(len(demo.states) - 1)
        last = np.asarray(im.convert("RGB"))
    assert first.shape == last.shape and (first != last).any()  # the agent moved



def test_a_gif_is_written_into_a_fifo_not_over_it(demo, tmp_path):
    """The GIF writer seeks, which a FIFO cannot: the animation is drawn into a private file first."""
    import stat
    import time

    from test_render import _read_fifo

    read = _read_fifo(tmp_path / "demo.gif")
    save_animation(tmp_path / "demo.gif", demo.states[:2], hold_last=0)
    for _ in range(100):
        if read:
            break
        time.sleep(0.05)
    assert read and read[0].startswith(b"GIF89a")
    assert stat.S_ISFIFO((tmp_path / "demo.gif").lstat().st_mode)
    assert [p.name for p in tmp_path.iterdir()] == ["demo.gif"]

def test_bad_paths_and_empty_trajectories_are_value_errors(demo, tmp_path):
    with pytest.raises(ValueError, match="GIF"):
        save_animation(tmp_path / "demo.png", demo.states)
    with pytest.raises(ValueError, match="no states"):
        save_animation(tmp_path / "demo.gif", [])
    assert list(tmp_path.iterdir()) == []


class _FakeConstraint:
    atoms = ()


class _FakeInterpretation:
    def __init__(self, lifted, goal):
        self.lifted, self.goal, self.constraint = lifted, goal, _FakeConstraint()


def test_posterior_bar_chart_sums_goals_and_orders_bars():
    from groundlang.logic.atoms import parse_goal

    green, red = parse_goal("agentInRoom(agent0, room0)"), parse_goal("toyInRoom(block0, room1)")
    post = Posterior("go to green", [_FakeInterpretation("agentToRoom", green),
                                     _FakeInterpretation("toyToRoom", red),
                                     _FakeInterpretation("agentToRoom", green)],
                     np.array([0.3, 0.25, 0.45]))
    ax = posterior_bar_chart(post, kind="goals")
    labels = [t.get_text() for t in ax.get_yticklabels()]
    widths = [p.get_width() for p in ax.patches]
    assert labels == ["agentInRoom(agent0, room0)", "toyInRoom(block0, room1)"]
    assert widths == pytest.approx([0.75, 0.25])
    ax = posterior_bar_chart(post, kind="lifted", top=1)
    assert [t.get_text() for t in ax.get_yticklabels()] == ["agentToRoom"]
    with pytest.raises(ValueError, match="reading probabilities"):
        posterior_bar_chart(post, kind="readings")
    with pytest.raises(ValueError, match="unknown kind"):
        posterior_bar_chart(post, kind="words")


@pytest.mark.slow
def test_animate_follow_titles_the_command(tmp_path):
    PIL = pytest.importorskip("PIL.Image")
    from groundlang.corpus import read_corpus, read_state_file
    from groundlang.learner import Learner

    learner = Learner(cache_dir=False).fit(read_corpus(example_corpus_path(), "sokoban").instances)
    novel = read_state_file(example_corpus_path() / "novel_a.state", "sokoban")
    result = learner.follow("go to the blue room", novel)
    assert result.reached
    path = animate_follow(tmp_path / "follow.gif", result)
    with PIL.open(path) as im:
        assert im.n_frames == len(result.states)
    ax = posterior_bar_chart(result.posterior, kind="readings")
    probs = [p.get_width() for p in ax.patches]
    assert sum(probs) == pytest.approx(1.0, abs=1e-6) and probs == sorted(probs, reverse=True)
