"""The linear agents give the same weights with and without numba (NUMBA_DISABLE_JIT=1)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.nojit_support import script_arrays

TRAINING = """
import sys
import numpy as np
from skidnav.agents.training import train_agent
from tests.agents.linear.support import make, small_pose_env

setups = [
    ("linear-q", {}),
    ("linear-sarsa", {"lam": 0.8}),
    ("linear-dyna", {"planning_steps": 3, "planning_memory": 20}),
]
arrays = {}
for index, (name, options) in enumerate(setups):
    env = small_pose_env()
    agent = make(name, env, index, tiles=[2], n_tilings=4, initial_q=0.5, **options)
    log = train_agent(agent, env, 4, max_steps=12, seed=index)
    arrays[name] = agent.w
    arrays[name + " lengths"] = log.lengths
np.savez(sys.argv[1], **arrays)
"""


def run(out: Path, disable_jit: bool) -> dict[str, np.ndarray]:
    return script_arrays(TRAINING, out, disable_jit=disable_jit, timeout=240)


def test_weights_are_bit_identical_without_jit(tmp_path: Path) -> None:
    compiled = run(tmp_path / "jit.npz", disable_jit=False)
    interpreted = run(tmp_path / "nojit.npz", disable_jit=True)
    assert compiled.keys() == interpreted.keys()
    for key in compiled:
        assert compiled[key].tobytes() == interpreted[key].tobytes(), key
        if "lengths" not in key:
            assert np.any(compiled[key] != 0.5 / 4)
