"""The robot's running clock in seconds, on CPython and on MicroPython.

The protocol needs a clock that keeps counting while the robot is stalled and never steps
(docs/protocol.md, "Stale commands", rule 2): ``time.monotonic`` on CPython; on MicroPython,
which has none, the millisecond ticks ``time.ticks_ms``, which wrap around, summed with
``time.ticks_diff``. Read the clock at least once per half wrap period (days on every port; the
main loop reads it every control period).
"""

import time

TYPE_CHECKING = False  # MicroPython has no typing module: its names are for the type checker
if TYPE_CHECKING:
    from collections.abc import Callable


def running_clock(
    ticks_ms: "Callable[[], int] | None" = None,
    ticks_diff: "Callable[[int, int], int] | None" = None,
) -> "Callable[[], float]":
    """A function returning the running clock [s]: ``time.monotonic`` where it exists (and no
    ticks are given), else seconds since the first call summed from the wrapping ``ticks_ms``
    [ms] by ``ticks_diff`` (MicroPython's, by default).

    >>> ticks = iter([2**30 - 5, 2**30 - 1, 3])  # a counter that wraps at 2**30 ms
    >>> clock = running_clock(lambda: next(ticks), lambda new, old: (new - old) % 2**30)
    >>> clock(), clock()
    (0.004, 0.008)
    """
    if ticks_ms is None:
        monotonic = getattr(time, "monotonic", None)
        if monotonic is not None:
            return monotonic  # type: ignore[no-any-return]
        ticks_ms, ticks_diff = time.ticks_ms, time.ticks_diff  # type: ignore[attr-defined]
    assert ticks_diff is not None, "give ticks_diff with ticks_ms"
    read, difference = ticks_ms, ticks_diff
    state = [read(), 0]  # the last tick read [ms], the milliseconds summed so far

    def now() -> float:
        tick = read()
        state[1] += difference(tick, state[0])
        state[0] = tick
        return state[1] / 1000

    return now
