"""Pictures of Cleanup World states: matplotlib drawings and ASCII for terminals.

North is up in both. matplotlib is imported inside the functions (Agg, no
pyplot), so importing this module costs nothing and needs no display.
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from groundlang.logic.storage import as_path
from groundlang.model.world import State

__all__ = ["glyph", "as_written", "cell_inches", "draw_state", "picture_title", "picture_format", "check_picture_destination", "save_picture", "ascii_state", "trajectory_positions"]

# Half an inch a cell up to this many inches a side, then smaller cells: a 1000 x 1000 room at half an
# inch a cell was a 50,000-pixel-square canvas (75 GiB). Ticks are labelled only on small grids.
MAX_FIGURE_INCHES = 16.0
MAX_TICKED_CELLS = 40

_WALL = (0.18, 0.18, 0.2)
_DOOR = (0.93, 0.89, 0.80)
_OUTSIDE = (1.0, 1.0, 1.0)


def as_written(text: str) -> str:
    """``text`` for matplotlib to draw as written: its dollar signs escaped, so that none opens mathtext (a
    palette's glyph "$^$", a command "go to the $x$ room" in a title, which had ended a drawing with a
    mathtext parse error; ``parse_math=False`` is not enough where a title is wrapped, measured as math)."""
    return text.replace("$", r"\$")


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


# Where a marker of the end of a trajectory sits in its cell, and how large, against one of the start:
# a toy that ends on the agent's start cell, or the agent on a toy's start cell, leaves both visible.
# Toys end up and to the right of the cell's centre, the agent down and to the left: the agent ends beside
# the toy it pushed, and the two end markers never meet.
END_OFFSET = 0.27  # cells
END_SCALE = 0.55
AGENT_END_SCALE = 0.7  # of the agent's start circle: a cross this size still shows the toy glyph around it
# Drawing order, bottom to top: paths, then start markers, then end markers (smaller, so they never hide them).
_Z_PATH, _Z_TOY, _Z_AGENT, _Z_TOY_END, _Z_AGENT_END = 3, 5, 6, 8, 9


def _mathtext(text: str) -> str:
    """A glyph as a mathtext marker (``$★$``), every printable ASCII character drawable: ``$ _ { } % #``
    escaped, ``^`` and ``~`` (accents there) over an empty group, and ``"`` and a backquote, which mathtext
    cannot draw in any spelling, as the typographic quotes they look like."""
    return "$" + "".join(_MATHTEXT.get(c, c) for c in text) + "$"


_MATHTEXT = {"\\": "\\backslash ", "^": "\\^{}", "~": "\\~{}", '"': "\u201d", "`": "\u2018",
             **{c: "\\" + c for c in "$_{}%#"}}


def _named(names: Mapping[str, str] | None):
    """An object's name as shown: the file's (``names``, by the layout's name, ``corpus.file_names``) where it
    gives one, else the layout's."""
    return (lambda name: name) if not names else (lambda name: _short(names.get(name, name)))


def _short(name: str, most: int = 40) -> str:
    """A name as drawn: a file may name an object with 60,000 letters, which would widen the picture to match."""
    return name if len(name) <= most else name[: most - 1] + "\u2026"


def _legend(ax, state: State, moved: list[int], has_path: bool, cell: float,
            names: Mapping[str, str] | None = None) -> None:
    """A legend below the map: the agent and each toy by id and in words, what start, end and paths look
    like, and each room's id and colour (two rooms of one colour are told apart by the ids drawn in them)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    lay, palette, shown = state.layout, state.layout.palette, _named(names)
    agent = shown(lay.movable_names[0])
    size = 9
    handles = [Line2D([], [], marker="o", ls="none", ms=size, mfc="white", mec="black",
                      label=f"{agent}{' at the start' if has_path else ''}")]
    if has_path:
        handles += [Line2D([], [], color="black", lw=2, alpha=0.7, label=f"{agent}'s path"),
                    Line2D([], [], marker="X", ls="none", ms=size * AGENT_END_SCALE, mfc="black", mec="white",
                           label=f"{agent} at the end (lower left)")]
    for k, (name, toy) in enumerate(zip(lay.toy_names, state.toys), start=1):
        colour, mark = _rgb(toy.colour, palette), _mathtext(glyph(toy.shape, palette))
        start = " at the start" if k in moved else ""
        handles.append(Line2D([], [], marker=mark, ls="none", ms=size * 1.2, color=colour, mec="black", mew=0.3,
                              label=f"{shown(name)} ({toy.colour} {toy.shape}{_added(lay, name)}){start}"))
        if k in moved:
            handles += [Line2D([], [], ls="--", lw=2, color=colour, label=f"{shown(name)}'s path"),
                        Line2D([], [], marker=mark, ls="none", ms=size * 1.2 * END_SCALE, color=colour,
                               mec="black", mew=0.3, label=f"{shown(name)} at the end (small, upper right)")]
    handles += [Patch(facecolor=0.45 * _rgb(r.colour, palette) + 0.55, edgecolor="black", lw=0.5,
                      label=f"{shown(name)} ({r.colour}{_added(lay, name)})")
                for name, r in zip(lay.room_names, lay.rooms)]
    handles += [Patch(facecolor=_DOOR, edgecolor="black", lw=0.5, label="door"),
                Patch(facecolor=_WALL, edgecolor="black", lw=0.5, label="wall")]
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.04 if cell >= 0.3 else -0.02),
              ncol=3 if lay.width >= 9 else 2, fontsize=7, frameon=False, handlelength=2.2)


def draw_state(state: State, ax=None, trajectory=None, title: str | None = None, legend: bool = True,
               names: Mapping[str, str] | None = None):
    """Draw a state (and optionally a trajectory as paths) on a matplotlib Axes; returns the Axes.

    ``trajectory``: sequence of States or positions ``[T, 1 + num_toys, 2]``. The state's own positions
    are the start; where the trajectory ends is drawn on top, smaller and off the cell's centre, so no
    marker hides another. ``legend``: a key below the map (the agent, toys and rooms by id and in words,
    the start, end and path markers); animation frames and gym observations leave it out.
    Without ``ax`` a new Agg figure is made (no pyplot, no display needed). ``names``: the objects' names
    as a file gives them, by the layout's (``corpus.file_names``), for the ids drawn and the legend.
    """
    import matplotlib.patheffects as pe
    from matplotlib.figure import Figure

    cell = cell_inches(state)
    if ax is None:
        lay = state.layout
        fig = Figure(figsize=(cell * lay.width + 1, cell * lay.height + 1))
        ax = fig.add_subplot(1, 1, 1)
    lay, palette = state.layout, state.layout.palette
    glyph_size = 32 * cell  # points: 16 at half an inch a cell, as before; smaller with the cells
    marker_size = 26 * cell
    ax.imshow(
        _cell_colours(state), origin="lower", interpolation="nearest",
        extent=(-0.5, lay.width - 0.5, -0.5, lay.height - 0.5),
    )
    # Each room's id in its upper-left corner: titles and printed goals name rooms by id.
    for name, r in zip(lay.room_names, lay.rooms):
        ax.text(r.left + 0.55, r.top - 0.55, as_written(_named(names)(name)), ha="left", va="top", fontsize=max(4.0, 12 * cell),
                color=(0.15, 0.15, 0.15), alpha=0.75, zorder=2)
    outline = [pe.withStroke(linewidth=2.5, foreground="black")]
    pos = trajectory_positions(trajectory)
    moved: list[int] = []
    if len(pos) > 1:
        moved = [k for k in range(1, min(pos.shape[1], len(state.toys) + 1)) if (pos[:, k] != pos[0, k]).any()]
        ax.plot(pos[:, 0, 0], pos[:, 0, 1], "-", color="black", lw=2, alpha=0.7, zorder=_Z_PATH)
        for k in moved:
            toy = state.toys[k - 1]
            ax.plot(pos[:, k, 0], pos[:, k, 1], "--", color=_rgb(toy.colour, palette), lw=2.5,
                    path_effects=outline, zorder=_Z_PATH)
            ax.text(pos[-1, k, 0] + END_OFFSET, pos[-1, k, 1] + END_OFFSET, as_written(glyph(toy.shape, palette)),
                    ha="center", va="center", fontsize=glyph_size * END_SCALE, color=_rgb(toy.colour, palette),
                    family="DejaVu Sans", path_effects=[pe.withStroke(linewidth=1, foreground="black")],
                    zorder=_Z_TOY_END)
        # Above every start marker: the agent often ends where a toy started (it pushed the toy on).
        ax.plot(pos[-1, 0, 0] - END_OFFSET, pos[-1, 0, 1] - END_OFFSET, "X", ms=marker_size * AGENT_END_SCALE,
                mfc="black", mec="white",
                mew=min(1.5, 3 * cell), zorder=_Z_AGENT_END)
    for toy in state.toys:
        ax.text(toy.x, toy.y, as_written(glyph(toy.shape, palette)), ha="center", va="center", fontsize=glyph_size,
                color=_rgb(toy.colour, palette),
                family="DejaVu Sans", path_effects=[pe.withStroke(linewidth=1.5, foreground="black")], zorder=_Z_TOY)
    ax.plot(state.agent.x, state.agent.y, "o", ms=marker_size, color="white", mec="black", mew=min(2, 4 * cell),
            zorder=_Z_AGENT)
    ax.text(state.agent.x, state.agent.y, "A", ha="center", va="center", fontsize=18 * cell, weight="bold",
            zorder=_Z_AGENT)
    ax.set_xlim(-0.5, lay.width - 0.5)
    ax.set_ylim(-0.5, lay.height - 0.5)
    if max(lay.width, lay.height) <= MAX_TICKED_CELLS:
        ax.set_xticks(range(lay.width))
        ax.set_yticks(range(lay.height))
    ax.tick_params(labelsize=7)
    ax.set_aspect("equal")
    if title:
        ax.set_title(as_written(title), fontsize=9, wrap=True)
    if legend:
        _legend(ax, state, moved, len(pos) > 1, cell, names)
    return ax


def picture_title(command: str, goal_words: str, goal_ids: str, outcome: str | None = None) -> str:
    """A picture's title a person reads: the command quoted, then the goal in words with its ids beside
    ("the yellow star in the red room \u2014 toyInRoom(block0, room2)") and, if given, the outcome."""
    goal = f"{goal_words} \u2014 {goal_ids}" if goal_words else goal_ids
    return f"\u201c{command}\u201d\n\u2192 {goal}" + (f": {outcome}" if outcome else "")


def picture_format(path: str | Path) -> str:
    """The image format of a picture's path, from its suffix ("png" without one); ValueError unless png,
    svg or pdf, and unless matplotlib (the ``plot`` extra) is installed. Commands ask before their work,
    :func:`save_picture` again when it writes."""
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    if fmt not in ("png", "svg", "pdf"):
        raise ValueError(f"{path}: picture format {fmt!r} is not supported; expected .png, .svg or .pdf")
    try:
        import matplotlib  # noqa: F401  (an optional extra: asked here, before any work)
    except ImportError:
        raise ValueError(f"{path}: drawing a picture needs matplotlib, an optional extra: "
                         "pip install 'groundlang[plot]' (in a clone: pip install -e '.[plot]')") from None
    return fmt


def check_picture_destination(path: str | Path, option: str = "--out", reads=()) -> Path:
    """A picture's path, refused before any work if its format is unsupported or it cannot be written, or
    would replace what the command reads (``reads``: ``(option, path)`` pairs, as ``check_destination``)."""
    from groundlang.logic.storage import check_destination

    picture_format(path)
    return check_destination(path, option, reads)


def save_picture(path: str | Path, state: State, trajectory=None, title: str | None = None,
                 names: Mapping[str, str] | None = None) -> Path:
    """Draw a state (and trajectory) and write the image atomically; format from the suffix (png, svg, pdf);
    ``names`` as :func:`draw_state`'s."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    path = as_path(path, "save_picture: path")
    fmt = picture_format(path)
    lay = state.layout
    cell = cell_inches(state)
    fig = Figure(figsize=(cell * lay.width + 1.5, cell * lay.height + 1.5))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    draw_state(state, ax=ax, trajectory=trajectory, title=title, names=names)
    from groundlang.logic.storage import atomic_path

    # Drawn in memory first: the PNG writer seeks, which a FIFO given as --out cannot.
    image = io.BytesIO()
    # "tight" grows the canvas to take in the legend below the map and a long title.
    fig.savefig(image, format=fmt, dpi=100, bbox_inches="tight", pad_inches=0.15)
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        handle.write(image.getvalue())
    return path


def _toy_symbols(state: State) -> list[str]:
    """Shape initials in upper case, or digits when two toys' initials would collide."""
    initials = [t.shape[:1].upper() for t in state.toys]
    if len(set(initials)) == len(initials) and "A" not in initials:
        return initials
    return [str(i % 10) for i in range(len(state.toys))]


def _room_symbols(state: State) -> list[str]:
    """Colour initials in lower case, or letters in order when two rooms' initials would collide (two red
    rooms, or a green and a gray one): a picture whose rooms look alike says nothing of which is which."""
    initials = [r.colour[:1].lower() for r in state.layout.rooms]
    if len(set(initials)) == len(initials):
        return initials
    return [chr(ord("a") + i % 26) for i in range(len(initials))]


def ascii_state(state: State, names: Mapping[str, str] | None = None) -> str:
    """A text picture, north up: ``#`` wall, ``+`` door, room floors by colour initial, ``A`` agent, toys.

    Ends with a legend naming every symbol's object (room0, block0, ...; ``names``: as a file names them,
    by the layout's names, ``corpus.file_names``).
    """
    shown = _named(names)
    lay = state.layout
    grid = np.full((lay.width, lay.height), " ", dtype="<U1")
    grid[lay.wall] = "#"
    grid[lay.wall & lay.walkable] = "+"
    rooms = _room_symbols(state)
    for sym, r in zip(rooms, lay.rooms):
        grid[r.left + 1 : r.right, r.bottom + 1 : r.top] = sym
    symbols = _toy_symbols(state)
    for sym, toy in zip(symbols, state.toys):
        grid[toy.x, toy.y] = sym
    grid[state.agent.x, state.agent.y] = "A"
    rows = ["".join(grid[:, y]).rstrip() for y in range(lay.height - 1, -1, -1)]
    door = lay.wall & lay.walkable

    def on_door(x: int, y: int) -> str:  # its symbol hides the door's "+"
        return ", on a door" if door[x, y] else ""

    agent_door = " (on a door)" if door[state.agent.x, state.agent.y] else ""
    legend = [f"legend: # wall, + door, A {shown(lay.movable_names[0])}{agent_door}"]
    legend += [f"  {s} {shown(name)} ({t.colour} {t.shape}{_added(lay, name)}{on_door(t.x, t.y)})"
               for s, name, t in zip(symbols, lay.toy_names, state.toys)]
    legend += [f"  {sym} {shown(name)} ({r.colour}{_added(lay, name)})"
               for sym, name, r in zip(rooms, lay.room_names, lay.rooms)]
    return "\n".join(rows + legend)


def _added(layout, name: str) -> str:
    """The values of the attributes the palette adds to object ``name``, each after a space (" metal")."""
    return "".join(f" {v}" for v in layout.added_values(name).values())
