"""Numbers and counts written for people: every report table and every line the commands print
formats its numbers here, so a reader never meets ``6819378.33``, ``nan``, ``[nan, nan]`` or
"1 episodes".

* :func:`readable` rounds to about three significant figures (whole numbers from 100 on, with
  thousands separators), writes "n/a" for a missing value and "∞" for an infinite one;
* :func:`interval` writes an estimate with its interval, the bounds at the estimate's
  precision, the estimate alone when the interval is undefined, and — over fewer than
  :data:`MIN_INTERVAL_SEEDS` seeds — the estimate with a caveat instead of an interval a reader
  would take at face value (a percentile bootstrap over two seeds can only return the two
  values themselves; Efron & Tibshirani (1993) ch. 13);
* :func:`plural` counts a noun.

>>> readable(6819378.33), readable(123.456), readable(12.345), readable(0.01234)
('6,820,000', '123', '12.3', '0.0123')
>>> readable(float("nan")), readable(float("inf")), readable(None)
('n/a', '∞', 'n/a')
>>> interval(12.3, 10.1, 14.2), interval(0.5, float("nan"), float("nan"))
('12.3 [10.1, 14.2]', '0.5')
>>> interval(12.3, 10.1, 14.2, seeds=2)
'12.3 (2 seeds: too few for an interval)'
>>> plural(1, "episode"), plural(3, "episode"), plural(2, "policy", "policies")
('1 episode', '3 episodes', '2 policies')
"""

from __future__ import annotations

import math

NOT_AVAILABLE = "n/a"
"""What a missing number (NaN, None) is written as."""
MIN_INTERVAL_SEEDS = 3
"""Fewest seeds (independent runs) over which a bootstrap interval is printed as one."""
SIGNIFICANT = 3
"""Significant figures of a number written for people."""


def _missing(value: float | None) -> bool:
    return value is None or value != value  # NaN


def decimals(value: float, significant: int = SIGNIFICANT) -> int:
    """Decimals that show ``value`` to ``significant`` figures: none from 10^(significant − 1)
    on, at most 6.

    >>> decimals(123.4), decimals(12.34), decimals(0.5), decimals(0.0)
    (0, 1, 3, 0)
    """
    if value == 0 or not math.isfinite(value):
        return 0
    magnitude = math.floor(math.log10(abs(value)))
    return min(max(significant - 1 - magnitude, 0), 6)


def readable(value: float | None, digits: int | None = None) -> str:
    """``value`` for people: ``digits`` decimals when given, else about :data:`SIGNIFICANT`
    significant figures (trailing zeros dropped); from 10 000 on rounded to three significant
    figures with thousands separators; "n/a" when missing, "∞" when infinite."""
    if _missing(value):
        return NOT_AVAILABLE
    number = float(value)  # type: ignore[arg-type]
    if math.isinf(number):
        return "∞" if number > 0 else "−∞"
    if digits is not None:
        return f"{number:,.{digits}f}"
    if abs(number) >= 10_000:
        magnitude = math.floor(math.log10(abs(number)))
        return f"{round(number, SIGNIFICANT - 1 - magnitude):,.0f}"
    text = f"{number:,.{decimals(number)}f}"
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text == "-0" else text


def interval(
    estimate: float | None,
    low: float | None,
    high: float | None,
    digits: int | None = None,
    seeds: int | None = None,
) -> str:
    """``estimate [low, high]``: the bounds with the estimate's decimals (``digits``, else
    those :func:`readable` gives the estimate); the estimate alone when a bound is missing;
    "n/a" when the estimate is; with ``seeds`` below :data:`MIN_INTERVAL_SEEDS`, the estimate
    and :func:`seeds_caveat` instead of the interval."""
    if _missing(estimate):
        return NOT_AVAILABLE
    if seeds is not None and seeds < MIN_INTERVAL_SEEDS:
        return f"{readable(estimate, digits)} ({seeds_caveat(seeds)})"
    if _missing(low) or _missing(high):
        return readable(estimate, digits)
    values = [float(v) for v in (estimate, low, high)]  # type: ignore[arg-type]
    largest = max((abs(v) for v in values if math.isfinite(v)), default=0.0)
    if digits is None and largest < 10_000:
        digits = decimals(largest)
    shown = [readable(v, digits) for v in values]
    return f"{shown[0]} [{shown[1]}, {shown[2]}]"


def seeds_caveat(seeds: int) -> str:
    """Why no interval is shown over ``seeds`` seeds.

    >>> seeds_caveat(1)
    '1 seed: too few for an interval'
    """
    return f"{plural(seeds, 'seed')}: too few for an interval"


def plural(count: int, noun: str, plural_noun: str | None = None) -> str:
    """``count`` and ``noun``, in the plural (``plural_noun``, else ``noun + "s"``) unless the
    count is 1; thousands separated."""
    word = noun if count == 1 else (plural_noun or f"{noun}s")
    return f"{count:,} {word}"
