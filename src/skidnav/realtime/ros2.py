"""ROS 2 robot driver over rosbridge (roslibpy): ``/cmd_vel`` Twist out, pose or odometry in.

The robot runs ROS 2 with ``rosbridge_server`` (rosbridge v2 JSON protocol over a WebSocket,
default port 9090); this driver is a rosbridge client (docs/ros2.md). Wheel speeds become a body
twist through the skid-steer differential-drive relations (Kozłowski & Pazderski 2004, eq. 2 with
the ICR slip ignored): v = r(ω_R + ω_L)/2, yaw rate = r(ω_R − ω_L)/(2c).

roslibpy's default transport runs the Twisted reactor in one background thread that lives for the
whole process and cannot be restarted once stopped, so this driver never stops it: connecting and
closing any number of drivers in one process only opens and closes WebSocket connections.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import roslibpy

from skidnav.realtime.driver import Pose
from skidnav.robot.params import RobotParams

LOGGER = logging.getLogger(__name__)

POSE_TYPES = (
    "nav_msgs/Odometry",
    "geometry_msgs/PoseStamped",
    "geometry_msgs/PoseWithCovarianceStamped",
)


def canonical_type(name: str) -> str:
    """``"pkg/msg/Type"`` (ROS 2 spelling) → ``"pkg/Type"``; ``"pkg/Type"`` is returned as is."""
    parts = name.split("/")
    return f"{parts[0]}/{parts[2]}" if len(parts) == 3 and parts[1] == "msg" else name


@dataclass(frozen=True)
class Ros2Config:
    """Where the rosbridge server is and which topics to use.

    Attributes:
        host: rosbridge host (default loopback; a robot on the network is named explicitly).
        port: rosbridge WebSocket port.
        cmd_vel_topic: topic of the ``geometry_msgs/Twist`` commands.
        pose_topic: topic of the robot pose.
        pose_type: message type of ``pose_topic``: ``nav_msgs/Odometry``,
            ``geometry_msgs/PoseStamped`` or ``geometry_msgs/PoseWithCovarianceStamped`` (the ROS 2
            spelling ``pkg/msg/Type`` is accepted too).
        frame_offset: (x [m], y [m], heading [rad]) of the ROS frame's origin in the arena frame;
            the arena pose is ``frame_offset ⊕ ros_pose`` (e.g. the start pose for odometry).
        connect_timeout: seconds to wait for the connection before ``ConnectionError``.
        send_timeout: seconds :meth:`Ros2Driver.stop` waits for the zero twist to be sent.
    """

    host: str = "127.0.0.1"
    port: int = 9090
    cmd_vel_topic: str = "/cmd_vel"
    pose_topic: str = "/odom"
    pose_type: str = "nav_msgs/Odometry"
    frame_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    connect_timeout: float = 5.0
    send_timeout: float = 1.0

    def __post_init__(self) -> None:
        if not self.host:
            raise ValueError("expected a rosbridge host, got an empty string")
        if not 0 < self.port < 65536:
            raise ValueError(f"expected port in [1, 65535], got {self.port}")
        for name in ("cmd_vel_topic", "pose_topic"):
            if not getattr(self, name).startswith("/"):
                raise ValueError(f"expected {name} starting with '/', got {getattr(self, name)!r}")
        if canonical_type(self.pose_type) not in POSE_TYPES:
            raise ValueError(f"expected pose_type in {POSE_TYPES}, got {self.pose_type!r}")
        if len(self.frame_offset) != 3 or not all(map(math.isfinite, self.frame_offset)):
            raise ValueError(
                f"expected a finite (x, y, heading) frame_offset, got {self.frame_offset}"
            )
        if not (self.connect_timeout > 0 and self.send_timeout > 0):
            raise ValueError(
                f"expected positive timeouts, got {self.connect_timeout} and {self.send_timeout}"
            )

    @property
    def url(self) -> str:
        """The rosbridge WebSocket address, for messages."""
        return f"ws://{self.host}:{self.port}"


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


def heading_from_quaternion(x: float, y: float, z: float, w: float) -> float:
    """Yaw [rad, (-π, π]] of a unit quaternion: rotation about +z (ZYX Euler convention).

    >>> round(heading_from_quaternion(0.0, 0.0, math.sin(0.25), math.cos(0.25)), 6)
    0.5
    """
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def pose_from_message(message: Mapping[str, Any], pose_type: str) -> tuple[float, float, float]:
    """(x [m], y [m], heading [rad]) in the ROS frame from a pose message dict.

    Raises:
        ValueError: the message lacks a field or holds a non-finite number.
    """
    try:
        pose = message["pose"]
        if canonical_type(pose_type) != "geometry_msgs/PoseStamped":
            pose = pose["pose"]  # Odometry and PoseWithCovarianceStamped nest the covariance
        position, orientation = pose["position"], pose["orientation"]
        x, y = float(position["x"]), float(position["y"])
        quaternion = [float(orientation[k]) for k in ("x", "y", "z", "w")]
    except (KeyError, TypeError) as error:
        raise ValueError(f"expected a {pose_type} message, missing {error}") from None
    if not all(map(math.isfinite, [x, y, *quaternion])) or not any(quaternion):
        raise ValueError(f"expected finite position and non-zero orientation, got {message}")
    return x, y, heading_from_quaternion(*quaternion)


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
        math.atan2(math.sin(total), math.cos(total)),
    )


class Ros2Driver:
    """A :class:`~skidnav.realtime.driver.RobotDriver` for a ROS 2 robot behind rosbridge.

    Args:
        config: server address, topics and timeouts.
        params: robot geometry for the wheel-speed → twist conversion.
        clock: monotonic clock [s] stamping each received pose (the ROS header stamp is on another
            clock and is ignored).

    Pose messages arrive on roslibpy's thread; :meth:`latest_pose` may be called from any thread.
    """

    def __init__(
        self,
        config: Ros2Config | None = None,
        params: RobotParams | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.config = config or Ros2Config()
        self.params = params or RobotParams()
        self.malformed_messages = 0
        self._clock = clock
        self._lock = threading.Lock()
        self._latest: Pose | None = None
        self._ros: roslibpy.Ros | None = None
        self._cmd_vel: roslibpy.Topic | None = None
        self._pose_topic: roslibpy.Topic | None = None

    @property
    def connected(self) -> bool:
        """Whether the WebSocket to rosbridge is open."""
        return self._ros is not None and bool(self._ros.is_connected)

    def connect(self) -> None:
        """Open the WebSocket, advertise the command topic and subscribe to the pose topic.

        Raises:
            ConnectionError: rosbridge not reachable within ``config.connect_timeout`` seconds.
        """
        if self._ros is not None:
            return
        config = self.config
        ros: roslibpy.Ros | None = None
        try:
            ros = roslibpy.Ros(host=config.host, port=config.port)
            ros.run(timeout=config.connect_timeout)
        except Exception:  # roslibpy raises RosTimeoutError, the transport may raise others
            if ros is not None:
                _abandon(ros)
            raise ConnectionError(
                f"cannot reach rosbridge at {config.url} within {config.connect_timeout:g} s"
            ) from None
        self._ros = ros
        self._cmd_vel = roslibpy.Topic(ros, config.cmd_vel_topic, "geometry_msgs/Twist")
        self._cmd_vel.advertise()
        self._pose_topic = roslibpy.Topic(ros, config.pose_topic, config.pose_type)
        self._pose_topic.subscribe(self._on_pose)
        LOGGER.info("connected to rosbridge at %s", config.url)

    def _on_pose(self, message: dict[str, Any]) -> None:
        try:
            ros_pose = pose_from_message(message, self.config.pose_type)
        except ValueError as error:
            self.malformed_messages += 1
            LOGGER.warning("ignored pose message on %s: %s", self.config.pose_topic, error)
            return
        x, y, heading = compose(self.config.frame_offset, ros_pose)
        with self._lock:
            self._latest = Pose(self._clock(), x, y, heading)

    def command(self, omega_left: float, omega_right: float) -> None:
        """Publish the twist for wheel speeds ω_L, ω_R [rad/s]; ``ConnectionError`` if unlinked."""
        if not (math.isfinite(omega_left) and math.isfinite(omega_right)):
            raise ValueError(f"expected finite wheel speeds, got {omega_left}, {omega_right}")
        if self._cmd_vel is None or not self.connected:
            raise ConnectionError(f"not connected to rosbridge at {self.config.url}")
        self._cmd_vel.publish(
            roslibpy.Message(wheel_speeds_to_twist(omega_left, omega_right, self.params))
        )

    def latest_pose(self) -> Pose | None:
        """The newest pose received (arena frame), or None if none yet."""
        with self._lock:
            return self._latest

    def stop(self) -> bool:
        """Publish a zero twist; True once it has been handed to the socket.

        rosbridge does not acknowledge publications, so "confirmed" means sent on an open link.
        """
        if self._ros is None or self._cmd_vel is None or not self.connected:
            return False
        self._cmd_vel.publish(roslibpy.Message(wheel_speeds_to_twist(0.0, 0.0, self.params)))
        return _flush(self._ros, self.config.send_timeout) and self.connected

    def close(self) -> None:
        """Stop the wheels (best effort), withdraw the topics and close the WebSocket."""
        ros = self._ros
        if ros is None:
            return
        if not self.stop():
            LOGGER.warning("could not send the stop command before closing")
        for topic, withdraw in ((self._pose_topic, "unsubscribe"), (self._cmd_vel, "unadvertise")):
            if topic is not None and self.connected:
                getattr(topic, withdraw)()
        _flush(ros, self.config.send_timeout)
        try:
            ros.close(timeout=self.config.send_timeout)
        except Exception as error:  # closing is best effort; the server drops us anyway
            LOGGER.warning("rosbridge close: %s", error)
        self._ros = self._cmd_vel = self._pose_topic = None

    def __enter__(self) -> Ros2Driver:
        self.connect()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def _flush(ros: roslibpy.Ros, timeout: float) -> bool:
    """Wait until everything queued on roslibpy's event loop before this call has run.

    Both roslibpy transports run queued calls in order, so once a marker scheduled now has run,
    every earlier ``send`` has been written to the socket.
    """
    done = threading.Event()
    ros.call_later(0, done.set)
    return done.wait(timeout)


def _abandon(ros: roslibpy.Ros) -> None:
    """Stop a failed connection from retrying forever in the background."""
    factory = ros.factory
    stop_trying = getattr(factory, "stopTrying", None)  # Twisted's ReconnectingClientFactory
    if stop_trying is not None:
        ros.call_later(0, stop_trying)
    else:  # the asyncio transport checks this flag before each retry
        factory._stop = True
