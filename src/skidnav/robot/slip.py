"""Slip fields: how much each coarse floor region slows the wheels, and where its ICR lies.

The thesis (Alhawary (2020), App. A.1.1) slows each wheel by U(0, η) rad/s towards zero, where η
depends on the robot's coarse region (a 7 × 7 partition of the arena). A :class:`SlipField` holds,
per region, η [rad/s] and x_ICR [m], and may drift over time (non-stationary slip):

    η(region, t) = η₀(region) · max(0, 1 + A · sin(2π t / P + φ(region)))

with relative amplitude A, period P [s] and a seeded phase φ per region. x_ICR does not drift, so
once within [−a, b] (Kozłowski & Pazderski (2004); :meth:`SlipField.check_x_icr`) it stays there at
every time. The true variance of a wheel's speed in a region is η²/12 (variance of U(0, η)), and the
true expected body velocities of an action there follow from the expected wheel speeds
(:meth:`SlipField.expected_velocities`).

A field may also scale the robot's wheel radius and half track per region (the effective ICR
model of a calibrated floor, :mod:`skidnav.robot.floors`; 1 everywhere otherwise) and name each
region's floor material.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from skidnav._jit import jit
from skidnav.checks import check_number
from skidnav.robot.floors import (
    CALIBRATED_PRESETS,
    PRESET_FLOORS,
    calibrated_floor,
    calibrated_robot,
)
from skidnav.robot.kinematics import N_ACTIONS, commanded_wheel_speeds, expected_body_velocities
from skidnav.robot.params import RobotParams

SLIP_PRESETS = ("thesis", "slippery", "rough", "nominal", *CALIBRATED_PRESETS)


MAX_DRIFT_AMPLITUDE = 100.0
"""Largest relative drift amplitude A (a wheel-speed loss up to 101 times the field's)."""
MAX_DRIFT_PERIOD = 1e12
"""Longest drift period P [s]."""


@dataclass(frozen=True, eq=False)
class SlipField:
    """Per-region slip, validated on construction.

    Attributes:
        eta: wheel-speed loss scale η₀, shape (regions_x, regions_y) [rad/s], ≥ 0.
        x_icr: ICR offset per region, shape (regions_x, regions_y) [m].
        drift_amplitude: relative drift amplitude A ≥ 0 (0: stationary).
        drift_period: drift period P [s] > 0.
        drift_phase: phase φ per region, shape (regions_x, regions_y) [rad].
        wheel_radius_scale, half_track_scale: effective r and c per region relative to the
            robot's, shape (regions_x, regions_y), > 0 (None: 1 everywhere).
        materials: floor material name per region, shape (regions_x, regions_y) (None: the
            preset's, :data:`skidnav.robot.floors.PRESET_FLOORS`).
    """

    eta: np.ndarray
    x_icr: np.ndarray
    drift_amplitude: float = 0.0
    drift_period: float = 600.0
    drift_phase: np.ndarray = field(default_factory=lambda: np.zeros((7, 7)))
    wheel_radius_scale: np.ndarray | None = None
    half_track_scale: np.ndarray | None = None
    materials: np.ndarray | None = None

    def __post_init__(self) -> None:
        eta = np.asarray(self.eta, dtype=np.float64)
        if eta.ndim != 2 or min(eta.shape) < 1:
            raise ValueError(f"expected eta of shape (regions_x, regions_y), got {eta.shape}")
        if not np.all(np.isfinite(eta)) or np.any(eta < 0):
            raise ValueError("expected eta finite and >= 0 in every region")
        for name in ("x_icr", "drift_phase"):
            value = np.asarray(getattr(self, name), dtype=np.float64)
            if value.shape != eta.shape:
                raise ValueError(f"expected {name} of shape {eta.shape}, got {value.shape}")
            if not np.all(np.isfinite(value)):
                raise ValueError(f"expected {name} finite in every region")
            object.__setattr__(self, name, value)
        self._check_floor(eta.shape)
        object.__setattr__(self, "eta", eta)
        check_number("drift_amplitude", self.drift_amplitude, 0.0, MAX_DRIFT_AMPLITUDE, closed=True)
        check_number("drift_period", self.drift_period, 0.0, MAX_DRIFT_PERIOD)

    def _check_floor(self, shape: tuple[int, ...]) -> None:
        """Validate (and store as arrays) the optional scales and materials."""
        for name in ("wheel_radius_scale", "half_track_scale"):
            if getattr(self, name) is not None:
                value = np.asarray(getattr(self, name), dtype=np.float64)
                if value.shape != shape:
                    raise ValueError(f"expected {name} of shape {shape}, got {value.shape}")
                if not np.all(np.isfinite(value)) or np.any(value <= 0):
                    raise ValueError(f"expected {name} finite and > 0 in every region")
                object.__setattr__(self, name, value)
        if self.materials is not None:
            names = np.asarray(self.materials, dtype=object)
            if names.shape != shape or not all(isinstance(n, str) for n in names.flat):
                raise ValueError(f"expected materials as names of shape {shape}")
            object.__setattr__(self, "materials", names)

    @property
    def shape(self) -> tuple[int, int]:
        """(regions_x, regions_y)."""
        return (int(self.eta.shape[0]), int(self.eta.shape[1]))

    @property
    def drifting(self) -> bool:
        """True when η changes with time."""
        return self.drift_amplitude > 0

    def eta_at(self, time: float) -> np.ndarray:
        """η of every region at simulated time ``time`` [s], shape (regions_x, regions_y)."""
        if not self.drifting:
            return self.eta.copy()
        factor = 1.0 + self.drift_amplitude * np.sin(
            2.0 * math.pi * time / self.drift_period + self.drift_phase
        )
        return self.eta * np.maximum(factor, 0.0)

    def wheel_speed_variance(self, time: float = 0.0) -> np.ndarray:
        """True variance of a wheel's speed per region, η²/12 [rad²/s²]."""
        return self.eta_at(time) ** 2 / 12.0

    def check_x_icr(self, robot: RobotParams) -> None:
        """Raise ValueError unless x_ICR lies in [−a, b] (front and rear axle of ``robot``) in
        every region, as the ICR model requires (Kozłowski & Pazderski 2004).

        >>> field = SlipField(eta=np.zeros((2, 2)), x_icr=np.array([[0.0, 0.05], [0.2, -0.01]]),
        ...                   drift_phase=np.zeros((2, 2)))
        >>> field.check_x_icr(RobotParams())  # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        ValueError: expected x_icr in [-a, b] = [-0.05, 0.05] m in every region, got 0.2 m ...
        """
        low, high = -robot.front_axle, robot.rear_axle
        outside = np.argwhere((self.x_icr < low) | (self.x_icr > high))
        if len(outside):
            i, j = (int(v) for v in outside[0])
            more = f" and {len(outside) - 1} more regions" if len(outside) > 1 else ""
            raise ValueError(
                f"expected x_icr in [-a, b] = [{low:g}, {high:g}] m in every region, "
                f"got {self.x_icr[i, j]:g} m in region ({i}, {j}){more}"
            )

    def kernel_arrays(
        self, robot: RobotParams
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(eta, x_icr, wheel_radius, half_track, drift_phase) of ``robot`` on this floor, each
        flattened to shape (regions_x·regions_y,), region-major in x, for the compiled kernels
        (wheel radius and half track in metres: the robot's times the field's scales)."""
        ones = np.ones_like(self.eta)
        radius = self.wheel_radius_scale if self.wheel_radius_scale is not None else ones
        track = self.half_track_scale if self.half_track_scale is not None else ones
        return (
            np.ascontiguousarray(self.eta.ravel()),
            np.ascontiguousarray(self.x_icr.ravel()),
            np.ascontiguousarray(robot.wheel_radius * radius.ravel()),
            np.ascontiguousarray(robot.half_track * track.ravel()),
            np.ascontiguousarray(self.drift_phase.ravel()),
        )

    def expected_velocities(self, robot: RobotParams, samples: int = 256) -> np.ndarray:
        """The floor's true expected body velocities of every region and discrete action:
        :func:`~skidnav.robot.kinematics.expected_body_velocities` of the action's commanded
        wheel speeds with the region's η, x_ICR, r and c (:meth:`kernel_arrays`). A drifting
        field gives their average over one drift period (``samples`` evenly spaced times): the
        best stationary model of it.

        Returns:
            float64 (regions_x·regions_y, N_ACTIONS, 3): (v_x [m/s], v_y [m/s], yaw_rate
            [rad/s]), regions flat as :meth:`kernel_arrays`.

        >>> field = SlipField(eta=np.full((1, 1), 0.34), x_icr=np.full((1, 1), 0.05),
        ...                   drift_phase=np.zeros((1, 1)))
        >>> [round(float(v), 5) for v in field.expected_velocities(RobotParams())[0, 2]]  # left
        [0.0, -0.02869, 0.57375]
        """
        _, x_icr, radius, track, _ = self.kernel_arrays(robot)
        times = np.arange(samples) * (self.drift_period / samples) if self.drifting else [0.0]
        total = np.zeros((x_icr.size, N_ACTIONS, 3))
        for time in times:
            eta = np.ascontiguousarray(self.eta_at(time).ravel())
            _add_expected_velocities(eta, x_icr, radius, track, robot.wheel_speed, total)
        return total / len(times)


@jit
def _add_expected_velocities(
    eta: np.ndarray,
    x_icr: np.ndarray,
    wheel_radius: np.ndarray,
    half_track: np.ndarray,
    wheel_speed: float,
    total: np.ndarray,
) -> None:
    """Add the expected body velocities of every flat region and action (float64 (n_regions,)
    inputs as :meth:`SlipField.kernel_arrays`; ``wheel_speed`` [rad/s]) to ``total``, float64
    (n_regions, N_ACTIONS, 3)."""
    for region in range(eta.shape[0]):
        for action in range(total.shape[1]):
            omega_left, omega_right = commanded_wheel_speeds(action, wheel_speed)
            twist = expected_body_velocities(
                omega_left, omega_right, eta[region], x_icr[region], wheel_radius[region],
                half_track[region],
            )  # fmt: skip
            for k in range(3):
                total[region, action, k] += twist[k]


def make_slip_field(
    preset: str,
    rng: np.random.Generator,
    *,
    regions: tuple[int, int] = (7, 7),
    drift_amplitude: float = 0.0,
    drift_period: float = 600.0,
    robot: RobotParams | None = None,
) -> SlipField:
    """Build a slip field from a named preset.

    Presets:
        ``thesis``: η = (i + j)/1000 rad/s in region (i, j) (under 1 % of the 1.7 rad/s wheel speed:
        almost no slip) and the nominal x_ICR everywhere, as the thesis's simulation.
        ``slippery``: η = 0.3 rad/s everywhere and 3–5 seeded patches of one region with
        η = 1.7 rad/s (up to 100 %, on average 50 % of wheel speed lost there); x_ICR drawn
        per region in [0, b] (shifted towards the centre).
        ``rough``: high friction, η = 0.05 rad/s (at most 3 % loss), nominal x_ICR.
        ``nominal``: the datasheet robot: η = 0 and the nominal x_ICR everywhere.
        ``rough-physics``, ``slippery-physics``: the floors of ``rough`` and ``slippery`` made of
        their materials (:data:`~skidnav.robot.floors.PRESET_FLOORS`: rubber mat; laminate with
        the same seeded wet-tile patches as ``slippery``), each region with its material's
        calibrated η, x_ICR and effective r and c (:mod:`skidnav.robot.floors`);
        ``ice-physics``: ice everywhere, calibrated likewise ("BARN on ice" for the Jackal). A
        calibrated preset takes the floors fitted on ``robot``'s build (the Jackal's for the
        Jackal, the thesis robot's otherwise).

    Args:
        preset: one of :data:`SLIP_PRESETS`.
        rng: draws the patches, x_ICR and drift phases.
        regions: (regions_x, regions_y).
        drift_amplitude, drift_period: see :class:`SlipField`.
        robot: for the nominal x_ICR and its bounds (defaults to the thesis robot).
    """
    robot = robot or RobotParams()
    shape = regions
    ii, jj = np.meshgrid(np.arange(shape[0]), np.arange(shape[1]), indexing="ij")
    x_icr = np.full(shape, robot.x_icr)
    if preset == "thesis":
        eta = (ii + jj) / 1000.0
    elif preset == "slippery":
        eta = np.full(shape, 0.3)
        eta.ravel()[_patches(rng, shape)] = robot.wheel_speed
        x_icr = rng.uniform(0.0, robot.rear_axle, size=shape)
    elif preset == "rough":
        eta = np.full(shape, 0.05)
    elif preset == "nominal":
        eta = np.zeros(shape)
    elif preset in CALIBRATED_PRESETS:
        return _calibrated_field(preset, rng, shape, (drift_amplitude, drift_period), robot)
    else:
        raise ValueError(f"expected slip preset one of {', '.join(SLIP_PRESETS)}, got {preset!r}")
    phase = rng.uniform(0.0, 2.0 * math.pi, size=shape)
    return SlipField(
        eta=eta,
        x_icr=x_icr,
        drift_amplitude=drift_amplitude,
        drift_period=drift_period,
        drift_phase=phase,
    )


def _patches(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    """Flat indices of 3–5 distinct seeded regions: the patches of a slippery floor."""
    n_patches = int(rng.integers(3, 6))
    return rng.choice(shape[0] * shape[1], size=n_patches, replace=False)


def _calibrated_field(
    preset: str,
    rng: np.random.Generator,
    shape: tuple[int, int],
    drift: tuple[float, float],
    robot: RobotParams,
) -> SlipField:
    """A field of :data:`~skidnav.robot.floors.CALIBRATED_PRESETS`: the preset's materials
    (patches drawn as for ``slippery``), each region with its material's floor calibrated on
    ``robot``'s build; ``drift`` = (amplitude, period [s])."""
    floor, patch = PRESET_FLOORS[preset]
    names = np.full(shape, floor, dtype=object)
    if patch is not None:
        names.ravel()[_patches(rng, shape)] = patch
    fits = [calibrated_floor(str(name), robot) for name in names.flat]
    built = calibrated_robot(robot)
    scales = np.array([fit.scales(built) for fit in fits]).reshape(*shape, 2)
    return SlipField(
        eta=np.array([fit.simulated_eta(built) for fit in fits]).reshape(shape),
        x_icr=np.array([fit.x_icr for fit in fits]).reshape(shape),
        drift_amplitude=drift[0],
        drift_period=drift[1],
        drift_phase=rng.uniform(0.0, 2.0 * math.pi, size=shape),
        wheel_radius_scale=scales[..., 0],
        half_track_scale=scales[..., 1],
        materials=names,
    )
