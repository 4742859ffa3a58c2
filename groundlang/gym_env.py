"""Cleanup World as a gymnasium environment; a learned model's policy for it is in :mod:`groundlang.gym_policy`.

    import gymnasium, groundlang.gym_policy       # registers "groundlang/Cleanup-v0" (gym_env does)
    env = gymnasium.make("groundlang/Cleanup-v0", render_mode="rgb_array")
    obs, info = env.reset(seed=0)                 # obs["grid"]: [H, W, 6] uint8, obs["command"]: str
    act = groundlang.gym_policy.policy(learner, obs["command"], env.unwrapped.state)  # also gym_env.policy
    obs, reward, terminated, truncated, info = env.step(act(obs))

Without ``gymnasium`` installed this module cannot be imported (``pip install
groundlang[gym]``); the rest of groundlang never imports it. With gymnasium
1.x, ``gymnasium.make("groundlang.gym_env:groundlang/Cleanup-v0")`` imports
and registers in one go.

Observation channels of ``grid`` (row 0 is the north edge, column 0 the west
edge, as the pictures of :mod:`groundlang.render` show them):

    0 wall          1 on wall cells no door clears
    1 door          1 on door cells
    2 room colour   1 + palette colour index of the room the cell lies in, 0 elsewhere
    3 agent         1 where the agent stands
    4 toy colour    1 + palette colour index of the toy on the cell, 0 where none
    5 toy shape     1 + palette shape index of the toy on the cell, 0 where none
    6, ...          one per attribute the palette adds (``attribute(toy, material)``), named
                    ``CLASS_ATTRIBUTE`` (``toy_material``) in the palette's order: 1 + the index of
                    the value of the room (on its cells), door or toy there, 0 elsewhere

``env.channels`` names them (:func:`channels`): a palette of colours and shapes alone has the six.
"""

from __future__ import annotations

import enum
import logging
import string
from functools import lru_cache
from typing import Any, Callable

import gymnasium
import numpy as np
from gymnasium import spaces

from groundlang.learner_state import check_count
from groundlang.logic.atoms import Atom, parse_goal
from groundlang.model.world import Action, State, step

__all__ = [
    "ENV_ID",
    "CleanupAction",
    "CleanupEnv",
    "CHANNELS",
    "channels",
    "COMMAND_CHARSET",
    "MAX_COMMAND_LENGTH",
    "CommandPolicy",  # these three live in groundlang.gym_policy, read from here as before
    "policy",
    "observation_positions",
    "register_envs",
]

log = logging.getLogger(__name__)

ENV_ID = "groundlang/Cleanup-v0"
CHANNELS = ("wall", "door", "room_colour", "agent", "toy_colour", "toy_shape")
# Printable ASCII without tabs and line breaks: what a command line holds after normalisation.
COMMAND_CHARSET = "".join(c for c in string.printable if c not in "\t\n\r\x0b\x0c")
MAX_COMMAND_LENGTH = 1024
# Typographic characters crowd workers type, and their ASCII spelling in observations.
_ASCII = str.maketrans({"\u2018": "'", "\u2019": "'", "\u201c": '"', "\u201d": '"', "\u2013": "-", "\u2014": "-"})


# The moves are model.world.Action's, written there once; TERMINATE follows them, as the planner's stop column
# does (inference.planning.TERMINATE), so that a policy's argmax column is the action it names.
CleanupAction = enum.IntEnum("CleanupAction", [(a.name, a.value) for a in Action] + [("TERMINATE", len(Action))])
CleanupAction.__doc__ = "The moves of :class:`groundlang.model.world.Action` (same names and values) and TERMINATE."


def command_text(command: str) -> str:
    """The command as the observation holds it: one line of printable ASCII.

    Typographic quotes and dashes become ASCII, other characters outside
    ``COMMAND_CHARSET`` become ``?``; longer than ``MAX_COMMAND_LENGTH`` is a ValueError.
    """
    text = " ".join(str(command).translate(_ASCII).split())
    text = "".join(c if c in COMMAND_CHARSET else "?" for c in text)
    if len(text) > MAX_COMMAND_LENGTH:
        raise ValueError(f"command of {len(text)} characters; at most {MAX_COMMAND_LENGTH} fit the observation")
    return text


@lru_cache(maxsize=1)
def _example_pool() -> tuple[tuple[State, str, tuple[Atom, ...] | None], ...]:
    """(initial state, command, gold goal) of every example-corpus instance, in file order."""
    from groundlang.corpus import example_corpus_path, read_corpus
    from groundlang.labels import label_for, read_labels

    root = example_corpus_path()
    corpus = read_corpus(root, "sokoban")
    labels = read_labels(root / "labels.csv")
    return tuple((inst.initial_state, inst.command, label_for(inst, labels)) for inst in corpus)


