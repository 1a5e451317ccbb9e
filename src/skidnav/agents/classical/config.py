"""Settings of the ``classical`` navigator: one frozen dataclass, validated on construction.

>>> ClassicalConfig().horizon
1.5
>>> ClassicalConfig(cost_scaling=-1.0)
Traceback (most recent call last):
...
ValueError: expected cost_scaling to be a finite number in [0, 100], got -1.0
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any

from skidnav.checks import check_integer, check_number
from skidnav.files.configtables import build_dataclass

MAX_SAMPLES = 101
"""Most speed or yaw-rate levels of the controller's grid."""
MAX_LENGTH = 100.0
"""Greatest length [m] or duration [s] of any setting: beyond any arena or horizon here."""
MAX_WEIGHT = 1e6
"""Greatest weight of a cost term."""
MAX_ACCELERATION = 1e4
"""Greatest acceleration [m/s² or rad/s²] of the dynamic window: far beyond any robot's."""


@dataclass(frozen=True)
class ClassicalConfig:
    """The global planner's and the local controller's settings (docs/agents/classical.md).

    The controller's score is in seconds: the global cost-to-go D [m] over the top speed
    sampled, and every other term weighed against it; so the same weights serve a robot of
    2 m/s and one of 4 cm/s.
    """

    inflation_radius: float = 0.55
    """How far [m] from an obstacle's surface the inflation cost reaches (Nav2's default),
    ≥ 0."""
    cost_scaling: float = 10.0
    """k [1/m] of the inflation cost exp(−k (d − r_in)) at a distance d beyond the footprint's
    inscribed radius r_in (Nav2's ``cost_scaling_factor``), ≥ 0."""
    inflation_weight: float = 3.0
    """Cells of path that entering a cell of inflation cost 1 adds to the cost-to-go (in cell
    sides, the smaller one), ≥ 0."""
    footprint_length: float | None = None
    """The rectangle's length along the heading [m], ≥ 0; None: the robot's
    ``footprint_length`` (0, a point, for a robot without one)."""
    footprint_width: float | None = None
    """Its width across the heading [m], ≥ 0; None: the robot's ``footprint_width``."""
    footprint_padding: float = 0.02
    """Margin [m] added to each side of the footprint in the controller's collision check and
    to the inscribed radius of the inflation, ≥ 0."""
    max_speed: float | None = None
    """Greatest forward speed sampled [m/s]; None: the datasheet's top speed r Ω."""
    reverse_speed: float = 0.3
    """Speed [m/s] of the one backwards level sampled (0: none), ≥ 0."""
    max_yaw_rate: float = 4.0
    """Greatest yaw rate sampled [rad/s], > 0 (capped by the datasheet's r Ω / c)."""
    speed_samples: int = 9
    """Forward speed levels from 0 to ``max_speed``, in [2, 101]."""
    yaw_rate_samples: int = 21
    """Yaw-rate levels from −``max_yaw_rate`` to ``max_yaw_rate``, odd (0 among them), in
    [3, 101]."""
    horizon: float = 1.5
    """How long [s] each sampled command is rolled out, > 0."""
    rollout_step: float = 0.05
    """Time [s] between the rollout's footprint checks, in (0, ``horizon``]."""
    acceleration: float | None = None
    """a [m/s²]: the forward speeds searched are those within a T of the current speed, T the
    control period (Fox et al.'s dynamic window; the speed measured from the robot's own
    poses), > 0; None: a robot that takes any command at once, whose window is the whole
    range."""
    yaw_acceleration: float | None = None
    """α [rad/s²]: the yaw rates searched are those within α T of the current yaw rate, > 0;
    None: the whole range."""
    half_track: float | None = None
    """The half track c [m] the controller's model turns with, > 0; None: the datasheet's. A
    skid-steer robot's tyres scrub, and it turns as a wider robot would (Mandow et al. 2007):
    its effective half track, measured by driving it."""
    stuck_time: float = 2.0
    """How long [s] the progress check looks back (0: no check), ≥ 0."""
    stuck_speed: float = 0.05
    """The robot is stuck when, over ``stuck_time``, it moved less than this fraction of what
    ``max_speed`` would cover, in [0, 1]; then the recovery runs."""
    recovery_time: float = 1.0
    """How long [s] the recovery runs once the robot is stuck, > 0 (at least one period)."""
    deceleration: float = 2.5
    """a_b [m/s²]: a command is admissible if the robot, holding it for a control period and
    then braking at a_b, stops before its rollout's first collision (Fox et al. 1997), > 0."""
    heading_weight: float = 0.15
    """Seconds per radian of the end heading's angle to the route ``lookahead`` ahead, ≥ 0."""
    obstacle_weight: float = 0.25
    """Seconds per unit of the greatest inflation cost along a rollout, ≥ 0."""
    speed_weight: float = 0.1
    """Seconds per unit of the speed deficit 1 − v / ``max_speed``, ≥ 0."""
    lookahead: float = 1.0
    """How far along the global route [m] the heading term aims, ≥ 0."""
    ray_stride: int = 1
    """Read every ``ray_stride``-th lidar ray into the map (1: all), in [1, 1024]."""

    def __post_init__(self) -> None:
        for name in ("inflation_radius", "cost_scaling", "inflation_weight", "footprint_padding",
                     "reverse_speed", "lookahead"):  # fmt: skip
            check_number(name, getattr(self, name), 0.0, MAX_LENGTH, closed=True)
        for name in ("heading_weight", "obstacle_weight", "speed_weight"):
            check_number(name, getattr(self, name), 0.0, MAX_WEIGHT, closed=True)
        for name in ("footprint_length", "footprint_width"):
            if getattr(self, name) is not None:
                check_number(name, getattr(self, name), 0.0, MAX_LENGTH, closed=True)
        if self.max_speed is not None:
            check_number("max_speed", self.max_speed, 0.0, MAX_LENGTH)
        for name in ("acceleration", "yaw_acceleration"):
            if getattr(self, name) is not None:
                check_number(name, getattr(self, name), 0.0, MAX_ACCELERATION)
        if self.half_track is not None:
            check_number("half_track", self.half_track, 0.0, MAX_LENGTH)
        check_number("stuck_time", self.stuck_time, 0.0, MAX_LENGTH, closed=True)
        check_number("stuck_speed", self.stuck_speed, 0.0, 1.0, closed=True)
        check_number("recovery_time", self.recovery_time, 0.0, MAX_LENGTH)
        check_number("max_yaw_rate", self.max_yaw_rate, 0.0, MAX_LENGTH)
        check_number("horizon", self.horizon, 0.0, MAX_LENGTH)
        check_number("deceleration", self.deceleration, 0.0, MAX_LENGTH)
        check_number("rollout_step", self.rollout_step, 0.0, self.horizon)
        check_integer("speed_samples", self.speed_samples, 2, MAX_SAMPLES)
        check_integer("yaw_rate_samples", self.yaw_rate_samples, 3, MAX_SAMPLES)
        if self.yaw_rate_samples % 2 == 0:
            raise ValueError(f"expected yaw_rate_samples to be odd, got {self.yaw_rate_samples}")
        check_integer("ray_stride", self.ray_stride, 1, 1024)

    def to_dict(self) -> dict[str, Any]:
        """Every field, JSON-able (read back by :meth:`from_mapping`)."""
        return asdict(self)

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any]) -> ClassicalConfig:
        """The config of a mapping of its fields (a TOML table, a saved agent's JSON);
        UserError in one line for an unknown key or a bad value."""
        return build_dataclass(cls, values, "params")
