"""Validation of settings written once: the integer checks of config dataclasses and arguments.

>>> check_integer("seeds", 3, 1)
>>> check_integer("hidden", True, 0, 64)
Traceback (most recent call last):
...
ValueError: expected hidden to be an integer in [0, 64], got True
"""

from __future__ import annotations


def check_integer(name: str, value: object, low: int, high: int | None = None) -> None:
    """ValueError ``"expected NAME to be an integer >= LOW, got …"`` (or ``in [LOW, HIGH]`` with
    ``high``) unless ``value`` is an ``int`` (a bool is not) within the bounds."""
    integer = isinstance(value, int) and not isinstance(value, bool)
    if integer and low <= value and (high is None or value <= high):  # type: ignore[operator]
        return
    bounds = f">= {low}" if high is None else f"in [{low}, {high}]"
    raise ValueError(f"expected {name} to be an integer {bounds}, got {value!r}")
