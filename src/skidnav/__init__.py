"""skidnav: model-based reinforcement learning navigation for skid-steering mobile robots.

Importing the package registers the Gymnasium environment ``skidnav/SkidSteerNav-v0`` (and the
grid mazes) as soon as Gymnasium is imported, without importing it
(:mod:`skidnav.envs.on_import`). The
Python API (:mod:`skidnav.api`: ``make_env``, ``make_agent``, ``train``, ``evaluate``,
``save_agent``, ``load_agent``, ``convergence_episode``, ``run_config``, ``agent_names``, and
the training callback's ``EpisodeInfo`` and ``StopTraining``) is
available from the package itself and imported only when first used, so ``import skidnav``
stays fast.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from skidnav.envs.on_import import register_on_import
from skidnav.version import __version__

register_on_import()

if TYPE_CHECKING:  # what type checkers see; at run time the module is imported on first use
    from skidnav.api import EpisodeInfo as EpisodeInfo
    from skidnav.api import RunResults as RunResults
    from skidnav.api import StopTraining as StopTraining
    from skidnav.api import agent_names as agent_names
    from skidnav.api import convergence_episode as convergence_episode
    from skidnav.api import evaluate as evaluate
    from skidnav.api import load_agent as load_agent
    from skidnav.api import make_agent as make_agent
    from skidnav.api import make_env as make_env
    from skidnav.api import reference_length as reference_length
    from skidnav.api import run_config as run_config
    from skidnav.api import save_agent as save_agent
    from skidnav.api import train as train

API = (
    "EpisodeInfo",
    "RunResults",
    "StopTraining",
    "agent_names",
    "convergence_episode",
    "evaluate",
    "load_agent",
    "make_agent",
    "make_env",
    "reference_length",
    "run_config",
    "save_agent",
    "train",
)
"""The names of :mod:`skidnav.api` the package gives (PEP 562: imported on first use)."""

__all__ = ["__version__", *API]


def __getattr__(name: str) -> Any:
    """The API function or class ``name`` (:data:`API`), its module imported now."""
    if name in API:
        from skidnav import api

        return getattr(api, name)
    raise AttributeError(f"module 'skidnav' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *API})
