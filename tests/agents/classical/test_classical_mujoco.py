"""The classical navigator on the MuJoCo Jackal with the settings of
configs/barn-mujoco-zero-shot.toml: a BARN run leaves the start and reaches the goal where the
datasheet navigator stalled (world 0: it stood still at (2.62, 6.99) m from 5 s on)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

pytest.importorskip("mujoco")

from skidnav.cli import main
from skidnav.experiments.store import ResultStore
from skidnav.studies.barn.grid import LAYOUT

SHIPPED = Path(__file__).parents[3] / "configs" / "barn-mujoco-zero-shot.toml"


def test_a_mujoco_barn_run_leaves_the_start_and_reaches_the_goal(tmp_path: Path) -> None:
    agents = tomllib.loads(SHIPPED.read_text(encoding="utf-8"))["agents"]
    (params,) = [agent["params"] for agent in agents if agent.get("label") is None
                 and agent["name"] == "classical"]  # fmt: skip
    shown = ", ".join(f"{key} = {value!r}" for key, value in params.items())
    config = tmp_path / "mujoco.toml"
    config.write_text(
        'kind = "barn"\n[barn]\nworlds = [0]\ndynamics = "mujoco"\nlidar_rays = 271\n'
        f'[[agents]]\nname = "classical"\nparams = {{ {shown} }}\n',
        encoding="utf-8",
    )
    out = tmp_path / "run"
    arguments = ["run", str(config), "--out", str(out), "--backend", "serial", "--no-progress"]
    assert main(arguments) == 0
    (row,) = ResultStore(out, LAYOUT).load_tables()[0].itertuples()
    assert row.clock_start < 1.0  # it left the start at once
    assert row.success and row.time < 15.0, (row.success, row.collision, row.time)
