"""The host's estimate of the robot's clock, the clock of its pose stamps: a pose stamped from
the future is refused (docs/protocol.md, "Pose stamps").

The loop counts a robot's control periods on its pose stamps (docs/realtime.md, "One action in
real time"), so a stamp far ahead (``1e308``) would make it count periods that never passed and
rush through its actions. The robot's clock is tracked by the robot's own rule for the host's
clock (:class:`~skidnav.realtime.reference_robot.host_clock.HostClock`, docs/protocol.md,
"Stale commands", rule 2), fed with the poses taken and this machine's monotonic clock scaled by
the time scale. A pose is judged against the estimate of the poses before it, and a refused one
never enters the estimate: no stamp, one far ahead or a robot clock that jumped ahead for good,
gets past it. A pose stamped behind the estimate (a robot that restarted) is taken, and its
clock adopted by the median from its second pose on.

The bound is the longest lease a command of this host can hold the wheels, ``min(ttl,
MAX_LEASE_LIMIT)`` [s wall] (the bound of the robot's own stall rule,
:mod:`~skidnav.realtime.reference_robot.rules`), on the robot's clock: as long as the host waits
for a pose before tripping, so a host or link that stalls no longer than that never sees a good
pose as ahead.

A lockstep robot's clock runs on commands, not on the wall clock, and the loop counts its
periods by ``ack`` (docs/protocol.md, "Lockstep"): its poses are not judged.
"""

from __future__ import annotations

from skidnav.realtime.reference_robot.host_clock import HostClock
from skidnav.realtime.reference_robot.rules import MAX_LEASE_LIMIT


class RobotClock:
    """The robot's clock as the host tracks it (see module doc).

    Args:
        time_scale: robot seconds per wall second (a real robot's: 1).
        ttl: the ``ttl`` of this host's commands [s wall].
        lockstep: the robot is a lockstep one: nothing is refused.
    """

    def __init__(self, time_scale: float, ttl: float, lockstep: bool = False) -> None:
        if not (time_scale > 0 and ttl > 0):
            raise ValueError(f"expected time_scale and ttl > 0, got {time_scale}, {ttl}")
        self.time_scale, self.lockstep = time_scale, lockstep
        self.tolerance = min(ttl, MAX_LEASE_LIMIT) * time_scale
        """How far ahead of the estimate a pose may be stamped [s robot time]: the longest lease
        a command of this host can hold the wheels, on the robot's clock."""
        self.estimate = HostClock()

    def refuse(self, stamp: float, received: float) -> str | None:
        """Why a pose stamped ``stamp`` [s robot clock] and received at ``received`` (monotonic
        [s]) is refused, in one line, or None (it is taken, and fed to the estimate).

        >>> clock = RobotClock(time_scale=1.0, ttl=0.5)
        >>> clock.refuse(stamp=20.0, received=1000.0), clock.refuse(stamp=20.1, received=1000.1)
        (None, None)
        >>> clock.refuse(stamp=1e308, received=1000.2)
        "robot pose stamped 1e+308 s ahead of the robot's clock (more than 0.5 s)"
        >>> clock.refuse(stamp=20.3, received=1000.3) is None  # the next one in time is taken
        True
        """
        now = received * self.time_scale  # this machine's clock in robot seconds
        if not self.lockstep and self.estimate.offset is not None:
            ahead = -self.estimate.age(stamp, now)
            if ahead > self.tolerance:
                return (
                    f"robot pose stamped {ahead:.3g} s ahead of the robot's clock (more than "
                    f"{self.tolerance:g} s)"
                )
        self.estimate.observe(stamp, now)
        return None
