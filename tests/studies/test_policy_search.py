"""The CMA-ES policy search as a study: a config run by ``skidnav run`` (one run file per preset
and seed, each search with its own seeds, the same numbers on the serial and the process
backend), a policy file written from the results equal to the one of ``skidnav study search``,
the report section, and bad configs as one line and exit code 2."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from skidnav.agents.policies.search.policy_file import load_policy
from skidnav.cli import main
from skidnav.experiments.store import ResultStore
from skidnav.studies.policy_search.export import export_search
from skidnav.studies.policy_search.grid import LAYOUT
from skidnav.studies.policy_search.report import report_section
from tests.cli_support import exit_code

SEARCH = """
[search]
map_kind = "free"
world_seed = 3
max_episode_steps = 20
hidden = 2
population = 6
generations = 2
episodes_per_candidate = 1
eval_episodes = 2
"""
TINY = 'kind = "policy-search"\npresets = ["thesis", "slippery"]\nseeds = 2\nroot_seed = 5\n'
TINY += SEARCH
SHORTCUT = [
    "study", "search", "--map", "free", "--world-seed", "3", "--max-steps", "20", "--hidden", "2",
    "--population", "6", "--generations", "2", "--episodes", "1", "--eval-episodes", "2",
]  # fmt: skip
"""The same search as ``TINY``'s ``[search]`` on one preset and seed."""
CLOCK = "wall_time"
"""The one column that differs between two runs of the same config."""


@pytest.fixture(scope="module")
def serial(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The results of :data:`TINY` run by ``skidnav run --backend serial``."""
    folder = tmp_path_factory.mktemp("search")
    (folder / "tiny.toml").write_text(TINY)
    out = folder / "serial"
    arguments = ["--out", str(out), "--backend", "serial", "--no-progress"]
    assert main(["run", str(folder / "tiny.toml"), *arguments]) == 0
    return out


def _tables(out: Path) -> tuple[pd.DataFrame, pd.DataFrame]:
    curves, summaries = ResultStore(out, LAYOUT).load_tables()
    return curves.drop(columns=CLOCK), summaries.drop(columns=CLOCK)


def test_one_run_file_per_preset_and_seed_the_same_on_both_backends(
    serial: Path, tmp_path: Path
) -> None:
    assert len(list((serial / "runs").glob("run-*.npz"))) == 4
    curves, summaries = _tables(serial)
    assert list(zip(summaries["preset"], summaries["seed"], strict=True)) == [
        ("thesis", 0), ("thesis", 1), ("slippery", 0), ("slippery", 1)
    ]  # fmt: skip
    assert summaries["search_seed"].nunique() == 4  # each search its own seeds
    assert (summaries["generations"] == 2).all() and len(curves) == 4 * 3
    process = tmp_path / "process"
    arguments = ["--out", str(process), "--backend", "process", "--jobs", "2", "--no-progress"]
    assert main(["run", str(serial.parent / "tiny.toml"), *arguments]) == 0
    for mine, theirs in zip(_tables(process), (curves, summaries), strict=True):
        pd.testing.assert_frame_equal(mine, theirs)
    for run_id in summaries["run_id"]:
        runs = [ResultStore(out, LAYOUT).read_run(run_id) for out in (serial, process)]
        assert np.array_equal(runs[0].arrays["parameters"], runs[1].arrays["parameters"])


def test_the_policy_file_of_a_run_is_the_one_of_the_shortcut(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = tmp_path / "one.toml"
    config.write_text('kind = "policy-search"\nroot_seed = 7\n' + SEARCH)
    results = tmp_path / "results"
    assert main(["run", str(config), "--out", str(results), "--backend", "serial"]) == 0
    exported = tmp_path / "exported"
    exported.mkdir()
    names = [path.name for path in export_search(results, "run-000000", exported)]
    assert names == ["policy.npz", "policy.json", "curve.csv", "search.json"]
    shortcut = tmp_path / "shortcut"
    assert main([*SHORTCUT, "--seed", "7", "--out", str(shortcut)]) == 0
    policies = [load_policy(out / "policy") for out in (exported, shortcut)]
    assert np.array_equal(policies[0].parameters, policies[1].parameters)
    assert ResultStore(shortcut, LAYOUT).config() == ResultStore(results, LAYOUT).config()


def test_the_report_section_has_the_curves_and_the_final_scores(serial: Path) -> None:
    section = report_section(serial)
    assert "4 of 4 runs finished" in section and section.count("<img") == 2
    assert "<h3>Slip preset slippery</h3>" in section and "final success" in section
    summaries = ResultStore(serial, LAYOUT).load_tables()[1]
    assert f"{summaries['final_return'].iloc[0]:.3g}" in section


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("seedz = 2\n" + SEARCH, "(did you mean 'seeds'? expected one of kind, name, presets"),
        ("seeds = 0\n" + SEARCH, "expected seeds to be an integer in [1, 1000], got 0"),
        ('presets = ["ice"]\n' + SEARCH, "expected presets to be distinct slip presets among"),
        ('presets = "thesis"\n' + SEARCH, "expected presets to be distinct slip presets"),
        (
            SEARCH + 'slip = "rough"\n',
            "key 'slip' is set per run in {config}: [search] (list presets, give root_seed)\n",
        ),
        (SEARCH + "populaton = 4\n", "bad.toml: [search] (did you mean 'population'?"),
        (SEARCH.replace("population = 6", "population = 1"), "expected population to be an"),
    ],
)
def test_a_bad_config_is_one_line_and_exit_code_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, message: str
) -> None:
    config = tmp_path / "bad.toml"
    config.write_text(f'kind = "policy-search"\n{text}')
    assert exit_code(["run", str(config), "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    message = message.replace("{config}", str(config))
    assert error.count("\n") == 1 and str(config) in error and message in error, error
    assert not (tmp_path / "out").exists()
