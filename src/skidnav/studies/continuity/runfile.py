"""What one run of the continuity study stores (:data:`CONTINUITY_LAYOUT`), and its traces back.

A run is one learner's run k (:mod:`skidnav.studies.continuity.comparison`): its final
policy's R evaluation rollouts, each a :class:`~skidnav.studies.continuity.traces.Trace` of T_r
actions. Its run file (:class:`~skidnav.experiments.store.ResultStore`) holds

* per rollout (the runner's episode columns, :data:`EPISODE_COLUMNS`, each shape (R,)):
  ``actions`` T_r, ``truncated``, and the trace's metrics (:class:`~skidnav.studies.continuity.
  traces.TraceMetrics`: success, time to goal [s], path length [m], wheel change [rad/s],
  reversals per metre [1/m], energy [rad²/s], collisions);
* the traces themselves, rollout after rollout: ``poses`` float64 (Σ (T_r + 1), 3) [m, m, rad],
  ``commands`` float64 (Σ T_r, 2) [rad/s], ``rewards`` float64 (Σ T_r,), ``collided`` bool
  (Σ T_r,);
* the summary: real episodes used and to learn (NaN: never), wall time of training and its
  checks [s], share of rollouts at the goal, control period [s], the integer training seed.

So the report rebuilds every trace exactly (:func:`traces_of`) and computes the comparison from
the results directory alone.
"""

from __future__ import annotations

import numpy as np

from skidnav.experiments.runs import RunSpec
from skidnav.experiments.store import RunLayout, TrialResult
from skidnav.files.saved import ArraySpec, up_to
from skidnav.studies.continuity.comparison import (
    ComparisonConfig,
    LearnerRun,
    comparison_from_dict,
    comparison_to_dict,
)
from skidnav.studies.continuity.traces import Trace, TraceMetrics, metric_rows

EPISODE_COLUMNS = ("actions", "truncated", *TraceMetrics._fields)
"""The per-rollout columns of a run (``episodes.parquet``: one row per rollout)."""


def run_result(spec: RunSpec[ComparisonConfig], run: LearnerRun) -> TrialResult:
    """The runner's result of run ``spec``: ``run``'s rollouts as described in the module doc."""
    traces = run.traces
    metrics = metric_rows(traces)
    episodes: dict[str, np.ndarray] = {
        "actions": np.array([trace.n_actions for trace in traces], dtype=np.int64),
        "truncated": np.array([trace.truncated for trace in traces], dtype=bool),
    }
    for column, name in enumerate(TraceMetrics._fields):
        episodes[name] = metrics[:, column]
    arrays = {
        "poses": _joined([trace.poses for trace in traces], (0, 3)),
        "commands": _joined([trace.commands for trace in traces], (0, 2)),
        "rewards": _joined([trace.rewards for trace in traces], (0,)),
        "collided": _joined([trace.collisions for trace in traces], (0,)).astype(bool),
    }
    summary = {
        "episodes_used": run.episodes_used,
        "episodes_to_learn": run.episodes_to_learn,
        "wall_time": run.wall_time,
        "success": float(np.mean([trace.terminated for trace in traces])),
        "control_period": traces[0].control_period if traces else spec.config.control_period,
        "run_seed": run.seed,
    }
    return TrialResult(spec.run_id, spec.coordinates, episodes, summary, arrays)


def _joined(parts: list[np.ndarray], empty: tuple[int, ...]) -> np.ndarray:
    return np.concatenate(parts) if parts else np.zeros(empty)


def traces_of(result: TrialResult) -> tuple[Trace, ...]:
    """The rollouts of a stored run, in order, exactly as recorded."""
    actions = np.asarray(result.episodes["actions"], dtype=np.int64)
    success = np.asarray(result.episodes["success"])
    truncated = np.asarray(result.episodes["truncated"], dtype=bool)
    period = float(result.summary["control_period"])
    traces, step, pose = [], 0, 0
    for number, length in enumerate(actions.tolist()):
        traces.append(
            Trace(
                poses=result.arrays["poses"][pose : pose + length + 1],
                commands=result.arrays["commands"][step : step + length],
                control_period=period,
                rewards=result.arrays["rewards"][step : step + length],
                collisions=result.arrays["collided"][step : step + length],
                terminated=bool(success[number] == 1.0),
                truncated=bool(truncated[number]),
            )
        )
        step, pose = step + length, pose + length + 1
    return tuple(traces)


def run_file_specs(config: ComparisonConfig) -> dict[str, ArraySpec]:
    """What a run file of ``config`` may hold besides its document: ``rollouts`` entries per
    column, at most ``max_steps`` actions per rollout."""
    rollouts = up_to(config.rollouts)
    steps = up_to(config.rollouts * config.max_steps)
    poses = up_to(config.rollouts * (config.max_steps + 1))
    specs = {f"episode.{name}": ArraySpec((rollouts,), kinds="fiub") for name in EPISODE_COLUMNS}
    specs["array.poses"] = ArraySpec((poses, 3), "<f8")
    specs["array.commands"] = ArraySpec((steps, 2), "<f8")
    specs["array.rewards"] = ArraySpec((steps,), "<f8")
    specs["array.collided"] = ArraySpec((steps,), kinds="b")
    return specs


CONTINUITY_LAYOUT = RunLayout(
    "continuity", EPISODE_COLUMNS, comparison_to_dict, comparison_from_dict, run_file_specs
)
"""The results directory of the continuity study (:class:`~skidnav.experiments.store.RunLayout`)."""
