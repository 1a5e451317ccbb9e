"""Same seed, same numbers with and without numba (NUMBA_DISABLE_JIT=1)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.nojit_support import script_arrays

TRAINING = """
import sys
import numpy as np
from skidnav.agents.tabular.registry import make_agent
from skidnav.agents.training import train_agent
from skidnav.envs.mazes import dyna_maze

setups = [
    ("q-learning", {}),
    ("dyna-q", {"planning_steps": 5, "planning_mode": "most-probable"}),
    ("dyna-q", {"planning_steps": 5, "planning_mode": "sample"}),
    ("dyna-q", {"planning_steps": 5, "planning_mode": "expected"}),
    ("dyna-q-plus", {"planning_steps": 5}),
    ("prioritized-sweeping", {"planning_steps": 5}),
]
tables = {}
for index, (name, options) in enumerate(setups):
    agent = make_agent(name, 54, 4, {"initial_q": 0.5, **options}, np.random.default_rng(index))
    train_agent(agent, dyna_maze(max_episode_steps=300), 6, seed=index)
    tables[f"{index}"] = agent.q
np.savez(sys.argv[1], **tables)
"""


def run(out: Path, disable_jit: bool) -> dict[str, np.ndarray]:
    return script_arrays(TRAINING, out, disable_jit=disable_jit, timeout=240)


def test_results_are_bit_identical_without_jit(tmp_path: Path) -> None:
    compiled = run(tmp_path / "jit.npz", disable_jit=False)
    interpreted = run(tmp_path / "nojit.npz", disable_jit=True)
    assert compiled.keys() == interpreted.keys()
    for key in compiled:
        assert compiled[key].tobytes() == interpreted[key].tobytes(), key
        assert np.any(compiled[key] != 0.5)