def channels(palette) -> tuple[str, ...]:
    """The names of an observation grid's channels for states of ``palette``: :data:`CHANNELS`, then one per
    attribute the palette adds (``toy_material``), so that toys (rooms, doors) the words tell apart by one
    are told apart in the grid too."""
    return CHANNELS + tuple(f"{cls}_{attribute}" for cls, attribute in palette.added)


def _interior(room, H: int) -> tuple[slice, slice]:
    """A room's interior cells in a grid of ``H`` rows, north up: rows H-1-y for y in bottom+1..top-1."""
    return slice(H - room.top, H - room.bottom - 1), slice(room.left + 1, room.right)


def _added_planes(state: State, shape: tuple[int, int], classes: tuple[str, ...]) -> np.ndarray:
    """The channels of the palette's added attributes ``[H, W, len(added)]``, filled for objects of
    ``classes`` (the rooms and doors stay put, the toys move)."""
    lay, (H, W) = state.layout, shape
    cells = {"room": [(name, _interior(r, H)) for name, r in zip(lay.room_names, lay.rooms)],
             "door": [(name, (slice(H - 1 - d.top, H - d.bottom), slice(d.left, d.right + 1)))
                      for name, d in zip(lay.door_names, lay.doors)],
             "toy": [(name, (H - 1 - t.y, t.x)) for name, t in zip(lay.toy_names, state.toys)]}
    grid = np.zeros((H, W, len(lay.palette.added)), dtype=np.uint8)
    for k, (cls, attribute) in enumerate(lay.palette.added):
        if cls in classes:
            values = lay.palette.values_of(attribute)
            for name, (rows, cols) in cells[cls]:
                grid[rows, cols, k] = values.index(lay.added_values(name)[attribute]) + 1
    return grid


def _static_grid(state: State, shape: tuple[int, int]) -> np.ndarray:
    """The channels of a layout that stay put ``[H, W, 6 + added]`` (north up), padded to ``shape`` =
    (H, W): 0-2 and the rooms' and doors' added attributes; the rest is 0, filled by :func:`_observed_grid`."""
    lay = state.layout
    H, W = shape
    grid = np.zeros((H, W, len(channels(lay.palette))), dtype=np.uint8)
    wall, walkable = lay.wall, lay.walkable  # [width, height]
    door = wall & walkable
    h = lay.height
    # layout grids are [x, y]; the observation is [row, col] with row 0 = y = h - 1
    grid[H - h:, : lay.width, 0] = (wall & ~walkable).T[::-1]
    grid[H - h:, : lay.width, 1] = door.T[::-1]
    for r in lay.rooms:
        value = lay.palette.colour_index(r.colour) + 1
        grid[(*_interior(r, H), 2)] = value
    grid[:, :, len(CHANNELS):] = _added_planes(state, shape, ("room", "door"))
    return grid


def _observed_grid(static: np.ndarray, state: State) -> np.ndarray:
    """The observation of ``state``: the layout's ``static`` channels with the agent and the toys on them."""
    grid = static.copy()
    H = grid.shape[0]
    pal = state.layout.palette
    grid[H - 1 - state.agent.y, state.agent.x, 3] = 1
    for toy in state.toys:
        grid[H - 1 - toy.y, toy.x, 4] = pal.colour_index(toy.colour) + 1
        grid[H - 1 - toy.y, toy.x, 5] = pal.shape_index(toy.shape) + 1
    if pal.added:
        grid[:, :, len(CHANNELS):] |= _added_planes(state, grid.shape[:2], ("toy",))
    return grid


def _largest_value(palette) -> int:
    """The largest value a grid cell of this palette holds: the index + 1 of a colour, shape or added
    attribute's value (0 is none)."""
    return max(len(values) for _, values in palette.all_values) + 1


def _library(library):
    """A task library given to the env: None (the domain's PFs), a TaskLibrary, or the path of its file."""
    import os

    from groundlang.logic.tasks import TaskLibrary

    if library is None or isinstance(library, TaskLibrary):
        return library
    if isinstance(library, (str, os.PathLike, list, tuple)):  # what TaskLibrary.load takes
        if not str(library).strip() or library in ([], ()):  # "" would read the working folder
            raise ValueError(f"library {library!r}: empty; give a TaskLibrary or the path of its .lp file")
        try:
            return TaskLibrary.load(library)
        except OSError as exc:  # a folder, a missing file: said of the library, not as an Errno
            raise ValueError(f"library {exc.filename or library}: {exc.strerror or exc}; expected the path of a "
                             ".lp file") from None
    raise TypeError(f"library must be a TaskLibrary, the path of its .lp file or None, got {type(library).__name__}")


