"""What airspeed velocity records per commit: the key ratios (:mod:`key_figures`) and, per
agent, how long it takes to learn (:mod:`time_to_learn`). Each class measures everything once
(``setup_cache``) and its ``track_`` functions read one figure each. Every figure recorded is
one of which less is better, as ``asv compare`` reads them: a compiled path's time relative to
its twin's (1 / its ratio), not the ratio."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import key_figures
import time_to_learn

Measured = dict[str, tuple[float, float]]
Learned = dict[str, dict[str, Any]]


def finite(value: float) -> float:
    """``value``, or NaN (asv: not measured) for ∞."""
    return value if math.isfinite(value) else math.nan


def interval_tracker(figure: str, index: int, unit: str) -> Callable[..., float]:
    """An asv ``track_`` function reading one end (``index`` 0: the median, 1: the low end,
    2: the high end) of the time to learn's ``figure`` (``"seconds"`` or ``"episode"``), in
    ``unit``; ∞ as NaN."""

    def track(self: object, learned: Learned, agent: str) -> float:
        return finite(learned[agent][figure][index])

    track.unit = unit  # type: ignore[attr-defined]
    return track


class KeyFigures:
    """The key ratios, at ``make bench``'s sizes."""

    params = tuple(key_figures.FIGURES)
    param_names = ("figure",)
    timeout = 900

    def setup_cache(self) -> Measured:
        return {name: figure.measure(False) for name, figure in key_figures.FIGURES.items()}

    def track_relative_time(self, measured: Measured, name: str) -> float:
        compiled, twin = measured[name]
        return twin / compiled

    track_relative_time.unit = "× its twin's time"  # type: ignore[attr-defined]

    def track_time_per_million(self, measured: Measured, name: str) -> float:
        return 1e6 / measured[name][0]

    track_time_per_million.unit = "s per million"  # type: ignore[attr-defined]


class TimeToLearn:
    """How long each agent of ``time_to_learn.toml`` takes to learn: the Kaplan–Meier medians
    and the ends of their intervals (∞ recorded as NaN: asv's "not measured")."""

    params = tuple(time_to_learn.agent_labels())
    param_names = ("agent",)
    timeout = 1800

    def setup_cache(self) -> Learned:
        return {
            label: dict(figures._asdict())
            for label, figures in time_to_learn.time_to_learn().items()
        }

    # the medians and the ends of their intervals: (figure, index in its triple, unit)
    track_seconds = interval_tracker("seconds", 0, "s")
    track_seconds_low = interval_tracker("seconds", 1, "s")
    track_seconds_high = interval_tracker("seconds", 2, "s")
    track_episodes = interval_tracker("episode", 0, "episodes")
    track_episodes_low = interval_tracker("episode", 1, "episodes")
    track_episodes_high = interval_tracker("episode", 2, "episodes")

    def track_unconverged_runs(self, learned: Learned, agent: str) -> float:
        return float(learned[agent]["runs"] - learned[agent]["converged"])

    track_unconverged_runs.unit = "runs"  # type: ignore[attr-defined]

    def track_time_per_update(self, learned: Learned, agent: str) -> float:
        rate = learned[agent]["updates_per_second"]
        return 1e9 / rate if rate > 0 else math.nan

    track_time_per_update.unit = "ns"  # type: ignore[attr-defined]

    def track_time_per_step(self, learned: Learned, agent: str) -> float:
        return 1e6 / learned[agent]["steps_per_second"]

    track_time_per_step.unit = "µs"  # type: ignore[attr-defined]
