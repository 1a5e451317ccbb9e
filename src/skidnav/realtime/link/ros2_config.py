"""The settings of the ROS 2 driver (docs/ros2.md): the ``[ros2]`` table of a real-time config,
checked when the config is read, without roslibpy (which only the driver,
``skidnav.realtime.link.ros2``, imports)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from skidnav.realtime.link.ros2_messages import (
    POSE_TYPES,
    TF_MESSAGE,
    TWIST,
    TWIST_STAMPED,
    canonical_type,
)

# Whether each ROS 2 distro's cmd_vel convention is stamped (docs/ros2.md, "Which message").
DISTRO_STAMPED = {
    "humble": False,
    "iron": False,
    "jazzy": True,
    "kilted": True,
    "lyrical": True,
    "rolling": True,
}
CLOCKS = ("arrival", "header")


@dataclass(frozen=True)
class Ros2Config:
    """Where the rosbridge server is, which topics and messages to use, how poses are stamped.

    Attributes:
        host: rosbridge host (default loopback; a robot on the network is named explicitly).
        port: rosbridge WebSocket port.
        cmd_vel_topic: topic of the velocity commands.
        pose_topic: topic of the robot pose (``/tf`` for tf poses).
        pose_type: message type of ``pose_topic``: ``nav_msgs/Odometry``,
            ``geometry_msgs/PoseStamped``, ``geometry_msgs/PoseWithCovarianceStamped`` or
            ``tf2_msgs/TFMessage`` (the ROS 2 spelling ``pkg/msg/Type`` is accepted too).
        frame_offset: (x [m], y [m], heading [rad]) of the ROS frame's origin in the arena frame;
            the arena pose is ``frame_offset ⊕ ros_pose`` (e.g. the start pose for odometry).
        connect_timeout: seconds to wait for the connection before ``ConnectionError``.
        send_timeout: seconds :meth:`Ros2Driver.stop` waits for the zero twist to be sent.
        distro: the robot's ROS 2 distribution; picks the command type when ``stamped`` is None:
            ``humble``, ``iron`` → ``geometry_msgs/Twist``; ``jazzy`` and later →
            ``geometry_msgs/TwistStamped``.
        stamped: True or False to override the distro's choice of command type.
        base_frame_id: the robot's body frame: ``header.frame_id`` of stamped commands and the
            child frame of the tf pose (diff_drive_controller's ``base_frame_id``).
        odom_frame_id: parent frame of the tf pose (diff_drive_controller's ``odom_frame_id``).
        clock: ``"arrival"``: poses are stamped when they arrive and stamped commands carry a
            zero stamp (the robot stamps them on receipt); ``"header"``: this machine's and the
            robot's clocks are synchronised (NTP, chrony), so pose stamps come from the message
            headers and commands are stamped with this machine's time.
        max_pose_age: with ``clock = "header"``, oldest pose accepted [s].
        future_tolerance: with ``clock = "header"``, how far in the future a pose stamp may lie
            (clock offset and jitter) [s].
    """

    host: str = "127.0.0.1"
    port: int = 9090
    cmd_vel_topic: str = "/cmd_vel"
    pose_topic: str = "/odom"
    pose_type: str = "nav_msgs/Odometry"
    frame_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    connect_timeout: float = 5.0
    send_timeout: float = 1.0
    distro: str = "jazzy"
    stamped: bool | None = None
    base_frame_id: str = "base_link"
    odom_frame_id: str = "odom"
    clock: str = "arrival"
    max_pose_age: float = 0.5
    future_tolerance: float = 0.05

    def __post_init__(self) -> None:
        self._check_link()
        self._check_messages()
        self._check_clock()

    def _check_link(self) -> None:
        if not self.host:
            raise ValueError("expected a rosbridge host, got an empty string")
        if not 0 < self.port < 65536:
            raise ValueError(f"expected port in [1, 65535], got {self.port}")
        for name in ("cmd_vel_topic", "pose_topic"):
            if not getattr(self, name).startswith("/"):
                raise ValueError(f"expected {name} starting with '/', got {getattr(self, name)!r}")
        if not (self.connect_timeout > 0 and self.send_timeout > 0):
            raise ValueError(
                f"expected positive timeouts, got {self.connect_timeout} and {self.send_timeout}"
            )

    def _check_messages(self) -> None:
        if canonical_type(self.pose_type) not in POSE_TYPES:
            raise ValueError(f"expected pose_type in {POSE_TYPES}, got {self.pose_type!r}")
        if len(self.frame_offset) != 3 or not all(map(math.isfinite, self.frame_offset)):
            raise ValueError(
                f"expected a finite (x, y, heading) frame_offset, got {self.frame_offset}"
            )
        if self.distro not in DISTRO_STAMPED:
            raise ValueError(f"expected distro in {tuple(DISTRO_STAMPED)}, got {self.distro!r}")
        if self.stamped is not None and not isinstance(self.stamped, bool):
            raise ValueError(f"expected stamped true or false, got {self.stamped!r}")
        for name in ("base_frame_id", "odom_frame_id"):
            frame = getattr(self, name)
            if not isinstance(frame, str) or not frame or frame.startswith("/"):
                raise ValueError(f"expected {name} a frame name (no leading '/'), got {frame!r}")

    def _check_clock(self) -> None:
        if self.clock not in CLOCKS:
            raise ValueError(f"expected clock in {CLOCKS}, got {self.clock!r}")
        if not (0 < self.max_pose_age < math.inf and 0 <= self.future_tolerance < math.inf):
            raise ValueError(
                "expected max_pose_age > 0 and future_tolerance >= 0 (finite seconds), "
                f"got {self.max_pose_age} and {self.future_tolerance}"
            )

    @property
    def url(self) -> str:
        """The rosbridge WebSocket address, for messages."""
        return f"ws://{self.host}:{self.port}"

    @property
    def stamped_commands(self) -> bool:
        """Whether commands are ``TwistStamped``: ``stamped`` if set, else the distro's choice."""
        return DISTRO_STAMPED[self.distro] if self.stamped is None else self.stamped

    @property
    def cmd_vel_type(self) -> str:
        """Message type advertised on ``cmd_vel_topic``."""
        return TWIST_STAMPED if self.stamped_commands else TWIST

    @property
    def tf_poses(self) -> bool:
        """Whether poses are read from tf (``odom_frame_id`` → ``base_frame_id``)."""
        return canonical_type(self.pose_type) == TF_MESSAGE
