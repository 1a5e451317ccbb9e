"""The classical navigator gives the same actions, maps and routes with and without numba
(NUMBA_DISABLE_JIT=1), on a short drive into a BARN world."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.nojit_support import script_arrays

DRIVE = """
import sys
import numpy as np
import skidnav
from tests.agents.classical.support import JACKAL, barn_env

env = barn_env(226, rays=90)
agent = skidnav.make_agent(
    "classical", env, speed_samples=3, yaw_rate_samples=5, horizon=1.0, ray_stride=2, **JACKAL
)
observation, _ = env.reset(seed=0)
actions = []
for _ in range(25):
    action = agent.act(observation)
    observation, *_ = env.step(action)
    actions.append(action)
navigator = agent.navigator
np.savez(
    sys.argv[1], actions=np.array(actions), occupied=navigator.occupied,
    ends=navigator.ray_ends, crossings=navigator.ray_crossings,
    **navigator.cost_map._asdict(), replans=np.array([navigator.replans]),
)
"""


def run(out: Path, disable_jit: bool) -> dict[str, np.ndarray]:
    return script_arrays(DRIVE, out, disable_jit=disable_jit, timeout=600)


def test_same_actions_and_maps_without_jit(tmp_path: Path) -> None:
    compiled = run(tmp_path / "jit.npz", disable_jit=False)
    interpreted = run(tmp_path / "nojit.npz", disable_jit=True)
    assert compiled.keys() == interpreted.keys()
    for key in compiled:
        assert compiled[key].tobytes() == interpreted[key].tobytes(), key
    assert compiled["occupied"].sum() > 10 and compiled["replans"][0] >= 2  # it mapped, replanned
    assert np.abs(compiled["actions"]).max() > 10.0  # it drove (Ω ≈ 20.4 rad/s)