class CleanupEnv(gymnasium.Env):
    """Cleanup World with a command: move (and push toys), then TERMINATE.

    ``state``: the initial state; None picks one example-corpus instance per
    reset (by the reset's seed) with its command and gold goal.
    ``command``: the text in every observation (default: the picked instance's).
    ``goal``: atoms, or text like ``"toyInRoom(block0, room1)"``; optional.
    ``library``: a TaskLibrary (or the path of its ``.lp`` file) whose PF rules the goal may use
    (default: the domain's, ``logic/pfs.lp``), as ``goal_holds`` takes it.
    Reward is 1 on the step that makes the goal hold (or on TERMINATE while
    it holds), else 0. An episode terminates on TERMINATE or when the goal
    holds, and is truncated after ``max_steps`` steps. ``info["goal_holds"]``
    says whether the goal holds (False without a goal); ``info["state"]`` is
    the :class:`State`. ``reset(options={"state": ..., "command": ...,
    "goal": ...})`` overrides any of them for that episode.
    """

    metadata = {"render_modes": ["rgb_array", "ansi"], "render_fps": 4}

    def __init__(self, state: State | None = None, command: str = "", goal=None,
                 render_mode: str | None = None, max_steps: int = 200, library=None):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode {render_mode!r} is not supported; expected one of "
                             f"{', '.join(self.metadata['render_modes'])} or None")
        check_count("CleanupEnv", "max_steps", max_steps)
        if state is not None and not isinstance(state, State):
            raise TypeError(f"state must be a State (or None for the example corpus's), got {type(state).__name__}")
        if not isinstance(command, str):
            raise TypeError(f"command must be a str, got {type(command).__name__}")
        self.library = _library(library)
        self.render_mode = render_mode
        self.max_steps = int(max_steps)
        self._fixed_state = state
        self._fixed_command = command_text(command) if command else ""
        self._fixed_goal = self._goal(goal)
        if state is not None and self._fixed_goal is not None:
            from groundlang.labels import check_goal_objects

            check_goal_objects(self._fixed_goal, state, library=self.library)  # refused now, not at the first reset
        layouts = [state.layout] if state is not None else [s.layout for s, _, _ in _example_pool()]
        self.grid_shape = (max(l.height for l in layouts), max(l.width for l in layouts))
        # Colour and shape indices + 1 must fit uint8.
        top = max(_largest_value(l.palette) for l in layouts)
        self.channels = channels(layouts[0].palette)  # the example corpus's layouts share one palette
        self.palette = layouts[0].palette  # what the grid's colour and shape numbers mean
        self.action_space = spaces.Discrete(len(CleanupAction))
        self.observation_space = spaces.Dict({
            "grid": spaces.Box(0, top, shape=(*self.grid_shape, len(self.channels)), dtype=np.uint8),
            "command": spaces.Text(MAX_COMMAND_LENGTH, min_length=0, charset=COMMAND_CHARSET),
        })
        self.state: State | None = None
        self.command = ""
        self.goal: tuple[Atom, ...] | None = None
        self.steps = 0
        self._over = False  # terminated or truncated: only reset() goes on
        self._static: np.ndarray | None = None

    @staticmethod
    def _goal(goal) -> tuple[Atom, ...] | None:
        if goal is None or goal == "" or goal == ():
            return None
        if isinstance(goal, str):
            return parse_goal(goal)
        if isinstance(goal, Atom):
            return (goal,)
        if isinstance(goal, (tuple, list)) and all(isinstance(a, Atom) for a in goal):
            return tuple(goal)
        raise TypeError(f"goal must be a goal string, an Atom or a sequence of Atoms, got {type(goal).__name__}")

    def _holds(self) -> bool:
        from groundlang.labels import goal_holds

        return self.goal is not None and goal_holds(self.goal, self.state, self.library)

    def _observation(self) -> dict[str, Any]:
        return {"grid": _observed_grid(self._static, self.state), "command": self.command}

    def _info(self) -> dict[str, Any]:
        return {"goal_holds": self._holds(), "state": self.state, "goal": self.goal, "steps": self.steps}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        if options is not None and not isinstance(options, dict):
            raise TypeError(f"options must be a dict, got {type(options).__name__}")
        options = dict(options or {})
        if unknown := sorted(set(options) - {"state", "command", "goal"}):
            raise ValueError(f"options {', '.join(map(repr, unknown))}: expected state, command or goal")
        if "state" in options and not isinstance(options["state"], State):
            raise TypeError(f"options['state'] must be a State, got {type(options['state']).__name__}")
        if "command" in options and not isinstance(options["command"], str):
            raise TypeError(f"options['command'] must be a str, got {type(options['command']).__name__}")
        state, command, goal = self._fixed_state, self._fixed_command, self._fixed_goal
        if "state" not in options and state is None:
            pool = _example_pool()
            picked, picked_command, picked_goal = pool[int(self.np_random.integers(len(pool)))]
            state = picked
            command = command or command_text(picked_command)
            goal = goal if goal is not None else picked_goal
        if "state" in options:
            state = options["state"]
        if "command" in options:
            command = command_text(options["command"])
        if "goal" in options:
            goal = self._goal(options["goal"])
        if state.layout.height > self.grid_shape[0] or state.layout.width > self.grid_shape[1]:
            raise ValueError(f"state of size {state.layout.height}x{state.layout.width} does not fit the "
                             f"observation grid {self.grid_shape[0]}x{self.grid_shape[1]} of this env")
        palette = state.layout.palette
        # A grid's numbers are indices into the env's palette: another palette's state of as many channels had
        # been taken, its colours then read as the env's (red as blue)
        if (palette.all_values, palette.added) != (self.palette.all_values, self.palette.added):
            raise ValueError(f"state of palette {palette.name}: this env's grids number the values of palette "
                             f"{self.palette.name}; make the env with a state of that palette")
        if goal is not None:
            from groundlang.labels import check_goal_objects

            # before anything changes: a refused reset leaves the episode as it was
            check_goal_objects(goal, state, library=self.library)
        self.state, self.command, self.goal, self.steps, self._over = state, command, goal, 0, False
        self._static = _static_grid(state, self.grid_shape)
        return self._observation(), self._info()

    def step(self, action):
        if self.state is None:
            raise RuntimeError("call reset() before step()")
        if self._over:
            raise RuntimeError("the episode is over (terminated or truncated): call reset() before step()")
        # int(1.5) would take a move no policy chose; an integer type only, in range
        if isinstance(action, bool) or not isinstance(action, (int, np.integer)) or not 0 <= action < len(CleanupAction):
            raise ValueError(f"action must be an integer from 0 to {len(CleanupAction) - 1} (CleanupAction), "
                             f"got {action!r:.40}")
        action = CleanupAction(int(action))
        self.steps += 1
        if action == CleanupAction.TERMINATE:
            self._over = True
            return self._observation(), float(self._holds()), True, False, self._info()
        self.state = step(self.state, action)
        holds = self._holds()
        truncated = not holds and self.steps >= self.max_steps
        self._over = holds or truncated
        return self._observation(), float(holds), holds, truncated, self._info()

    def render(self):
        if self.render_mode is None or self.state is None:
            return None
        if self.render_mode == "ansi":
            from groundlang.render import ascii_state

            return ascii_state(self.state) + "\n"
        return render_rgb(self.state, title=self.command or None)


