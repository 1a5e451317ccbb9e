"""Registration of skidnav's Gymnasium environments.

Experiment configs name environments only by these registered ids (or any other registered
Gymnasium id, including Gymnasium's own ``module:Env-v0`` form): nothing named in a config is
ever called (docs/experiments.md).
"""

from __future__ import annotations

import gymnasium

ENV_ID = "skidnav/SkidSteerNav-v0"
MAX_EPISODE_STEPS = 500
"""Actions per episode of ``skidnav/SkidSteerNav-v0`` before Gymnasium's ``TimeLimit`` truncates
it (``gymnasium.make(ENV_ID, max_episode_steps=N)`` overrides it)."""
MAZE_IDS = {
    "skidnav/DynaMaze-v0": "skidnav.envs.mazes:dyna_maze",
    "skidnav/BlockingMaze-v0": "skidnav.envs.mazes:blocking_maze",
    "skidnav/ShortcutMaze-v0": "skidnav.envs.mazes:shortcut_maze",
}
"""The Sutton & Barto (2018) ch. 8 grid mazes (Examples 8.1–8.3) → their factories. They are
registered without a time limit, as the book runs them (episodes end at the goal)."""


def register_envs() -> None:
    """Register ``skidnav/SkidSteerNav-v0`` (truncated by Gymnasium's ``TimeLimit`` after
    :data:`MAX_EPISODE_STEPS` actions; ``gymnasium.make_vec`` makes its compiled vector env,
    :mod:`skidnav.envs.vector`) and the grid mazes (idempotent)."""
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(
            id=ENV_ID,
            entry_point="skidnav.envs.navigation:SkidSteerNavEnv",
            vector_entry_point="skidnav.envs.vector:make_vector_env",
            max_episode_steps=MAX_EPISODE_STEPS,
        )
    for env_id, entry_point in MAZE_IDS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(id=env_id, entry_point=entry_point, max_episode_steps=None)
