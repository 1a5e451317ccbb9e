"""What every family's config is made of: the value-learning hyperparameters (α, γ, ε),
the learned kinematic model's fields, and the one check that gives a config's one-line error.

The families' configs extend :class:`QLearningConfig` (tabular and linear agents) and add
:class:`KinematicModelFields` (every agent that learns the kinematic model: the model-based
tabular agents, ``linear-dyna-kinematic``, ``mppi-kinematic``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, TypeVar

from skidnav.errors import shown
from skidnav.files.configtables import check_keys
from skidnav.models.kinematic_config import KinematicModelConfig

KINEMATIC_MODELS = ("learned", "prior", "true")
"""Values of :attr:`KinematicModelFields.kinematic_model`."""


C = TypeVar("C", bound="QLearningConfig")


def check(condition: bool, expected: str, value: object) -> None:
    if not condition:
        raise ValueError(f"expected {expected}, got {shown(value)}")


@dataclass(frozen=True)
class QLearningConfig:
    """One-step Q-learning with a decaying ε-greedy behaviour (Sutton & Barto (2018) §6.5)."""

    alpha: float = 0.1
    """Step size α of every value update, in (0, 1]."""
    gamma: float = 0.95
    """Discount factor γ per action, in [0, 1]."""
    epsilon: float = 0.1
    """Initial exploration rate ε₀ (probability of a uniformly random action), in [0, 1]."""
    epsilon_decay: float = 1.0
    """Per-episode factor: ε_k = max(epsilon_min, ε₀ · decay^k) after k episodes; 1 = constant."""
    epsilon_min: float = 0.0
    """Floor of the decaying ε, in [0, epsilon]."""
    initial_q: float = 0.0
    """Initial value of every entry of the Q table (optimistic if above the true values)."""
    alpha_visit_exponent: float = 0.0
    """Exponent ω of the step size of real updates, in [0, 1]: the n-th real update of a pair
    uses α · n^(−ω) (polynomial step sizes, Even-Dar & Mansour (2003)); 0 = the constant α of
    the thesis. Planning updates keep the constant α."""

    def __post_init__(self) -> None:
        check(0.0 < self.alpha <= 1.0, "alpha in (0, 1]", self.alpha)
        check(0.0 <= self.gamma <= 1.0, "gamma in [0, 1]", self.gamma)
        check(0.0 <= self.epsilon <= 1.0, "epsilon in [0, 1]", self.epsilon)
        check(0.0 < self.epsilon_decay <= 1.0, "epsilon_decay in (0, 1]", self.epsilon_decay)
        check(
            0.0 <= self.epsilon_min <= self.epsilon, "epsilon_min in [0, epsilon]", self.epsilon_min
        )
        check(math.isfinite(self.initial_q), "a finite initial_q", self.initial_q)
        check(
            0.0 <= self.alpha_visit_exponent <= 1.0,
            "alpha_visit_exponent in [0, 1]",
            self.alpha_visit_exponent,
        )

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict of every field."""
        return dataclasses.asdict(self)

    @classmethod
    def from_mapping(cls: type[C], values: Mapping[str, Any]) -> C:
        """Build from a mapping (e.g. a TOML table or a saved agent's JSON); unknown keys raise
        ValueError. Messages quote at most :data:`~skidnav.errors.EXCERPT_CHARS` characters of a
        value or key (:func:`~skidnav.files.saved.shown`)."""
        check_keys(values, sorted(field.name for field in dataclasses.fields(cls)))
        return cls(**dict(values))


@dataclass(frozen=True)
class KinematicModelFields:
    """The learned kinematic model's hyperparameters as fields of an agent's config (those of
    :class:`~skidnav.models.kinematic_config.KinematicModelConfig`, prefixed ``kinematic_``), for
    every agent that learns one (``dyna-kinematic`` and its variants, ``linear-dyna-kinematic``);
    the agent's ``__post_init__`` validates them by calling :meth:`kinematic_config`."""

    kinematic_min_samples: int = 20
    """Samples a region needs before its own regression is used."""
    kinematic_refit_every: int = 500
    """Minimum new sub-step samples between refits (checked at episode ends)."""
    kinematic_refit_growth: float = 1.0
    """Refits also wait for this fraction of the samples already fitted (0 for drifting slip)."""
    kinematic_window: int = 500
    """Samples kept per region (sliding window)."""
    kinematic_forgetting: float = 1.0
    """Per-sample weight decay of older samples, in (0, 1]."""
    kinematic_speed_strata: int = 1
    """Rings of commanded speed each region's window is split into (1: one window), so that slow
    samples cannot crowd fast ones out (:class:`~skidnav.models.kinematic.KinematicModelConfig`'s
    ``speed_strata``); the discrete actions all command one speed."""
    kinematic_model: str = "learned"
    """Which kinematic model the agent plans with: "learned" (the thesis: refitted online from
    the kinematic log), "prior" (the nominal robot, the regression's prior, never refitted: the
    ablation of learning) or "true" (the simulator's expected body velocities of each slip
    region and action, never refitted: a reference no real robot offers; it needs the
    kinematic env's ``true_kinematics``)."""

    def kinematic_config(self) -> KinematicModelConfig:
        """The kinematic model's config (ValueError for a bad field, ``kinematic_model``
        included)."""
        check(
            self.kinematic_model in KINEMATIC_MODELS,
            f"kinematic_model in {KINEMATIC_MODELS}",
            self.kinematic_model,
        )
        return KinematicModelConfig(
            min_samples=self.kinematic_min_samples,
            refit_every=self.kinematic_refit_every,
            refit_growth=self.kinematic_refit_growth,
            window=self.kinematic_window,
            forgetting=self.kinematic_forgetting,
            speed_strata=self.kinematic_speed_strata,
        )
