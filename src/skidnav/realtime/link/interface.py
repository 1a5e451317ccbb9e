"""The one interface every robot driver implements.

A robot is anything that takes wheel-speed commands and gives back a stream of timestamped poses.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol


class Pose(NamedTuple):
    """A measured pose.

    Attributes:
        stamp: time of the measurement on the driver's monotonic clock [s].
        x, y: position in the arena frame [m]. heading: counter-clockwise from +x [rad].
    """

    stamp: float
    x: float
    y: float
    heading: float


class RobotDriver(Protocol):
    """Wheel-speed commands in, timestamped poses out.

    Implementations: ``sim`` (a simulated robot server over TCP), ``tcp`` and ``serial`` (the
    line protocol of docs/protocol.md), ``ros2`` (rosbridge).
    """

    def connect(self) -> None:
        """Open the link; raises ``ConnectionError`` if the robot cannot be reached."""

    def command(self, omega_left: float, omega_right: float) -> None:
        """Send wheel angular speeds [rad/s]; returns without waiting for motion."""

    def latest_pose(self) -> Pose | None:
        """The newest pose received, or None if none yet."""

    def stop(self) -> bool:
        """Command zero wheel speeds, retrying until the robot confirms (True) or the link is
        found dead (False); returns within :data:`skidnav.realtime.control.safety.STOP_WAIT`."""

    def close(self) -> None:
        """Stop the wheels (best effort) and release the link."""
