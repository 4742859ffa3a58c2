"""Pictures of Cleanup World states: matplotlib drawings and ASCII for terminals.

North is up in both. matplotlib is imported inside the functions (Agg, no
pyplot), so importing this module costs nothing and needs no display.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from groundlang.model.world import State

__all__ = ["glyph", "cell_inches", "draw_state", "picture_format", "check_picture_destination", "save_picture", "ascii_state", "trajectory_positions"]

# Half an inch a cell up to this many inches a side, then smaller cells: a 1000 x 1000 room at half an
# inch a cell was a 50,000-pixel-square canvas (75 GiB). Ticks are labelled only on small grids.
MAX_FIGURE_INCHES = 16.0
MAX_TICKED_CELLS = 40

_WALL = (0.18, 0.18, 0.2)
_DOOR = (0.93, 0.89, 0.80)
_OUTSIDE = (1.0, 1.0, 1.0)


def glyph(shape: str, palette) -> str:
    """The text that marks a toy of ``shape`` (the palette's glyph/2, else the shape's first letter)."""
    return dict(palette.glyphs).get(shape, shape[:1].upper())


def _rgb(colour: str, palette=None) -> np.ndarray:
    from matplotlib.colors import to_rgb

    name = dict(palette.rgb).get(colour, colour) if palette is not None else colour
    try:
        return np.array(to_rgb(name))
    except ValueError:  # a palette's own colour word matplotlib does not know ("cream"): drawn grey
        return np.array((0.6, 0.6, 0.6))


def trajectory_positions(trajectory) -> np.ndarray:
    """Positions ``[T, 1 + num_toys, 2]`` from a sequence of States or an array of that shape."""
    if trajectory is None:
        return np.zeros((0, 1, 2), dtype=np.int64)
    items = list(trajectory)
    if items and isinstance(items[0], State):
        return np.stack([s.positions for s in items])
    arr = np.asarray(items, dtype=np.int64)
    if arr.ndim != 3 or arr.shape[-1] != 2:
        raise ValueError(f"trajectory must be States or positions [T, 1+num_toys, 2], got shape {arr.shape}")
    return arr


def _cell_colours(state: State) -> np.ndarray:
    """RGB image ``[height, width, 3]`` (row = y) of rooms, walls, doors and outside."""
    lay = state.layout
    img = np.empty((lay.height, lay.width, 3))
    img[:] = _OUTSIDE
    wall = lay.wall.T
    img[wall] = _WALL
    img[wall & lay.walkable.T] = _DOOR
    for r in lay.rooms:
        # A tint keeps toys of the room's own colour visible on its floor.
        img[r.bottom + 1 : r.top, r.left + 1 : r.right] = 0.45 * _rgb(r.colour, state.layout.palette) + 0.55
    return img


def cell_inches(state: State) -> float:
    """The side of one cell in the figure: half an inch, less on a grid larger than MAX_FIGURE_INCHES."""
    return min(0.5, MAX_FIGURE_INCHES / max(state.layout.width, state.layout.height))


def draw_state(state: State, ax=None, trajectory=None, title: str | None = None):
    """Draw a state (and optionally a trajectory as paths) on a matplotlib Axes; returns the Axes.

    ``trajectory``: sequence of States or positions ``[T, 1 + num_toys, 2]``.
    Without ``ax`` a new Agg figure is made (no pyplot, no display needed).
    """
    import matplotlib.patheffects as pe
    from matplotlib.figure import Figure

    cell = cell_inches(state)
    if ax is None:
        lay = state.layout
        fig = Figure(figsize=(cell * lay.width + 1, cell * lay.height + 1))
        ax = fig.add_subplot(1, 1, 1)
    lay = state.layout
    glyph_size = 32 * cell  # points: 16 at half an inch a cell, as before; smaller with the cells
    marker_size = 26 * cell
    ax.imshow(
        _cell_colours(state), origin="lower", interpolation="nearest",
        extent=(-0.5, lay.width - 0.5, -0.5, lay.height - 0.5),
    )
    outline = [pe.withStroke(linewidth=2.5, foreground="black")]
    pos = trajectory_positions(trajectory)
    if len(pos) > 1:
        ax.plot(pos[:, 0, 0], pos[:, 0, 1], "-", color="black", lw=2, alpha=0.7, zorder=3, label="agent path")
        for k, toy in enumerate(state.toys, start=1):
            if k < pos.shape[1] and (pos[:, k] != pos[0, k]).any():
                ax.plot(pos[:, k, 0], pos[:, k, 1], "--", color=_rgb(toy.colour, state.layout.palette), lw=2.5,
                        path_effects=outline, zorder=3)
        ax.plot(pos[-1, 0, 0], pos[-1, 0, 1], "x", color="black", ms=10, mew=2, zorder=4)
        for k, toy in enumerate(state.toys, start=1):
            if k < pos.shape[1] and (pos[-1, k] != pos[0, k]).any():
                # Where the toy ends up, faint, so start and end both show.
                ax.text(pos[-1, k, 0], pos[-1, k, 1], glyph(toy.shape, state.layout.palette),
                        ha="center", va="center", fontsize=glyph_size, color=_rgb(toy.colour, state.layout.palette),
                        alpha=0.5, family="DejaVu Sans", zorder=4)
    for toy in state.toys:
        ax.text(toy.x, toy.y, glyph(toy.shape, state.layout.palette), ha="center", va="center", fontsize=glyph_size,
                color=_rgb(toy.colour, state.layout.palette),
                family="DejaVu Sans", path_effects=[pe.withStroke(linewidth=1.5, foreground="black")], zorder=5)
    ax.plot(state.agent.x, state.agent.y, "o", ms=marker_size, color="white", mec="black", mew=min(2, 4 * cell),
            zorder=6)
    ax.text(state.agent.x, state.agent.y, "A", ha="center", va="center", fontsize=18 * cell, weight="bold", zorder=7)
    ax.set_xlim(-0.5, lay.width - 0.5)
    ax.set_ylim(-0.5, lay.height - 0.5)
    if max(lay.width, lay.height) <= MAX_TICKED_CELLS:
        ax.set_xticks(range(lay.width))
        ax.set_yticks(range(lay.height))
    ax.tick_params(labelsize=7)
    ax.set_aspect("equal")
    if title:
        ax.set_title(title, fontsize=9, wrap=True)
    return ax


def picture_format(path: str | Path) -> str:
    """The image format of a picture's path, from its suffix ("png" without one); ValueError unless png,
    svg or pdf. Commands ask before their work, :func:`save_picture` again when it writes."""
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    if fmt not in ("png", "svg", "pdf"):
        raise ValueError(f"{path}: picture format {fmt!r} is not supported; expected .png, .svg or .pdf")
    return fmt


def check_picture_destination(path: str | Path, option: str = "--out") -> Path:
    """A picture's path, refused before any work if its format is unsupported or it cannot be written."""
    from groundlang.model.storage import check_destination

    picture_format(path)
    return check_destination(path, option)


