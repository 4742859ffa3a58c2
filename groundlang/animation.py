"""Pictures that move or compare: an animated GIF of a trajectory, and posterior bar charts.

    result = learner.follow("take the star to the red room", state)
    save_animation("follow.gif", result.states, title=result.command)
    posterior_bar_chart(result.posterior, kind="goals")   # a matplotlib Axes

matplotlib is imported inside the functions (Agg, no pyplot, no display);
files are written atomically (a temporary file in the same folder, then
``os.replace``; a FIFO or a device is written into, see logic.storage).
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np

from groundlang.logic.atoms import format_goal
from groundlang.logic.storage import as_path
from groundlang.model.world import State
from groundlang.render import as_written

__all__ = ["save_animation", "animate_follow", "posterior_bar_chart", "POSTERIOR_KINDS"]

POSTERIOR_KINDS = ("goals", "lifted", "interpretations", "readings")


def save_animation(path: str | Path, states: Sequence[State], title: str | None = None, fps: float = 4.0,
                   dpi: int = 60, hold_last: int = 2) -> Path:
    """Write an animated GIF of a trajectory: one frame per state, the path so far drawn behind.

    ``states``: the trajectory (at least one State, all of one layout).
    ``hold_last``: extra copies of the final frame, so a looping GIF pauses at the end.
    Raises ValueError for an empty trajectory or a path not ending in ``.gif``.
    """
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from groundlang.render import cell_inches, draw_state

    path = as_path(path, "save_animation: path")
    if path.suffix.lower() != ".gif":
        raise ValueError(f"{path}: an animation is written as GIF; expected a path ending in .gif")
    states = list(states)
    if not states:
        raise ValueError(f"{path}: no states to animate; expected a trajectory of at least one state")
    lay = states[0].layout
    cell = cell_inches(states[0])  # bounded like a picture's: a large layout is drawn with smaller cells
    fig = Figure(figsize=(cell * lay.width + 1.5, cell * lay.height + 1.5), dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    frames = list(range(len(states))) + [len(states) - 1] * max(0, int(hold_last))

    def draw(i: int):
        ax.clear()
        label = f"step {i}/{len(states) - 1}"
        # No legend: frames keep one size, and a key below the map would be cut off at the figure's edge.
        draw_state(states[i], ax=ax, trajectory=states[: i + 1], title=f"{title}\n{label}" if title else label,
                   legend=False)
        return []

    draw(0)
    fig.tight_layout()
    animation = FuncAnimation(fig, draw, frames=frames, blit=False, repeat=False)
    import tempfile

    from groundlang.logic.storage import atomic_path

    # Drawn into a private file first: the GIF writer seeks, which a FIFO given as the path cannot.
    with tempfile.TemporaryDirectory(prefix="groundlang-gif-") as folder:
        drawn = Path(folder) / "animation.gif"
        animation.save(str(drawn), writer=PillowWriter(fps=fps), dpi=dpi)
        with atomic_path(path, suffix=".gif") as tmp, open(tmp, "wb") as handle:
            handle.write(drawn.read_bytes())
    return path


def animate_follow(path: str | Path, result, fps: float = 4.0, dpi: int = 60) -> Path:
    """GIF of what :meth:`groundlang.Learner.follow` did, titled with the command and the goal it chose."""
    from groundlang.render import picture_title

    outcome = "reached" if result.reached else f"not reached ({result.reason})"
    title = picture_title(result.command, result.goal_words, format_goal(result.goal), outcome)
    return save_animation(path, result.states, title=title, fps=fps, dpi=dpi)


def _bars(posterior, kind: str, top: int) -> tuple[list[str], np.ndarray]:
    if kind == "goals":
        items = [(format_goal(goal), p) for goal, p in posterior.goals()]
    elif kind == "lifted":
        items = list(posterior.lifted_tasks().items())
    elif kind == "interpretations":
        items = []
        for p, interp in posterior.ranked():
            constraint = " ∧ ".join(str(a) for a in interp.constraint.atoms) or "true"
            items.append((f"{format_goal(interp.goal)} | {constraint}", p))
    elif kind == "readings":
        if posterior.reading_probabilities is None:
            raise ValueError("this posterior has no reading probabilities (only the parse-aligned "
                             "language model aligns readings); use kind='goals' or 'lifted'")
        items = [(r.logical_form.paper_str(), float(p))
                 for r, p in zip(posterior.readings, posterior.reading_probabilities)]
        items.sort(key=lambda kv: -kv[1])
    else:
        raise ValueError(f"unknown kind {kind!r}; expected one of {', '.join(POSTERIOR_KINDS)}")
    items = items[:top]
    return [label for label, _ in items], np.array([p for _, p in items], dtype=float)


def posterior_bar_chart(posterior, kind: str = "goals", top: int = 8, ax=None, title: str | None = None):
    """Horizontal bars of a :class:`groundlang.learner.Posterior`, most probable on top; returns the Axes.

    ``kind``: ``goals`` (grounded goals, summed over constraints), ``lifted``
    (lifted tasks), ``interpretations`` (goal and constraint) or ``readings``
    (logical forms; parse-aligned model only). Without ``ax`` a new Agg
    figure is made. Raises ValueError for an unknown kind.
    """
    from matplotlib.figure import Figure

    labels, probs = _bars(posterior, kind, top)
    if ax is None:
        fig = Figure(figsize=(7, 0.35 * max(len(labels), 2) + 1.2))
        ax = fig.add_subplot(1, 1, 1)
    y = np.arange(len(labels))
    ax.barh(y, probs, color="tab:blue")
    ax.set_yticks(y, [as_written(label) for label in labels], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlim(0, 1)
    ax.set_xlabel("posterior probability")
    for yi, p in zip(y, probs):
        ax.text(min(p, 0.85) + 0.01, yi, f"{p:.3f}", va="center", fontsize=7)
    ax.set_title(as_written(title if title is not None else f"{posterior.command!r}: {kind}"), fontsize=9)
    return ax
