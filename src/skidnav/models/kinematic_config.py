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
        speed_strata: the window of a region is split into this many rings of
            ``window // speed_strata`` samples, one per equal bin of commanded speed
            ``max(|ω_L|, |ω_R|) / wheel_speed`` (:mod:`skidnav.models.kinematic_moments`), so
            that a long run of slow commands cannot push the fast samples out of the window
            (1: the plain sliding window). Samples must then be fed through
            :meth:`~skidnav.models.kinematic.KinematicModel.feed`.
        incremental: refit from per-ring moments kept up to date sample by sample (equal to
            the refit from the raw window up to floating-point rounding); False: rebuild every
            fit from the window.
    """

    min_samples: int = 20
    refit_every: int = 500
    refit_growth: float = 1.0
    window: int = 500
    forgetting: float = 1.0
    fit_intercept: bool = False
    speed_strata: int = 1
    incremental: bool = True

    def __post_init__(self) -> None:
        for name in ("min_samples", "refit_every", "window", "speed_strata"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise ValueError(f"expected {name} to be an integer >= 1, got {value!r}")
        if not self.refit_growth >= 0:
            raise ValueError(f"expected refit_growth >= 0, got {self.refit_growth}")
        if not 0 < self.forgetting <= 1:
            raise ValueError(f"expected forgetting in (0, 1], got {self.forgetting}")
        if self.speed_strata > self.window:
            raise ValueError(
                f"expected speed_strata <= window ({self.window}), got {self.speed_strata}"
            )
        for name in ("fit_intercept", "incremental"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"expected {name} to be a bool, got {getattr(self, name)!r}")


def window_slots(count: int, window: int) -> np.ndarray:
    """Ring-buffer slots of the kept samples of a region that has received ``count`` samples
    into a buffer of ``window``, oldest first: int64 (min(count, window),)."""
    return np.arange(count - min(count, window), count) % window
