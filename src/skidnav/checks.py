"""Validation of settings written once: the integer and number checks of config dataclasses,
arguments and saved files.

>>> check_integer("seeds", 3, 1)
>>> check_integer("hidden", True, 0, 64)
Traceback (most recent call last):
...
ValueError: expected hidden to be an integer in [0, 64], got True
>>> check_number("sigma0", 0.5, 0.0, 1e30)
0.5
>>> check_number("wheel_speed", 10**400, 0.0)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
ValueError: expected wheel_speed to be a finite number > 0, got '1000...'…
"""

from __future__ import annotations

import contextlib
import math

import numpy as np

from skidnav.errors import shown


def check_integer(name: str, value: object, low: int, high: int | None = None) -> None:
    """ValueError ``"expected NAME to be an integer >= LOW, got …"`` (or ``in [LOW, HIGH]`` with
    ``high``) unless ``value`` is an ``int`` (a bool is not) within the bounds."""
    integer = isinstance(value, int) and not isinstance(value, bool)
    if integer and low <= value and (high is None or value <= high):  # type: ignore[operator]
        return
    bounds = f">= {low}" if high is None else f"in [{low}, {high}]"
    raise ValueError(f"expected {name} to be an integer {bounds}, got {value!r}")


def check_number(
    name: str, value: object, low: float, high: float = math.inf, *, closed: bool = False
) -> float:
    """``value`` as a float if it is an ``int`` or ``float`` (a bool is not), finite, above ``low``
    (at least ``low`` when ``closed``) and at most ``high``; else ValueError
    ``"expected NAME to be a finite number > LOW, got …"`` (``in (LOW, HIGH]`` with a finite
    ``high``). An integer too large for a float is a ValueError too, never an OverflowError."""
    number = math.nan
    if isinstance(value, int | float) and not isinstance(value, bool):
        with contextlib.suppress(OverflowError):  # an integer beyond the floats
            number = float(value)
    above = low <= number if closed else low < number
    if above and number <= high and math.isfinite(number):
        return number
    if math.isinf(high):
        bounds = f"{'>=' if closed else '>'} {low:g}"
    else:
        bounds = f"in {'[' if closed else '('}{low:g}, {high:g}]"
    raise ValueError(f"expected {name} to be a finite number {bounds}, got {shown(value)}")


def check_magnitude(name: str, values: np.ndarray, bound: float) -> None:
    """ValueError unless every value of the array ``name`` is below ``bound`` in magnitude (NaN
    is not).

    >>> check_magnitude("mean", np.array([1.0, np.nan]), 1e32)
    Traceback (most recent call last):
    ...
    ValueError: array 'mean' holds a value that is NaN or not below 1e+32 in magnitude
    """
    if not (np.abs(values) < bound).all():  # NaN fails the comparison
        raise ValueError(
            f"array {name!r} holds a value that is NaN or not below {bound:g} in magnitude"
        )


def check_names(name: str, values: object, known: tuple[str, ...]) -> None:
    """ValueError ``"expected NAME to be distinct names among …, got …"`` unless ``values`` is a
    non-empty tuple of distinct members of ``known``."""
    if (
        isinstance(values, tuple)
        and values
        and len(set(values)) == len(values)
        and all(isinstance(value, str) and value in known for value in values)
    ):
        return
    got = shown(list(values) if isinstance(values, tuple) else values)
    raise ValueError(f"expected {name} to be distinct names among {', '.join(known)}, got {got}")
