"""One run of a policy-search study: one CMA-ES search (:mod:`skidnav.agents.policies.search`).

:class:`SearchTrial` is the runner's trial function of a
:class:`~skidnav.studies.policy_search.grid.PolicySearchGrid`: the search of
:func:`~skidnav.studies.policy_search.grid.run_search_config`, its results as the run's
(:func:`search_result`): the learning curve as the episode arrays (one per
:class:`~skidnav.agents.policies.search.curve.GenerationRecord` field, generations 0 .. G), the
final evaluation as the summary, the final mean policy's parameters and observation bounds as
the run's arrays (:func:`policy_of_run` builds the policy back from them).

A checkpoint per search (:mod:`skidnav.agents.policies.search.checkpoint`), when the trial is
given a folder for them: ``FOLDER/run-000042.npz`` (+ ``.json``), rewritten after every
generation; a run started again with its checkpoint there continues from it, with the numbers
of a search never stopped. The runner resumes a study run by run; the checkpoint resumes the one
long search a kill cut short.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from skidnav.agents.policies.search.curve import COUNTS, GenerationRecord
from skidnav.agents.policies.search.tanh_policy import PolicyLayout, TanhPolicy
from skidnav.agents.saving import save_paths
from skidnav.experiments.runs import RunSpec
from skidnav.experiments.store import TrialResult
from skidnav.studies.policy_search.grid import EPISODE_COLUMNS, PolicySearchGrid, run_search_config

if TYPE_CHECKING:  # the search itself needs the search extra (cmaes): imported by a run
    from skidnav.agents.policies.search.cmaes import SearchResult

GenerationCallback = Callable[[RunSpec[Any], GenerationRecord], None]
"""Called with the run and each of its new learning-curve records (module-level, so that it
can travel to a worker process)."""


@dataclass(frozen=True)
class SearchTrial:
    """The trial function of a policy-search study (module doc).

    Attributes:
        checkpoints: the folder of the searches' checkpoints (None: no checkpoint).
        on_generation: called with every new record of a search (None: nothing).
    """

    checkpoints: Path | None = None
    on_generation: GenerationCallback | None = None

    def __call__(self, spec: RunSpec[PolicySearchGrid]) -> TrialResult:
        """Run (or continue from its checkpoint) the search of ``spec``."""
        from skidnav.agents.policies.search.cmaes import run_search

        config = run_search_config(spec.config, spec.preset, spec.run_seed)
        checkpoint, resume = None, False
        if self.checkpoints is not None:
            self.checkpoints.mkdir(parents=True, exist_ok=True)
            checkpoint = self.checkpoints / spec.run_id
            resume = save_paths(checkpoint)[0].exists()
        report = None
        if self.on_generation is not None:
            report = functools.partial(self.on_generation, spec)
        result = run_search(config, checkpoint=checkpoint, resume=resume, on_generation=report)
        return search_result(spec, result)


def search_result(spec: RunSpec[Any], result: SearchResult) -> TrialResult:
    """The run's results of the search ``result`` (module doc). Summary: the last record's
    counts (``generations``, ``episodes``, ``evaluation_episodes``), wall time [s], scores
    (``best_return``, ``population_return``) and σ; the final mean policy's evaluation
    (``final_return``, ``final_success``); the best evaluation of the mean over the search
    (``peak_return``, ``peak_success``); the search's root seed (``search_seed``), the policy's
    size (``n_parameters``) and its largest wheel speed [rad/s] (``wheel_speed``)."""
    records = result.records
    episodes = {
        key: np.array(
            [getattr(record, key) for record in records],
            dtype=np.int64 if key in COUNTS else np.float64,
        )
        for key in EPISODE_COLUMNS
    }
    last, layout = records[-1], result.policy.layout
    summary: dict[str, float] = {
        "generations": last.generation,
        "episodes": last.episodes,
        "evaluation_episodes": last.evaluation_episodes,
        "wall_time": last.wall_time,
        "best_return": last.best_return,
        "population_return": last.population_return,
        "sigma": last.sigma,
        "final_return": last.mean_return,
        "final_success": last.mean_success,
        "peak_return": _peak(episodes["mean_return"]),
        "peak_success": _peak(episodes["mean_success"]),
        "search_seed": result.config.seed,
        "n_parameters": layout.n_parameters,
        "wheel_speed": layout.wheel_speed,
    }
    arrays = {
        "parameters": np.asarray(result.policy.parameters, dtype=np.float64),
        "observation_low": np.asarray(layout.observation_low, dtype=np.float64),
        "observation_high": np.asarray(layout.observation_high, dtype=np.float64),
    }
    return TrialResult(spec.run_id, spec.coordinates, episodes, summary, arrays)


def _peak(values: np.ndarray) -> float:
    """The largest of ``values`` that is not NaN (NaN if none is)."""
    finite = values[~np.isnan(values)]
    return float(finite.max()) if finite.size else math.nan


def policy_of_run(grid: PolicySearchGrid, result: TrialResult) -> TanhPolicy:
    """The final mean policy of a run's results ``result`` of ``grid``."""
    layout = PolicyLayout(
        result.arrays["observation_low"],
        result.arrays["observation_high"],
        hidden=grid.search.hidden,
        wheel_speed=float(result.summary["wheel_speed"]),
        lidar_rays=grid.search.lidar_rays,
        lidar_range=grid.search.lidar_range,
    )
    return TanhPolicy(layout, result.arrays["parameters"])


def records_of_run(result: TrialResult) -> list[GenerationRecord]:
    """The learning curve of a run's results ``result``."""
    columns = [result.episodes[key].tolist() for key in EPISODE_COLUMNS]
    return [GenerationRecord(*row) for row in zip(*columns, strict=True)]
