"""Helpers shared by the experiment tests: a tiny config, CLI subprocess commands."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pandas as pd

from skidnav.experiments.store import ResultStore

SRC = Path(__file__).resolve().parents[2] / "src"

TINY_TOML = """
[experiment]
name = "tiny"
episodes = 6
max_steps = 60
seeds = 2
root_seed = 11
presets = ["rough", "slippery"]
bootstrap_samples = 200
convergence_window = 2
eval_rollouts = 2
oracle_samples = 4

[[maps]]
kind = "free"

[[agents]]
name = "q-learning"

[[agents]]
name = "dyna-q"
label = "dyna-q-5"
params = { planning_steps = 5 }
"""
"""2 agents × 1 map × 2 presets × 2 seeds = 8 runs of 6 short episodes."""


def cli_env() -> dict[str, str]:
    """Environment of a ``python -m skidnav.cli`` subprocess."""
    env = dict(os.environ)
    env["PYTHONPATH"] = str(SRC)
    return env


def cli_command(*args: str) -> list[str]:
    """argv of ``python -m skidnav.cli ARGS``."""
    return [sys.executable, "-m", "skidnav.cli", *args]


def comparable(run_dir: Path) -> pd.DataFrame:
    """The episode records of a results dir without wall times, sorted, for equality checks."""
    episodes, _ = ResultStore(run_dir).load_tables()
    return (
        episodes.drop(columns=["wall_time"])
        .sort_values(["run_id", "episode"])
        .reset_index(drop=True)
    )