def render_rgb(state: State, title: str | None = None, trajectory=None, dpi: int = 60) -> np.ndarray:
    """An RGB picture ``[height, width, 3]`` uint8 of a state (matplotlib Agg, no display)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from groundlang.render import draw_state

    from groundlang.render import cell_inches

    lay = state.layout
    cell = cell_inches(state)  # half an inch a cell, less on a large grid: the picture's size is bounded as show's
    fig = Figure(figsize=(cell * lay.width + 1.5, cell * lay.height + 1.5), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    draw_state(state, ax=ax, trajectory=trajectory, title=title, legend=False)  # an observation: the map only
    fig.tight_layout()
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[:, :, :3].copy()


def run_episode(env: gymnasium.Env, act: Callable, seed: int | None = None, options: dict | None = None):
    """Reset ``env`` and act until the episode ends; returns (states, actions, total reward, info)."""
    obs, info = env.reset(seed=seed, options=options)
    states, actions, total = [info["state"]], [], 0.0
    while True:
        a = act(obs)
        obs, reward, terminated, truncated, info = env.step(a)
        total += reward
        actions.append(CleanupAction(int(a)))
        if CleanupAction(int(a)) != CleanupAction.TERMINATE:
            states.append(info["state"])
        if terminated or truncated:
            return states, actions, total, info


def __getattr__(name: str):
    # The policy reads this module's observations, so it imports this module; importing it back lazily keeps
    # ``from groundlang.gym_env import policy`` working without a cycle at import time.
    if name in ("CommandPolicy", "policy", "observation_positions"):
        from groundlang import gym_policy

        return getattr(gym_policy, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def register_envs() -> None:
    """Register ``groundlang/Cleanup-v0`` with gymnasium (idempotent)."""
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(id=ENV_ID, entry_point="groundlang.gym_env:CleanupEnv", max_episode_steps=None)


register_envs()
