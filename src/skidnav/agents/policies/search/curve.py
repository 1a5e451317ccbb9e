"""The learning curve of a search: one :class:`GenerationRecord` per generation, as JSON rows
(the CSV, the summary) and as a float64 table (the checkpoint), read back checked.

The evaluation schedule (:func:`scheduled`) depends on nothing but the generation and
``eval_every``, so the records a checkpoint holds are those every run of the same config
writes up to that generation; the extra evaluation after a search's last generation is not part
of them (:mod:`skidnav.agents.policies.search.cmaes`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from skidnav.agents.policies.search.config import SearchConfig


class GenerationRecord(NamedTuple):
    """One point of the learning curve (generation 0: the initial mean, before any episode)."""

    generation: int
    """Generations done."""
    episodes: int
    """Real episodes the search has consumed: λ · E · generation."""
    evaluation_episodes: int
    """Episodes of the mean's evaluations so far (not part of ``episodes``)."""
    wall_time: float
    """Seconds since the search started, its evaluations included (summed over resumed runs)."""
    best_return: float
    """This generation's best candidate score (mean return over its E episodes); NaN at 0."""
    population_return: float
    """The mean of this generation's λ scores; NaN at 0."""
    sigma: float
    """The step size σ after this generation's update."""
    mean_return: float
    """The mean policy's mean return on the evaluation seeds; NaN when not evaluated."""
    mean_success: float
    """The mean policy's share of evaluation episodes that reached the goal; NaN likewise."""


COUNTS = ("generation", "episodes", "evaluation_episodes")
"""The integer fields of a record (exact in the float64 table: at most 10¹⁴)."""


def scheduled(generation: int, eval_every: int) -> bool:
    """Whether the mean is evaluated after ``generation`` whatever the search's length: every
    ``eval_every``-th generation, and generation 0."""
    return generation % eval_every == 0


def record_rows(records: tuple[GenerationRecord, ...] | list[GenerationRecord]) -> list[Any]:
    """The records as JSON-able dicts, NaN as None (for JSON, CSV and the checkpoint)."""
    return [
        {
            key: None if isinstance(v, float) and math.isnan(v) else v
            for key, v in r._asdict().items()
        }
        for r in records
    ]


def records_table(records: list[GenerationRecord]) -> np.ndarray:
    """float64 (len(records), 9): one row per record, its fields in order, NaN kept."""
    return np.array([tuple(record) for record in records], dtype=np.float64).reshape(
        len(records), len(GenerationRecord._fields)
    )


def records_from_table(table: np.ndarray, config: SearchConfig) -> list[GenerationRecord]:
    """The records of :func:`records_table` (a search of ``config``, generations 0 .. G for G + 1
    rows); ValueError naming the first field that is not what such a search writes: its counts
    (generation, episodes, evaluation episodes), finite non-decreasing wall times ≥ 0 [s],
    σ > 0, finite scores after generation 0, and an evaluation (a finite mean return, a success
    rate in [0, 1]) in exactly the scheduled rows (NaN elsewhere)."""
    table = np.asarray(table, dtype=np.float64)
    column = dict(zip(GenerationRecord._fields, table.T, strict=True))
    generations = np.arange(len(table))
    evaluated = generations % config.eval_every == 0  # scheduled(), row by row
    counts = {
        "generation": generations,
        "episodes": generations * config.episodes_per_generation,
        "evaluation_episodes": config.eval_episodes * np.cumsum(evaluated),
    }
    for name, expected in counts.items():
        if not np.array_equal(column[name], expected):
            raise ValueError(f"records: {name} is not that of generations 0..{len(table) - 1}")
    present = {
        "wall_time": generations >= 0, "sigma": generations >= 0,
        "best_return": generations > 0, "population_return": generations > 0,
        "mean_return": evaluated, "mean_success": evaluated,
    }  # fmt: skip
    for name, rows in present.items():
        values = column[name]
        if not (np.isfinite(values[rows]).all() and np.isnan(values[~rows]).all()):
            raise ValueError(
                f"records: {name} is NaN where a search writes a number, or a number where it "
                "writes none"
            )
    wall_time, success = column["wall_time"], column["mean_success"][evaluated]
    if (wall_time < 0).any() or (np.diff(wall_time) < 0).any():
        raise ValueError("records: expected non-decreasing wall times >= 0")
    if (column["sigma"] <= 0).any() or (success < 0).any() or (success > 1).any():
        raise ValueError("records: expected sigma > 0 and success rates in [0, 1]")
    records = []
    for row in table.tolist():
        values = dict(zip(GenerationRecord._fields, row, strict=True))
        records.append(GenerationRecord(**{**values, **{key: int(values[key]) for key in COUNTS}}))
    return records
