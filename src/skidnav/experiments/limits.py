"""The limits of a run's settings, written once: what an experiment config, the Python API
(:mod:`skidnav.api`) and the studies built on them accept for the number of seeds, episodes,
actions per episode, evaluation rollouts, seeds and the convergence rule.

A value is refused with one line naming the setting, its bounds and the value:

>>> check_setting("episodes", 10**12)
Traceback (most recent call last):
...
ValueError: expected episodes to be an integer in [1, 10000000], got 1000000000000
>>> check_setting("root_seed", None, shown_as="seed")
Traceback (most recent call last):
...
ValueError: expected seed to be an integer in [0, 9223372036854775807], got None
>>> check_setting("convergence_level", float("nan"), shown_as="level")
Traceback (most recent call last):
...
ValueError: expected level to be a number in [1e-06, 1.0], got nan
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from skidnav.errors import shown

MAX_SEEDS = 10_000
"""Most seeds per cell of an experiment."""
MAX_EPISODES = 10_000_000
"""Most training episodes per run."""
MAX_STEPS = 1_000_000
"""Largest action limit per episode."""
MAX_ROLLOUTS = 100
"""Most greedy rollouts per evaluation."""
MAX_SEED = 2**63 - 1
"""Largest seed (NumPy's ``SeedSequence`` takes any non-negative integer; one of 63 bits is
what every saved file and table can hold)."""


def check_range(name: str, value: object, low: float, high: float, *, integer: bool) -> None:
    """ValueError ``"expected NAME to be an integer in [LOW, HIGH], got …"`` (``a number``
    when not ``integer``; ``>= LOW`` with an infinite ``high``) unless ``value`` is an ``int``
    (a bool is not; a ``float`` too when not ``integer``) within the closed bounds (NaN is
    not)."""
    kind = "an integer" if integer else "a number"
    ok_type = isinstance(value, int) if integer else isinstance(value, int | float)
    inside = ok_type and low <= value <= high  # type: ignore[operator]
    if isinstance(value, bool) or not inside:
        bounds = f"in [{low}, {high}]" if math.isfinite(high) else f">= {low}"
        raise ValueError(f"expected {name} to be {kind} {bounds}, got {shown(value)}")


@dataclass(frozen=True)
class Limit:
    """The closed range [low, high] of a setting and whether it is an integer."""

    low: float
    high: float
    integer: bool


SETTINGS: Mapping[str, Limit] = MappingProxyType(
    {
        "seeds": Limit(1, MAX_SEEDS, True),
        "episodes": Limit(1, MAX_EPISODES, True),
        "max_steps": Limit(1, MAX_STEPS, True),
        "root_seed": Limit(0, MAX_SEED, True),
        "eval_rollouts": Limit(1, MAX_ROLLOUTS, True),
        "convergence_tolerance": Limit(1e-6, 0.999, False),
        "convergence_window": Limit(1, 10_000, True),
        "convergence_level": Limit(1e-6, 1.0, False),
    }
)
"""Every shared setting's limit, by its name in an experiment config."""


def check_setting(
    name: str, value: object, *, shown_as: str = "", low: float | None = None
) -> None:
    """ValueError (one line, :func:`check_range`) unless ``value`` is within the limit of the
    setting ``name`` (:data:`SETTINGS`), named ``shown_as`` in the message (default ``name``);
    ``low`` raises the lower bound where a caller needs more (an experiment's two episodes)."""
    limit = SETTINGS[name]
    bottom = limit.low if low is None else low
    check_range(shown_as or name, value, bottom, limit.high, integer=limit.integer)
