"""A trained learner's closed-loop policy for :class:`groundlang.gym_env.CleanupEnv`: observations read back
into states of the layout, and an action for each from one plan (see :mod:`groundlang.gym_env`).

Without ``gymnasium`` installed this module cannot be imported (``pip install groundlang[gym]``).
"""

from __future__ import annotations

from itertools import permutations
from math import factorial

import gymnasium
import numpy as np

from groundlang.gym_env import CHANNELS, CleanupAction, _static_grid, channels
from groundlang.model.relevance import pushes_scenery
from groundlang.model.world import Action, State

__all__ = ["CommandPolicy", "policy", "observation_positions"]


# Toys alike in all the grid shows of them (colour, shape, added attributes) are told apart by where they were a
# step before; only those that cannot be (after a reset to another state) are matched in every order, which grows
# as k! and is refused beyond this.
MAX_ASSIGNMENTS = 5040


def observation_positions(grid: np.ndarray, layout, previous: np.ndarray | None = None) -> np.ndarray | None:
    """Agent and toy positions ``[1 + k, 2]`` (x, y) read from an observation grid.

    Toys are matched to the layout's toys by colour, shape and the values of
    the attributes the palette adds to toys; toys alike in all of them are
    interchangeable: each keeps its cell in ``previous`` (positions
    a step before) where a toy of its kind is still there, and the rest are
    assigned in every order by :func:`_position_candidates`. Returns None
    when the grid does not show the layout's agent and toys.
    """
    candidates = _position_candidates(grid, layout, previous)
    return candidates[0] if candidates else None


def _position_candidates(grid: np.ndarray, layout, previous: np.ndarray | None = None) -> list[np.ndarray]:
    grid = np.asarray(grid)
    if grid.ndim != 3 or grid.shape[2] != len(channels(layout.palette)):
        return []  # not a grid of this layout's palette
    H = grid.shape[0]
    rows, cols = np.nonzero(grid[:, :, 3])
    if len(rows) != 1:
        return []
    agent = (int(cols[0]), H - 1 - int(rows[0]))
    pal = layout.palette
    # a toy's kind: its colour, shape and the values of the attributes the palette adds to toys, as indices
    shown = [4, 5] + [len(CHANNELS) + k for k, (cls, _) in enumerate(pal.added) if cls == "toy"]
    cells: dict[tuple[int, ...], list[tuple[int, int]]] = {}
    for r, c in zip(*np.nonzero(grid[:, :, 4])):
        key = tuple(int(grid[r, c, k]) - 1 for k in shown)
        cells.setdefault(key, []).append((int(c), H - 1 - int(r)))
    wanted: dict[tuple[int, ...], list[int]] = {}
    toy_attributes = [a for cls, a in pal.added if cls == "toy"]
    for i, (name, (colour, shape)) in enumerate(zip(layout.toy_names, layout.toy_attributes)):
        values = layout.added_values(name)
        key = (pal.colour_index(colour), pal.shape_index(shape),
               *(pal.values_of(a).index(values[a]) for a in toy_attributes))
        wanted.setdefault(key, []).append(i)
    if {k: len(v) for k, v in wanted.items()} != {k: len(v) for k, v in cells.items()}:
        return []
    base = np.zeros((1 + len(layout.toy_attributes), 2), dtype=np.int64)
    base[0] = agent
    open_groups, assignments = [], 1
    for key, toys in wanted.items():
        free = list(cells[key])
        unmatched = []
        for t in toys:
            kept = tuple(int(v) for v in previous[1 + t]) if previous is not None else None
            if kept in free:
                free.remove(kept)
                base[1 + t] = kept
            else:
                unmatched.append(t)
        if len(unmatched) > 1:
            open_groups.append((unmatched, free))
            assignments *= factorial(len(unmatched))
        elif unmatched:
            base[1 + unmatched[0]] = free[0]
    if assignments > MAX_ASSIGNMENTS:
        raise ValueError(f"the observation shows toys alike in all it shows of them that cannot be told apart in "
                         f"{assignments:,} ways (at most {MAX_ASSIGNMENTS:,} are tried); step from the state the "
                         "policy was made for, or make the policy for this state")
    out = [base]
    for toys, free in open_groups:
        extended = []
        for known in out:
            for perm in permutations(free):
                new = known.copy()
                new[[1 + t for t in toys]] = perm
                extended.append(new)
        out = extended
    return out


def _same_static(grid: np.ndarray, state: State, expected: np.ndarray) -> bool:
    """Whether an observation ``grid`` shows ``state``'s layout (``expected``: its :func:`_static_grid` of the
    grid's shape): its walls, doors, rooms' colours and the rooms' and doors' added attributes, the channels
    that stay put (the agent and the toys aside)."""
    pal = state.layout.palette
    moving = {3, 4, 5} | {len(CHANNELS) + k for k, (cls, _) in enumerate(pal.added) if cls == "toy"}
    kept = [c for c in range(expected.shape[2]) if c not in moving]
    return bool(np.array_equal(grid[:, :, kept], expected[:, :, kept]))


