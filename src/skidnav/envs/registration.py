"""Registration of skidnav's Gymnasium environments."""

from __future__ import annotations

import gymnasium

ENV_ID = "skidnav/SkidSteerNav-v0"


def register_envs() -> None:
    """Register ``skidnav/SkidSteerNav-v0`` (idempotent)."""
    if ENV_ID in gymnasium.registry:
        return
    gymnasium.register(
        id=ENV_ID,
        entry_point="skidnav.envs.navigation:SkidSteerNavEnv",
        max_episode_steps=None,
    )
