"""The robot's estimate of the host's clock, for the stall rule (docs/protocol.md, "Stale
commands": rule 2)."""


class HostClock:
    """The robot's estimate of the host's clock, for the stall rule (docs/protocol.md).

    Every stamped message from the host (``cmd``, ``heartbeat``) gives a sample
    ``receipt − stamp`` = clock offset + transport delay (both in seconds, the receipt on the
    robot's own running clock). A *read* is everything the robot read at once (one ``now``);
    its smallest sample is its best offset measurement. The offset estimate is the median of the
    last :attr:`READS` reads' measurements (the lower one while there are only two), so

    - a command that sat in a buffer while either side stalled is read with others that did
      too: its read's measurement is large, the median still that of the reads before, and the
      command's age (:meth:`age`) shows the wait;
    - one message with a wild stamp (a host clock stepping forward or back, or a glitch) moves
      the estimate for at most that read, and a lasting step of the host's clock is adopted
      from its second read on: nothing can keep later commands stale;
    - clocks running at slightly different rates are followed read by read.

    >>> clock = HostClock()
    >>> clock.observe(stamp=100.0, now=4.0)  # offset -96 s (+ a delay)
    >>> clock.observe(stamp=100.1, now=4.1)
    >>> clock.observe(stamp=100.5, now=5.5)  # read 1 s late: a stall, not a new offset
    >>> clock.age(stamp=100.5, now=5.5)  # so it is 1 s old
    1.0
    >>> clock.observe(stamp=1e6, now=5.6)  # a stamp 10^6 s ahead (the host's clock jumped)
    >>> clock.observe(stamp=101.7, now=5.7)  # and back: the next command is fresh again
    >>> abs(clock.age(stamp=101.7, now=5.7)) < 1e-9
    True
    """

    READS = 3

    def __init__(self) -> None:
        self._reads: list[tuple[float, float]] = []  # (now, sample), the newest last

    def observe(self, stamp: float, now: float) -> None:
        """One host message with ``stamp`` [s, host clock] read at ``now`` [s, robot clock]."""
        sample = now - stamp
        if self._reads and self._reads[-1][0] == now:
            sample = min(sample, self._reads.pop()[1])
        self._reads.append((now, sample))
        if len(self._reads) > self.READS:
            self._reads.pop(0)

    @property
    def offset(self) -> float | None:
        """Robot clock minus host clock [s] as estimated (None before the first sample)."""
        if not self._reads:
            return None
        samples = sorted(sample for _, sample in self._reads)
        return samples[(len(samples) - 1) // 2]

    def age(self, stamp: float, now: float) -> float:
        """How long before ``now`` [s, robot clock] the host sent what it stamped ``stamp``
        [s] (call :meth:`observe` first); ±inf for absurd stamps (beyond ±1e307 s)."""
        offset = self.offset
        assert offset is not None, "observe a host stamp first"
        return (now - stamp) - offset
