"""ROS 2 robot driver over rosbridge (roslibpy): twists out on ``cmd_vel``, poses or tf in.

The robot runs ROS 2 with ``rosbridge_server`` (rosbridge v2 JSON over a WebSocket, default port
9090); this driver is a rosbridge client (docs/ros2.md). Commands are ``TwistStamped`` from Jazzy
on (diff_drive_controller requires it on ``~/cmd_vel`` there), ``Twist`` before; the messages are
built and read in ``skidnav.realtime.link.ros2_messages``. Poses are stamped on arrival, or by their
header stamp (``clock = "header"``, synchronised clocks); a pose that is malformed, too old or
from the future is refused and reported as a fault (``on_fault``: the safety monitor's trip).

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
from typing import Any

import roslibpy

from skidnav.realtime.link.interface import Pose
from skidnav.realtime.link.ros2_config import Ros2Config
from skidnav.realtime.link.ros2_messages import (
    ZERO_STAMP,
    compose,
    header_seconds,
    pose_from_message,
    pose_from_transform,
    ros_time,
    select_transform,
    twist_stamped,
    wheel_speeds_to_twist,
)
from skidnav.robot.params import RobotParams

LOGGER = logging.getLogger(__name__)


class PoseRefused(Exception):
    """A well-formed pose whose header stamp is too old or lies in the future."""


class Ros2Driver:
    """A :class:`~skidnav.realtime.link.interface.RobotDriver` for a ROS 2 robot behind rosbridge.

    Args:
        config: server address, topics, message types, timeouts and the pose clock.
        params: robot geometry for the wheel-speed → twist conversion.
        clock: monotonic clock [s] of :attr:`Pose.stamp`.
        wall_clock: this machine's time [s since the Unix epoch], the ROS time of command stamps
            and the reference of pose header stamps (``config.clock = "header"``).

    Attributes:
        fault: first fault since :meth:`connect` (a refused pose message), or None.
        on_fault: called with each fault's one-line reason (the safety monitor sets it).
        malformed_messages, refused_poses: counts of pose messages refused as malformed and as
            too old or from the future.

    Pose messages arrive on roslibpy's thread; :meth:`latest_pose` may be called from any thread.
    """

    def __init__(
        self,
        config: Ros2Config | None = None,
        params: RobotParams | None = None,
        clock: Callable[[], float] = time.monotonic,
        wall_clock: Callable[[], float] = time.time,
    ) -> None:
        self.config = config or Ros2Config()
        self.params = params or RobotParams()
        self.fault: str | None = None
        self.on_fault: Callable[[str], None] | None = None
        self.malformed_messages = 0
        self.refused_poses = 0
        self._clock = clock
        self._wall_clock = wall_clock
        self._lock = threading.Lock()
        self._latest: Pose | None = None
        self._measurement: tuple[Pose, float] | None = None
        self._ros: roslibpy.Ros | None = None
        self._cmd_vel: roslibpy.Topic | None = None
        self._pose_topic: roslibpy.Topic | None = None

    @property
    def connected(self) -> bool:
        """Whether the WebSocket to rosbridge is open."""
        return self._ros is not None and bool(self._ros.is_connected)

    def connect(self) -> None:
        """Open the WebSocket, advertise the command topic and subscribe to the pose topic; clears
        the fault and the last pose.

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
        self.fault = None
        with self._lock:
            self._latest = self._measurement = None
        self._ros = ros
        self._cmd_vel = roslibpy.Topic(ros, config.cmd_vel_topic, config.cmd_vel_type)
        self._cmd_vel.advertise()
        self._pose_topic = roslibpy.Topic(ros, config.pose_topic, config.pose_type)
        self._pose_topic.subscribe(self._on_pose)
        LOGGER.info("connected to rosbridge at %s", config.url)

    def _on_pose(self, message: dict[str, Any]) -> None:
        """roslibpy's callback: keep the pose, or count and report why it was refused."""
        # Each count follows its report: whoever sees a count has seen its on_fault call.
        try:
            self._accept(message)
        except PoseRefused as refusal:
            self._report(f"refused pose on {self.config.pose_topic}: {refusal}")
            self.refused_poses += 1
        except Exception as error:  # ValueError from the readers; the reader must outlive any
            detail = error if isinstance(error, ValueError) else f"{type(error).__name__}: {error}"
            self._report(f"malformed {self.config.pose_type} on {self.config.pose_topic}: {detail}")
            self.malformed_messages += 1

    def _accept(self, message: Mapping[str, Any]) -> None:
        """Read, stamp and store one pose message (a tf message without our transform is skipped).

        Raises:
            ValueError: a malformed message. PoseRefused: a stamp too old or in the future.
        """
        config = self.config
        source: Mapping[str, Any] | None = message
        if config.tf_poses:
            source = select_transform(message, config.odom_frame_id, config.base_frame_id)
            if source is None:
                return
            ros_pose = pose_from_transform(source)
        else:
            ros_pose = pose_from_message(message, config.pose_type)
        robot_stamp = header_seconds(source) if config.clock == "header" else None
        stamp = self._clock()
        if robot_stamp is not None:
            stamp -= self._age(robot_stamp)
        pose = Pose(stamp, *compose(config.frame_offset, ros_pose))
        with self._lock:
            self._latest = pose
            self._measurement = None if robot_stamp is None else (pose, robot_stamp)

    def _age(self, robot_stamp: float) -> float:
        """Age [s, ≥ 0] of a header stamp [s ROS time] on this machine's clock.

        Raises:
            PoseRefused: older than ``max_pose_age`` or newer than ``future_tolerance`` allows.
        """
        age = self._wall_clock() - robot_stamp
        config = self.config
        if age > config.max_pose_age:
            raise PoseRefused(
                f"stamp {age:.3f} s old (max_pose_age {config.max_pose_age:g} s): "
                "a stalled robot or unsynchronised clocks"
            )
        if age < -config.future_tolerance:
            raise PoseRefused(
                f"stamp {-age:.3f} s in the future (future_tolerance "
                f"{config.future_tolerance:g} s): are the clocks synchronised?"
            )
        return max(age, 0.0)  # within the tolerance a pose cannot be newer than its arrival

    def _report(self, reason: str) -> None:
        """One warning line for the first fault since connect(); every fault reaches on_fault."""
        if self.fault is None:
            self.fault = reason
            LOGGER.warning("%s", reason)
        else:
            LOGGER.debug("%s", reason)
        if self.on_fault is not None:
            self.on_fault(reason)

    def _twist_message(self, omega_left: float, omega_right: float) -> dict[str, Any]:
        """The command message for wheel speeds ω_L, ω_R [rad/s], of ``config.cmd_vel_type``."""
        twist = wheel_speeds_to_twist(omega_left, omega_right, self.params)
        if not self.config.stamped_commands:
            return twist
        synchronised = self.config.clock == "header"
        stamp = ros_time(self._wall_clock()) if synchronised else ZERO_STAMP
        return twist_stamped(twist, stamp, self.config.base_frame_id)

    def command(self, omega_left: float, omega_right: float) -> None:
        """Publish the twist for wheel speeds ω_L, ω_R [rad/s]; ``ConnectionError`` if unlinked."""
        if not (math.isfinite(omega_left) and math.isfinite(omega_right)):
            raise ValueError(f"expected finite wheel speeds, got {omega_left}, {omega_right}")
        if self._cmd_vel is None or not self.connected:
            raise ConnectionError(f"not connected to rosbridge at {self.config.url}")
        self._cmd_vel.publish(roslibpy.Message(self._twist_message(omega_left, omega_right)))

    def latest_pose(self) -> Pose | None:
        """The newest pose received (arena frame), or None if none yet."""
        with self._lock:
            return self._latest

    def latest_measurement(self) -> tuple[Pose, float] | None:
        """With ``clock = "header"``, the newest pose and its header stamp [s ROS time] (the
        robot's clock); None with ``clock = "arrival"`` or before the first pose."""
        with self._lock:
            return self._measurement

    def stop(self) -> bool:
        """Publish a zero twist; True once it has been handed to the socket.

        rosbridge does not acknowledge publications, so "confirmed" means sent on an open link.
        """
        if self._ros is None or self._cmd_vel is None or not self.connected:
            return False
        self._cmd_vel.publish(roslibpy.Message(self._twist_message(0.0, 0.0)))
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
