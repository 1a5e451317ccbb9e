"""Hyperparameters of the learned kinematic model (:mod:`skidnav.models.kinematic`) and the
sliding window of samples it keeps per slip region."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class KinematicModelConfig:
    """Hyperparameters of the learned kinematic model.

    Attributes:
        min_samples: samples a region (or the pool) needs before its own fit is used.
        refit_every: minimum new samples (free sub-steps) between two refits.
        refit_growth: also wait for ``refit_growth ×`` the samples seen at the last refit
            (0: refit every ``refit_every`` samples).
        window: samples kept per region (sliding window) [sub-steps].
        forgetting: per-sample weight decay in (0, 1]; 1 weighs all kept samples equally.
        fit_intercept: fit the intercepts vx_b, yaw_b, vy_b.
    """

    min_samples: int = 20
    refit_every: int = 500
    refit_growth: float = 1.0
    window: int = 500
    forgetting: float = 1.0
    fit_intercept: bool = False

    def __post_init__(self) -> None:
        for name in ("min_samples", "refit_every", "window"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise ValueError(f"expected {name} to be an integer >= 1, got {value!r}")
        if not self.refit_growth >= 0:
            raise ValueError(f"expected refit_growth >= 0, got {self.refit_growth}")
        if not 0 < self.forgetting <= 1:
            raise ValueError(f"expected forgetting in (0, 1], got {self.forgetting}")


def window_slots(count: int, window: int) -> np.ndarray:
    """Ring-buffer slots of the kept samples of a region that has received ``count`` samples
    into a buffer of ``window``, oldest first: int64 (min(count, window),)."""
    return np.arange(count - min(count, window), count) % window
