"""The two things a board provides: its wheels and pose (:class:`Robot`) and its byte channel to
the host (:class:`Transport`). A port implements both — subclass these or write classes with the
same methods — and hands them to :func:`~.loop.run`; nothing else in this package touches
hardware."""


class Robot:
    """The wheels and the pose of the robot.

    Attributes:
        wheel_limit: the largest wheel speed the motors run [rad/s]; a ``cmd`` beyond it is
            refused (``error`` ``range``), never clamped.
    """

    wheel_limit = 1.7

    def set_wheels(self, omega_left: float, omega_right: float) -> None:
        """Drive the left and right wheels at these angular speeds [rad/s] until told otherwise
        (each within ±:attr:`wheel_limit`)."""
        raise NotImplementedError

    def stop(self) -> None:
        """Zero both wheels now (and drop whatever a motor driver has queued)."""
        raise NotImplementedError

    def pose(self, now: float) -> tuple[float, float, float] | None:
        """The pose at ``now`` [s, robot clock] as (x [m], y [m], heading [rad,
        counter-clockwise from +x]) — from odometry, an IMU or a tracker — or None if there is
        none this period (the host tolerates a missing report now and then)."""
        raise NotImplementedError


class Transport:
    """The byte channel to the host, never blocking: a TCP listener, a UART, a USB serial port.

    One host at a time: a TCP transport answers other clients ``error`` ``busy`` and closes
    them (:data:`BUSY_LINE`); a serial line has one host, always attached.
    """

    connectionless = False
    """True for a serial line: no connection events; a new ``hello`` starts a new session."""

    def attach(self) -> bool:
        """True once a host is attached (a TCP transport accepts a pending connection here;
        a serial line is always attached)."""
        raise NotImplementedError

    def read(self) -> bytes | None:
        """The bytes that arrived (b"" if none yet), or None if the host went away."""
        raise NotImplementedError

    def write(self, data: bytes) -> int:
        """Write what fits now without waiting; the number of bytes taken (0 if none). OSError
        if the channel broke."""
        raise NotImplementedError

    def hang_up(self) -> None:
        """Drop the current host (TCP: close its connection; a serial line: nothing to close)."""
        raise NotImplementedError

    def wait(self, timeout: float) -> None:
        """Sleep until bytes may have arrived or ``timeout`` [s] passed."""
        raise NotImplementedError

    def close(self) -> None:
        """Release the channel."""


BUSY_LINE = (
    b'{"v":2,"type":"error","seq":0,"code":"busy","message":"another client is connected"}\n'
)
"""What a second host is told before its connection is closed."""
