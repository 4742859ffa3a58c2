"""Many (MDP, goal) blocks solved over their disjoint union, each stopping when it alone would."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from groundlang.inference.disjoint import solve_blocks
from groundlang.inference.planning import PlanningError, TaskSettings, solve_task


def _grid(width: int, height: int) -> np.ndarray:
    """A walled grid: moves north, south, east, west; a move into the wall stays."""
    s = np.arange(width * height).reshape(width, height)
    x, y = np.divmod(np.arange(width * height), height)
    north = s[x, np.minimum(y + 1, height - 1)]
    south = s[x, np.maximum(y - 1, 0)]
    east = s[np.minimum(x + 1, width - 1), y]
    west = s[np.maximum(x - 1, 0), y]
    return np.stack([north, south, east, west], axis=1)


@pytest.mark.slow
@pytest.mark.parametrize("absorbing", [False, True])
@pytest.mark.parametrize("backend", ["eager", "compiled"])
def test_each_block_gets_the_policy_its_own_solve_gives(absorbing, backend):
    settings = TaskSettings(absorbing_goal=absorbing)
    rng = np.random.default_rng(0)
    blocks, rows = [], []
    for width, height in ((3, 4), (20, 30), (8, 8), (40, 2)):  # far goals need many more sweeps than near ones
        ns = _grid(width, height)
        goal = np.zeros(len(ns), dtype=bool)
        goal[rng.integers(len(ns))] = True
        blocks.append((ns, goal))
        rows.append(rng.integers(len(ns), size=6))
    got = solve_blocks(blocks, settings, rows, backend=backend)
    for (ns, goal), at, policy in zip(blocks, rows, got):
        alone = solve_task(ns, goal, settings, backend=backend)
        assert policy.shape == (6, 5)
        want = alone.log_policy[torch.as_tensor(at)]
        finite = torch.isfinite(want)
        assert torch.equal(finite, torch.isfinite(policy))
        assert torch.allclose(policy[finite], want[finite], atol=1e-5)


def test_blocks_and_their_policy_states_must_pair_up():
    with pytest.raises(PlanningError, match="2 blocks but 1 lists of policy states"):
        solve_blocks([(_grid(2, 2), np.ones(4, bool))] * 2, TaskSettings(), [np.array([0])])


def test_a_block_stopped_at_max_sweeps_is_left_as_solve_task_leaves_it(caplog):
    settings = TaskSettings(max_sweeps=5)
    ns = _grid(30, 30)
    goal = np.zeros(len(ns), dtype=bool)
    goal[0] = True
    rows = np.array([0, 899])
    (policy,) = solve_blocks([(ns, goal)], settings, [rows], backend="eager")
    alone = solve_task(ns, goal, settings, backend="eager")
    assert not alone.converged and alone.sweeps == 5
    assert torch.allclose(policy, alone.log_policy[torch.as_tensor(rows)], atol=1e-6)
    assert "stopped 1 of 1 blocks after 5 sweeps" in caplog.text
