"""Every config shipped in configs/ loads with its loader: a preset that no longer parses (a
renamed agent, a bound tightened) fails here, not in a user's long run."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from skidnav.experiments.configfile import load_config
from skidnav.realtime.config import load_config as load_realtime_config
from skidnav.studies.loading import load_grid
from skidnav.studies.tuning.config import load_tune_config

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
SHIPPED = sorted(CONFIGS.glob("*.toml"))


def test_configs_are_shipped() -> None:
    assert len(SHIPPED) >= 10


@pytest.mark.parametrize("path", SHIPPED, ids=[path.name for path in SHIPPED])
def test_shipped_config_loads(path: Path) -> None:
    if path.name.startswith("realtime"):
        assert load_realtime_config(path).run.episodes > 0
    elif path.name.startswith("tune-"):
        experiment, tune = load_tune_config(path)
        assert experiment.agents and tune is not None
    elif "kind" in tomllib.loads(path.read_text()):  # a study config (docs/experiments.md)
        loaded = load_grid(path)
        assert loaded.study.kind == loaded.layout.kind and loaded.grid.n_runs > 0
    else:
        config = load_config(path)
        assert config.agents and config.seeds > 0 and config.episodes > 0