class CommandPolicy:
    """A closed-loop policy for one command: observation -> CleanupAction.

    Plans once, on every state reachable from the initial state (or, in a
    world too large for that, from its relevance abstraction for the goal),
    for the most probable grounded goal of the command; then each observation
    is looked up in that state space. TERMINATE where the goal holds or when the observation
    is outside the planned space (nothing sensible to do).
    """

    def __init__(self, goal, posterior, space, log_policy, mask, start: np.ndarray | None = None,
                 start_state: State | None = None):
        self.goal = goal  # tuple[Atom, ...]
        self.previous = None if start is None else np.asarray(start)  # positions last seen: toys told apart
        # The layout planned in: a state or grid of another (rooms recoloured, another palette) is outside the
        # planned space, though its positions may be looked up in it (it had been acted on as the planned one).
        self.start_state = start_state
        self._static: dict[tuple[int, int], np.ndarray] = {}  # the planned layout's still channels, by grid shape
        self.posterior = posterior
        self.space = space
        self.log_policy = np.asarray(log_policy)  # [S, 5]
        self.mask = np.asarray(mask, dtype=bool)  # [S]

    def state_index(self, observation) -> int:
        grid = observation.get("grid") if isinstance(observation, dict) else observation
        if isinstance(grid, State):
            if self.start_state is not None and grid.layout != self.start_state.layout:
                return -1
            self.previous = grid.positions
            return int(self.space.indices_of(grid.positions[None])[0])
        grid = np.asarray(grid) if isinstance(grid, np.ndarray) else None
        lay = self.space.layout
        depth = len(channels(lay.palette))
        if grid is None or grid.ndim != 3 or grid.shape[2] != depth or grid.shape[0] < lay.height \
                or grid.shape[1] < lay.width:
            raise ValueError(f"observation must be an env's (a dict whose 'grid' is [H, W, {depth}], at "
                             f"least {lay.height}x{lay.width} here) or a State, got {type(observation).__name__}")
        if self.start_state is not None:  # drawn once a grid shape, not once a step
            shape = grid.shape[:2]
            if shape not in self._static:
                self._static[shape] = _static_grid(self.start_state, shape)
            if not _same_static(grid, self.start_state, self._static[shape]):
                return -1
        candidates = _position_candidates(grid, lay, self.previous)
        if not candidates:
            return -1
        found = self.space.indices_of(np.stack(candidates))
        hits = np.flatnonzero(found >= 0)
        if not len(hits):
            return -1
        self.previous = candidates[hits[0]]
        return int(found[hits[0]])

    def __call__(self, observation) -> CleanupAction:
        s = self.state_index(observation)
        if s < 0 or self.mask[s]:
            return CleanupAction.TERMINATE
        action = int(np.argmax(self.log_policy[s]))
        # A move into a toy a relevance abstraction holds still pushes it in the world, out of the planned space:
        # the policy ends before it, where follow's plan ends ("scenery").
        if action < len(Action) and pushes_scenery(self.space, np.array([s]), np.array([action]))[0]:
            return CleanupAction.TERMINATE
        return CleanupAction(action)


def policy(learner, command: str, state) -> CommandPolicy:
    """Wrap a trained :class:`groundlang.Learner` into a callable ``observation -> action``.

    ``state`` is the initial :class:`State` or a reset :class:`CleanupEnv`
    (its current state). It ends where :meth:`Learner.follow` would
    (:meth:`Learner.ending`: where the goals of the whole posterior most
    probably hold, with the language model's ``expected_success``), else where
    the posterior's most probable grounded goal holds, planned by soft value
    iteration with the learner's settings. Raises NotFittedError for an
    untrained learner.
    """
    from groundlang.inference.planning import solve_task
    from groundlang.model.features import goal_mask
    from groundlang.model.pf_tables import library_pf_tables
    from groundlang.model.relevance import state_space_for

    from groundlang.learner import Learner

    if not isinstance(learner, Learner):
        raise TypeError(f"policy: learner must be a trained Learner, got {type(learner).__name__}")
    if isinstance(state, gymnasium.Env):
        state = state.unwrapped.state
        if state is None:
            raise ValueError("the environment has no state yet: call reset() first")
    post = learner.posterior(command, state)
    ending = learner.ending(post, state)
    if ending:
        space, _, _, mask, goal = ending
    else:
        goal = post.best_goal
        tables = library_pf_tables(state.layout, learner.library)
        space = state_space_for(state, goal, tables=tables)
        mask = goal_mask(space, goal, tables)
    solved = solve_task(space.next_state, mask, learner.settings)
    return CommandPolicy(goal, post, space, solved.log_policy.detach().cpu().numpy(), mask, start=state.positions,
                         start_state=state)
