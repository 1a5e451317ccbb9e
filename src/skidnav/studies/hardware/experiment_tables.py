"""The real-robot study's tables of an experiment run by the runner (``skidnav report RUN_DIR
--study``), e.g. the study on the MuJoCo robot, ``configs/physics-study.toml``.

A hardware-in-the-loop study (:mod:`skidnav.studies.hardware.study`) and an experiment of the runner
store their episodes alike; this module summarises each run of a results directory as a study
run (:func:`~skidnav.studies.hardware.trial.run_summary`: success over all episodes and over the
last half, episode length; nothing is aborted without a safety layer) and formats them with the
study's tables (:func:`~skidnav.studies.hardware.report.markdown_report`): per agent × preset,
rough vs slippery floor, and each agent minus the baseline, paired by preset and seed. A
preset's floor is its slip preset; it drifts when the experiment's slip drifts.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from skidnav.experiments.store import ResultStore
from skidnav.studies.hardware.report import markdown_report
from skidnav.studies.hardware.trial import run_summary

RUN_COLUMNS = ("agent", "preset", "seed", "map")
"""The grid coordinates every study summary carries."""


def study_summaries(episodes: pd.DataFrame) -> pd.DataFrame:
    """One study summary per run of an experiment's episode table (``episodes.parquet``: a row
    per (run, episode) with ``return``, ``length``, ``success``, ``collisions``,
    ``wall_time``)."""
    rows = []
    for run_id, run in episodes.groupby("run_id", sort=True):
        arrays = {key: run[key].to_numpy() for key in ("return", "length", "collisions")}
        arrays["success"] = run["success"].to_numpy(dtype=bool)
        arrays["aborted"] = np.zeros(len(run), dtype=bool)
        arrays["wall_time"] = run["wall_time"].to_numpy(dtype=float)
        coordinates = {key: run[key].iloc[0] for key in RUN_COLUMNS}
        rows.append({"run_id": run_id, **coordinates, **run_summary(arrays, 0)})
    return pd.DataFrame(rows)


def experiment_study_report(run_dir: Path | str) -> str:
    """The study's markdown tables of the experiment in ``run_dir`` (module doc)."""
    store = ResultStore(run_dir)
    config = store.config()
    episodes, _ = store.load_tables()
    drifting = config.drift_amplitude != 0.0
    conditions = {preset: (preset, drifting) for preset in config.presets}
    summaries = study_summaries(episodes)
    wall = summaries["wall_time"].sum()
    actions = int(episodes["length"].sum())
    header = (
        f"{len(summaries)} runs, {len(episodes)} episodes, {actions} actions, "
        f"{wall:.0f} s of training ({actions / wall:.1f} actions/s).\n\n"
    )
    return header + markdown_report(summaries, config, conditions)
