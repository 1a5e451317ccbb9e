"""ROS 2 messages as rosbridge JSON dicts: twists out, poses and tf transforms in (docs/ros2.md).

Pure functions, no connection: the driver in ``skidnav.realtime.link.ros2`` calls them. Every reader
checks each field it uses (type, range, finiteness) and raises ``ValueError`` with a one-line
reason, so a malformed message can be refused without a traceback. Wheel speeds become a body
twist through the skid-steer differential-drive relations (Kozłowski & Pazderski 2004, eq. 2 with
the ICR slip ignored): v = r(ω_R + ω_L)/2, yaw rate = r(ω_R − ω_L)/(2c).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, TypeGuard

from skidnav.robot.kinematics import wrap_angle
from skidnav.robot.params import RobotParams

TWIST = "geometry_msgs/Twist"
TWIST_STAMPED = "geometry_msgs/TwistStamped"
TF_MESSAGE = "tf2_msgs/TFMessage"
POSE_TYPES = (
    "nav_msgs/Odometry",
    "geometry_msgs/PoseStamped",
    "geometry_msgs/PoseWithCovarianceStamped",
    TF_MESSAGE,
)
ZERO_STAMP: Mapping[str, int] = {"sec": 0, "nanosec": 0}
NANOSECONDS = 1_000_000_000
INT32_LIMIT = 2**31  # builtin_interfaces/Time.sec is an int32


def canonical_type(name: str) -> str:
    """``"pkg/msg/Type"`` (ROS 2 spelling) → ``"pkg/Type"``; ``"pkg/Type"`` is returned as is."""
    parts = name.split("/")
    return f"{parts[0]}/{parts[2]}" if len(parts) == 3 and parts[1] == "msg" else name


def wheel_speeds_to_twist(
    omega_left: float, omega_right: float, params: RobotParams
) -> dict[str, dict[str, float]]:
    """``geometry_msgs/Twist`` (as a dict) for wheel angular speeds ω_L, ω_R [rad/s].

    linear.x = r(ω_R + ω_L)/2 [m/s], angular.z = r(ω_R − ω_L)/(2c) [rad/s]; other fields 0.

    >>> wheel_speeds_to_twist(1.0, 1.0, RobotParams())["linear"]["x"]
    0.0225
    """
    radius, half_track = params.wheel_radius, params.half_track
    return {
        "linear": {"x": radius * (omega_right + omega_left) / 2, "y": 0.0, "z": 0.0},
        "angular": {
            "x": 0.0,
            "y": 0.0,
            "z": radius * (omega_right - omega_left) / (2 * half_track),
        },
    }


def ros_time(seconds: float) -> dict[str, int]:
    """``builtin_interfaces/Time`` {sec, nanosec} of a time [s since the Unix epoch], rounded to
    the nearest nanosecond.

    >>> ros_time(1700000000.25)
    {'sec': 1700000000, 'nanosec': 250000000}
    """
    sec = math.floor(seconds)
    # The fraction first: seconds × 10⁹ itself would be past float64's 2⁵³ exact integers.
    carry, nanosec = divmod(round((seconds - sec) * NANOSECONDS), NANOSECONDS)
    return {"sec": sec + carry, "nanosec": nanosec}


def twist_stamped(
    twist: Mapping[str, Any], stamp: Mapping[str, int], frame_id: str
) -> dict[str, Any]:
    """``geometry_msgs/TwistStamped`` (as a dict): ``twist`` with a header {stamp, frame_id}."""
    return {"header": {"stamp": dict(stamp), "frame_id": frame_id}, "twist": dict(twist)}


def seconds_from_stamp(stamp: object) -> float:
    """A ``builtin_interfaces/Time`` {sec, nanosec} as seconds [s on the stamping clock].

    Raises:
        ValueError: not a mapping, sec not an integer in [0, 2³¹) or nanosec not in [0, 10⁹).

    >>> seconds_from_stamp({"sec": 12, "nanosec": 500000000})
    12.5
    """
    if not isinstance(stamp, Mapping):
        raise ValueError(f"expected a header stamp {{sec, nanosec}}, got {_short(stamp)}")
    sec, nanosec = stamp.get("sec"), stamp.get("nanosec")
    if not (_is_integer(sec) and 0 <= sec < INT32_LIMIT):
        raise ValueError(f"expected stamp sec an integer in [0, 2^31), got {_short(sec)}")
    if not (_is_integer(nanosec) and 0 <= nanosec < NANOSECONDS):
        raise ValueError(f"expected stamp nanosec an integer in [0, 10^9), got {_short(nanosec)}")
    return sec + nanosec / NANOSECONDS


def header_seconds(message: object) -> float:
    """The ``header.stamp`` of a stamped message, in seconds (see :func:`seconds_from_stamp`)."""
    return seconds_from_stamp(_field(message, "header.stamp"))


def heading_from_quaternion(x: float, y: float, z: float, w: float) -> float:
    """Heading [rad, (-π, π]] of a quaternion: its yaw, the rotation about +z (ZYX Euler angles),
    counter-clockwise from +x. Any non-zero scale is accepted (the quaternion is normalised).

    >>> round(heading_from_quaternion(0.0, 0.0, math.sin(0.25), math.cos(0.25)), 6)
    0.5
    >>> round(heading_from_quaternion(0.0, 0.0, 2.0, 2.0), 6)  # not normalised: still π/2
    1.570796

    Raises:
        ValueError: a zero or non-finite quaternion.
    """
    scale = max(abs(x), abs(y), abs(z), abs(w))
    if not (math.isfinite(scale) and scale > 0):
        raise ValueError(f"expected a finite non-zero quaternion, got {(x, y, z, w)}")
    x, y, z, w = x / scale, y / scale, z / scale, w / scale  # |q| in [1, 2]: no overflow
    # For a unit quaternion w² + x² − y² − z² = 1 − 2(y² + z²); this form is scale-invariant.
    return math.atan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z)


def pose_from_message(message: object, pose_type: str) -> tuple[float, float, float]:
    """(x [m], y [m], heading [rad]) in the message's frame from an Odometry, PoseStamped or
    PoseWithCovarianceStamped dict (tf messages: :func:`select_transform`).

    Raises:
        ValueError: a missing field, a non-number, a non-finite number or a zero quaternion.
    """
    # Odometry and PoseWithCovarianceStamped nest the pose beside its covariance.
    nested = canonical_type(pose_type) != "geometry_msgs/PoseStamped"
    pose = "pose.pose" if nested else "pose"
    return _planar(message, f"{pose}.position", f"{pose}.orientation")


def select_transform(message: object, parent: str, child: str) -> Mapping[str, Any] | None:
    """The last ``geometry_msgs/TransformStamped`` of a ``tf2_msgs/TFMessage`` dict from frame
    ``parent`` to frame ``child`` (a leading ``/`` on the message's frame ids is ignored), or
    None if the message holds no such transform (tf carries every frame of the robot).

    Raises:
        ValueError: ``transforms`` is not a list, or an entry is not a transform with frame ids.
    """
    transforms = _field(message, "transforms")
    if not isinstance(transforms, list):
        raise ValueError(f"expected a list of transforms, got {_short(transforms)}")
    found = None
    for transform in transforms:
        frames = (_field(transform, "header.frame_id"), _field(transform, "child_frame_id"))
        if not all(isinstance(frame, str) for frame in frames):
            raise ValueError(f"expected string frame ids, got {_short(frames)}")
        if tuple(frame.lstrip("/") for frame in frames) == (parent, child):
            found = transform
    return found


def pose_from_transform(transform: object) -> tuple[float, float, float]:
    """(x [m], y [m], heading [rad]) of a ``geometry_msgs/TransformStamped`` dict: the child
    frame's origin and yaw in the parent frame.

    Raises:
        ValueError: as :func:`pose_from_message`.
    """
    return _planar(transform, "transform.translation", "transform.rotation")


def compose(
    offset: tuple[float, float, float], pose: tuple[float, float, float]
) -> tuple[float, float, float]:
    """``offset ⊕ pose``: a pose in a frame placed at ``offset``, expressed in the outer frame."""
    ox, oy, oh = offset
    x, y, heading = pose
    cos_h, sin_h = math.cos(oh), math.sin(oh)
    total = oh + heading
    return (
        ox + cos_h * x - sin_h * y,
        oy + sin_h * x + cos_h * y,
        wrap_angle(total),
    )


def _planar(message: object, position: str, orientation: str) -> tuple[float, float, float]:
    """(x, y, heading) from the fields at the paths ``position`` (a point or translation) and
    ``orientation`` (a quaternion) of ``message``."""
    x, y = (_number(_field(message, f"{position}.{k}"), f"{position}.{k}") for k in "xy")
    quaternion = [
        _number(_field(message, f"{orientation}.{k}"), f"{orientation}.{k}") for k in "xyzw"
    ]
    return x, y, heading_from_quaternion(*quaternion)


def _field(message: object, path: str) -> Any:
    """``message[a][b]…`` for ``path = "a.b…"``; ValueError naming the path if absent."""
    value = message
    for key in path.split("."):
        if not isinstance(value, Mapping) or key not in value:
            raise ValueError(f"missing field {path}")
        value = value[key]
    return value


def _number(value: object, name: str) -> float:
    """``value`` as a finite float; ValueError for non-numbers (bools and strings included), huge
    integers and non-finite values."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"expected a number for {name}, got {_short(value)}")
    try:
        number = float(value)
    except OverflowError:
        raise ValueError(f"expected a finite {name}, got an integer out of range") from None
    if not math.isfinite(number):
        raise ValueError(f"expected a finite {name}, got {number}")
    return number


def _is_integer(value: object) -> TypeGuard[int]:
    return isinstance(value, int) and not isinstance(value, bool)


def _short(value: object, limit: int = 40) -> str:
    """``repr(value)`` cut to ``limit`` characters, for one-line messages."""
    if isinstance(value, int) and abs(value) >= 10**limit:
        return f"an integer of {value.bit_length()} bits"
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"
