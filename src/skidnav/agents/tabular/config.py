"""Hyperparameters of the tabular agents: frozen dataclasses validated on construction.

Each agent class names its config class in ``config_class``; configs extend each other, so an agent
that adds a hyperparameter subclasses the config of the agent it extends:
:class:`QLearningConfig` ⊂ :class:`DynaQConfig` ⊂ :class:`DynaQPlusConfig` and
:class:`PrioritizedSweepingConfig`.

>>> DynaQConfig(planning_steps=50).planning_steps
50
>>> DynaQConfig(alpha=1.5)
Traceback (most recent call last):
...
ValueError: expected alpha in (0, 1], got 1.5
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, TypeVar

from skidnav.errors import shown
from skidnav.models.kinematic import KinematicModelConfig
from skidnav.models.multinomial_kernels import PLANNING_MODES

KINEMATIC_MODELS = ("learned", "prior", "true")
"""Values of :attr:`KinematicModelFields.kinematic_model`."""
MAX_PLANNING_STEPS = 10_000_000
"""Most planning updates per real step (10 M: about a second of compiled planning)."""

MODEL_BASED_PLANNING_MODE = "expected"
"""The planning target of the model-based agents (``dyna-kinematic``, ``trajectory-prioritized``,
``dyna-full``, ``dyna-sweep``) by default: the expected update over the multinomial model's
outcomes (Sutton & Barto (2018) §8.5). The thesis's most-probable target jumps whenever the counts
of a pair's two likeliest outcomes swap, and the greedy policy jumps with it: measured on 30 worlds
of the thesis arena (docs/results.md, "Claims"), dyna-full at 100 planning updates stays converged
in 30 / 30 runs with the expected target against 23 / 30 with the most-probable one, and its
greedy policy passes 97 % of the last 10 % of evaluations against 88 %. Dyna-Q, Dyna-Q+ and
prioritized sweeping keep the thesis's target for the textbook comparisons; the thesis's
configs name "most-probable" to reproduce it."""

C = TypeVar("C", bound="QLearningConfig")


def _check(condition: bool, expected: str, value: object) -> None:
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
        _check(0.0 < self.alpha <= 1.0, "alpha in (0, 1]", self.alpha)
        _check(0.0 <= self.gamma <= 1.0, "gamma in [0, 1]", self.gamma)
        _check(0.0 <= self.epsilon <= 1.0, "epsilon in [0, 1]", self.epsilon)
        _check(0.0 < self.epsilon_decay <= 1.0, "epsilon_decay in (0, 1]", self.epsilon_decay)
        _check(
            0.0 <= self.epsilon_min <= self.epsilon, "epsilon_min in [0, epsilon]", self.epsilon_min
        )
        _check(math.isfinite(self.initial_q), "a finite initial_q", self.initial_q)
        _check(
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
        value or key (:func:`~skidnav.savedfile.shown`)."""
        known = {field.name for field in dataclasses.fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise ValueError(
                f"expected options among {sorted(known)}, got unknown {shown(unknown)}"
            )
        return cls(**dict(values))


@dataclass(frozen=True)
class DynaQConfig(QLearningConfig):
    """Dyna-Q with the multinomial model (Sutton & Barto (2018) §8.2; thesis)."""

    planning_steps: int = 5
    """Planning updates n after each real step (0 = plain Q-learning)."""
    planning_mode: str = "most-probable"
    """How the model answers: "most-probable" (thesis), "sample" or "expected"."""

    def __post_init__(self) -> None:
        super().__post_init__()
        _check(
            isinstance(self.planning_steps, int) and 0 <= self.planning_steps <= MAX_PLANNING_STEPS,
            f"an integer planning_steps in [0, {MAX_PLANNING_STEPS:,}]",
            self.planning_steps,
        )
        _check(
            self.planning_mode in PLANNING_MODES,
            f"planning_mode in {sorted(PLANNING_MODES)}",
            self.planning_mode,
        )

    @property
    def planning_mode_code(self) -> int:
        """The integer code of :attr:`planning_mode` for the kernels."""
        return PLANNING_MODES[self.planning_mode]


@dataclass(frozen=True)
class DynaQPlusConfig(DynaQConfig):
    """Dyna-Q+ (Sutton & Barto (2018) §8.3)."""

    kappa: float = 1e-3
    """Exploration-bonus weight κ: planning rewards get + κ·√τ, τ = real steps since the pair was
    last tried (reward units per √step), ≥ 0."""

    def __post_init__(self) -> None:
        super().__post_init__()
        _check(self.kappa >= 0.0 and math.isfinite(self.kappa), "kappa >= 0", self.kappa)


@dataclass(frozen=True)
class PrioritizedSweepingConfig(DynaQConfig):
    """Prioritized sweeping (Sutton & Barto (2018) §8.4). ``planning_steps`` bounds the queue
    updates per real step."""

    theta: float = 1e-4
    """Priority threshold θ ≥ 0: a pair is queued only if its |TD error| exceeds θ (reward)."""

    def __post_init__(self) -> None:
        super().__post_init__()
        _check(self.theta >= 0.0 and math.isfinite(self.theta), "theta >= 0", self.theta)
        _check(
            self.alpha_visit_exponent == 0.0,
            "alpha_visit_exponent 0 (its real update is a queue pop at the constant alpha)",
            self.alpha_visit_exponent,
        )


@dataclass(frozen=True)
class KinematicModelFields:
    """The learned kinematic model's hyperparameters as fields of an agent's config (those of
    :class:`~skidnav.models.kinematic.KinematicModelConfig`, prefixed ``kinematic_``), for every
    agent that learns one (``dyna-kinematic`` and its variants, ``linear-dyna-kinematic``); the
    agent's ``__post_init__`` validates them by calling :meth:`kinematic_config`."""

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
    kinematic_model: str = "learned"
    """Which kinematic model the agent plans with: "learned" (the thesis: refitted online from
    the kinematic log), "prior" (the nominal robot, the regression's prior, never refitted: the
    ablation of learning) or "true" (the simulator's expected body velocities of each slip
    region and action, never refitted: a reference no real robot offers; it needs the
    kinematic env's ``true_kinematics``)."""

    def kinematic_config(self) -> KinematicModelConfig:
        """The kinematic model's config (ValueError for a bad field, ``kinematic_model``
        included)."""
        _check(
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
        )
