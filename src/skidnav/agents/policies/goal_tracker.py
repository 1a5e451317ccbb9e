"""A reference continuous policy: proportional tracking of the goal on the feature observation.

The goal tracker reads only the goal's distance d [m] and bearing β (cos β, sin β) of the
``"features"`` observation (:mod:`skidnav.sim.features`) and ignores the lidar ranges: like the
discrete goal-seeker of :mod:`skidnav.studies.generalisation`, what it achieves on a map measures
how open the straight line from start to goal is, not what a policy can learn. It meets
:class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy`, so it runs wherever a learned
continuous policy does (the continuous env, ``skidnav robot run --policy goal-tracker``).

The control law, a proportional point-stabilising controller in the spirit of the kinematic
position control of a unicycle (Siegwart, Nourbakhsh & Scaramuzza (2011), *Introduction to
Autonomous Mobile Robots*, 2nd ed., ch. 3), in sin/cos form, without a final-heading term, and
with the turn's sign adapted to the skid:

    speed     v = k_d · d · cos β                        (backwards to a goal behind)
    yaw rate  ψ̇ = σ · k_ψ · sin β,   σ = +1 if d cos β > x_ICR, else −1

Why σ: a skid-steer robot turns about its pivot point, x_ICR ahead of the body centre (the ICR
model's v_y = −x_ICR ψ̇). With (e_x, e_y) = (d cos β, d sin β) the goal in the body frame, the
model gives ė_y = ψ̇ (x_ICR − e_x): turning towards the goal shrinks the lateral error only while
the goal lies ahead of the pivot (e_x > x_ICR); nearer, or behind, the slide of the centre
carries it away. So the tracker turns towards a goal ahead of the pivot and away from any other,
and |e_y| never grows; a goal behind is reached backwards instead of by turning in place (which
would swing the centre on a circle of radius x_ICR, into any wall nearby). Plain sin β steering
circles a goal about x_ICR away when actions are short (0.1 s). x_ICR is the nominal
``robot.x_icr``; a floor that moves the pivot only shifts the switch.

The twist (v, ψ̇) becomes wheel speeds by inverting the skid-steer ICR model
(:func:`skidnav.robot.kinematics.body_velocities`): ω_R = (v + c ψ̇)/r, ω_L = (v − c ψ̇)/r. Both
must stay within ± ``wheel_speed`` Ω, i.e. |v| + c |ψ̇| ≤ r Ω: the turn has priority (ψ̇ is
limited to ± r Ω / c, then |v| to what the wheels have left), so a far goal does not flatten the
turn towards it, and the result is clipped to ± Ω against rounding. On the free maps of worlds
0–29 it reaches the goal from every start without a collision, with 1 s actions (at most 18)
and with 0.1 s ones (tests/agents/test_goal_tracker.py tests a few).

>>> import numpy as np
>>> tracker = GoalTracker()
>>> ahead = np.array([0.1, 0.1, 1.0, 0.0, 0.02, 1.0, 0.0] + [0.3] * 8)  # goal 2 cm straight ahead
>>> [round(w, 4) for w in tracker.wheel_speeds(ahead)]
[0.8889, 0.8889]
>>> behind = ahead.copy(); behind[5:7] = (-1.0, 0.0)  # the goal 2 cm behind: reverse
>>> [round(w, 4) for w in tracker.wheel_speeds(behind)]
[-0.8889, -0.8889]
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from skidnav.checks import check_number
from skidnav.files.configtables import build_dataclass
from skidnav.robot.params import RobotParams
from skidnav.sim.features import POSE_GOAL_NAMES, check_lidar

POLICY_NAME = "goal-tracker"

_DISTANCE = POSE_GOAL_NAMES.index("goal_distance")
_COS_BEARING = POSE_GOAL_NAMES.index("goal_cos_bearing")
_SIN_BEARING = POSE_GOAL_NAMES.index("goal_sin_bearing")


@dataclass(frozen=True)
class GoalTrackerConfig:
    """Gains of the goal tracker and the observation it reads, validated on construction.

    Attributes:
        distance_gain: k_d [1/s], forward speed per metre of goal distance (before the wheel
            limit); 1 /s covers the remaining distance in one 1 s action, where the limit allows.
        turn_gain: k_ψ [rad/s], yaw rate per unit of sin β; 1 rad/s turns a small bearing away
            in one 1 s action (at most r Ω / c = 0.64 rad/s on the thesis robot).
        lidar_rays: range readings k of the observations it is given (read past, not used).
        lidar_range: their largest reading [m] (not used).
    """

    distance_gain: float = 1.0
    turn_gain: float = 1.0
    lidar_rays: int = 8
    lidar_range: float = 0.3

    def __post_init__(self) -> None:
        for name in ("distance_gain", "turn_gain"):
            check_number(name, getattr(self, name), 0.0)
        check_lidar(self.lidar_rays, self.lidar_range)

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any]) -> GoalTrackerConfig:
        """The config of a mapping of its fields (a TOML table, a saved tracker's JSON);
        ValueError in one line for an unknown key or a bad value."""
        return build_dataclass(cls, values, "goal-tracker")


class GoalTracker:
    """The goal-tracking controller of the module doc, a
    :class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy`.

    Args:
        config: gains and observation layout (defaults: :class:`GoalTrackerConfig`).
        robot: wheel radius r, half track c, nominal x_ICR and wheel-speed limit Ω (default:
            the thesis robot).
    """

    name = POLICY_NAME

    def __init__(
        self, config: GoalTrackerConfig | None = None, robot: RobotParams | None = None
    ) -> None:
        self.config = config or GoalTrackerConfig()
        self.robot = robot or RobotParams()
        self.lidar_rays = self.config.lidar_rays
        self.lidar_range = self.config.lidar_range

    def twist(self, observation: np.ndarray) -> tuple[float, float]:
        """(v [m/s], ψ̇ [rad/s]) within the wheels' reach, for a feature observation float64
        (7 + k,); ValueError for one of another shape or with non-finite goal features."""
        values = np.asarray(observation, dtype=np.float64)
        if values.shape != (7 + self.lidar_rays,):
            raise ValueError(
                f"expected an observation of shape ({7 + self.lidar_rays},), got {values.shape}"
            )
        distance, cos_bearing, sin_bearing = values[[_DISTANCE, _COS_BEARING, _SIN_BEARING]]
        if not np.isfinite([distance, cos_bearing, sin_bearing]).all():
            raise ValueError("expected finite goal distance and bearing")
        # towards the goal if it lies ahead of the pivot point, away from it otherwise
        turn_sign = 1.0 if distance * cos_bearing > self.robot.x_icr else -1.0
        r, c, limit = self.robot.wheel_radius, self.robot.half_track, self.robot.wheel_speed
        reach = r * limit  # the largest |v| + c |ψ̇| [m/s] the wheels allow
        yaw_rate = _clip(self.config.turn_gain * turn_sign * sin_bearing, reach / c)
        speed = _clip(self.config.distance_gain * distance * cos_bearing, reach - c * abs(yaw_rate))
        return speed, yaw_rate

    def wheel_speeds(self, observation: np.ndarray) -> tuple[float, float]:
        """(ω_L, ω_R) [rad/s] within ± ``robot.wheel_speed``, for a feature observation (see
        :meth:`twist`)."""
        speed, yaw_rate = self.twist(observation)
        r, c, limit = self.robot.wheel_radius, self.robot.half_track, self.robot.wheel_speed
        left, right = (speed - c * yaw_rate) / r, (speed + c * yaw_rate) / r
        return _clip(left, limit), _clip(right, limit)


def _clip(value: float, limit: float) -> float:
    """``value`` clipped to [−limit, limit], as a Python float."""
    return float(min(max(value, -limit), limit))