def save_picture(path: str | Path, state: State, trajectory=None, title: str | None = None) -> Path:
    """Draw a state (and trajectory) and write the image atomically; format from the suffix (png, svg, pdf)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    path = Path(path)
    fmt = picture_format(path)
    lay = state.layout
    cell = cell_inches(state)
    fig = Figure(figsize=(cell * lay.width + 1.5, cell * lay.height + 1.5))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    draw_state(state, ax=ax, trajectory=trajectory, title=title)
    fig.tight_layout()
    from groundlang.model.storage import atomic_path

    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, dpi=100)
    return path


def _toy_symbols(state: State) -> list[str]:
    """Shape initials in upper case, or digits when two toys' initials would collide."""
    initials = [t.shape[:1].upper() for t in state.toys]
    if len(set(initials)) == len(initials) and "A" not in initials:
        return initials
    return [str(i % 10) for i in range(len(state.toys))]


def ascii_state(state: State) -> str:
    """A text picture, north up: ``#`` wall, ``+`` door, room floors by colour initial, ``A`` agent, toys.

    Ends with a legend naming every symbol's object (room0, block0, ...).
    """
    lay = state.layout
    grid = np.full((lay.width, lay.height), " ", dtype="<U1")
    grid[lay.wall] = "#"
    grid[lay.wall & lay.walkable] = "+"
    for r in lay.rooms:
        grid[r.left + 1 : r.right, r.bottom + 1 : r.top] = r.colour[:1].lower()
    symbols = _toy_symbols(state)
    for sym, toy in zip(symbols, state.toys):
        grid[toy.x, toy.y] = sym
    grid[state.agent.x, state.agent.y] = "A"
    rows = ["".join(grid[:, y]).rstrip() for y in range(lay.height - 1, -1, -1)]
    legend = ["legend: # wall, + door, A agent0"]
    legend += [f"  {s} {name} ({t.colour} {t.shape})" for s, name, t in zip(symbols, lay.toy_names, state.toys)]
    legend += [f"  {r.colour[:1].lower()} {name} ({r.colour})" for name, r in zip(lay.room_names, lay.rooms)]
    return "\n".join(rows + legend)
