"""Shared fixtures of the experiment tests: a tiny config file and its serial results."""

from __future__ import annotations

from pathlib import Path

import pytest

from skidnav.experiments.configfile import parse_config
from skidnav.experiments.runner import run_experiment
from tests.browser_support import browser  # noqa: F401  (a fixture, found by name)
from tests.experiments.exp_support import TINY_TOML


@pytest.fixture(scope="session")
def tiny_config_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("config") / "tiny.toml"
    path.write_text(TINY_TOML)
    return path


@pytest.fixture(scope="session")
def serial_results(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The tiny config run serially in this process."""
    out = tmp_path_factory.mktemp("serial")
    run_experiment(parse_config(TINY_TOML), out, backend="serial")
    return out
