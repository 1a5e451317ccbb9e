"""skidnav: model-based reinforcement learning navigation for skid-steering mobile robots.

Importing the package registers the Gymnasium environment ``skidnav/SkidSteerNav-v0``.
"""

from __future__ import annotations

__version__ = "0.1.0"

from skidnav.envs.registration import register_envs

register_envs()

__all__ = ["__version__"]
