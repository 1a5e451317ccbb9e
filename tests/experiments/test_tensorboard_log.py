"""``skidnav run --tensorboard DIR``: the event files read back by TensorBoard equal the run's
episodes table; a resume writes them again without duplicates; without the ``logging`` extra
the command refuses in one line before any work."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given
from hypothesis import strategies as st
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from skidnav.cli import main
from skidnav.experiments.store import EPISODE_COLUMNS, ResultStore
from skidnav.experiments.tensorboard_log import EVENT_FILE, path_label, run_directory, scalar_tag

TAGS = {scalar_tag(column): column for column in EPISODE_COLUMNS}


@pytest.fixture(scope="module")
def logged(tmp_path_factory: pytest.TempPathFactory, tiny_config_file: Path) -> tuple[Path, Path]:
    """(results, TensorBoard directory) of the tiny config run serially with ``--tensorboard``."""
    root = tmp_path_factory.mktemp("tensorboard")
    out, logs = root / "results", root / "logs"
    arguments = ["run", str(tiny_config_file), "--out", str(out), "--backend", "serial"]
    assert main([*arguments, "--no-progress", "--tensorboard", str(logs)]) == 0
    return out, logs


def read_scalars(directory: Path) -> dict[str, pd.DataFrame]:
    """Every scalar series of a TensorBoard run directory, as TensorBoard reads it."""
    accumulator = EventAccumulator(str(directory), size_guidance={"scalars": 0})
    accumulator.Reload()
    return {
        tag: pd.DataFrame(accumulator.Scalars(tag), columns=["wall_time", "step", "value"])
        for tag in accumulator.Tags()["scalars"]
    }


def test_event_files_equal_the_episodes_table(logged: tuple[Path, Path]) -> None:
    out, logs = logged
    episodes, _ = ResultStore(out).load_tables()
    runs = list(episodes.groupby("run_id"))
    assert len(runs) == 8
    for _, table in runs:
        directory = run_directory(logs, table.iloc[0].to_dict())
        assert [path.name for path in directory.iterdir()] == [EVENT_FILE]
        scalars = read_scalars(directory)
        assert set(scalars) == set(TAGS)
        for tag, series in scalars.items():
            expected = table[TAGS[tag]].to_numpy(np.float64).astype(np.float32)
            assert series["step"].tolist() == table["episode"].tolist()
            np.testing.assert_array_equal(series["value"].to_numpy(np.float32), expected)
        # TensorBoard's relative time axis: the run's training time so far.
        times = scalars["train/return"]["wall_time"].to_numpy()
        elapsed = np.cumsum(table["wall_time"].to_numpy())
        np.testing.assert_allclose(times - times[0], elapsed - elapsed[0], atol=1e-5)


def test_directories_name_agent_map_preset_and_seed(logged: tuple[Path, Path]) -> None:
    _, logs = logged
    directories = {path.parent.relative_to(logs).as_posix() for path in logs.rglob(EVENT_FILE)}
    assert directories == {
        f"{agent}/free/{preset}/seed-{seed}"
        for agent in ("q-learning", "dyna-q-5")
        for preset in ("rough", "slippery")
        for seed in (0, 1)
    }


@pytest.mark.parametrize("where", ["same directory", "new directory"])
def test_a_resume_logs_every_finished_run_once(
    where: str,
    logged: tuple[Path, Path],
    tiny_config_file: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    out, logs = logged
    before = {path.relative_to(logs): read_scalars(path.parent) for path in logs.rglob(EVENT_FILE)}
    again = logs if where == "same directory" else tmp_path / "logs"
    arguments = ["run", str(tiny_config_file), "--out", str(out), "--backend", "serial"]
    assert main([*arguments, "--no-progress", "--tensorboard", str(again)]) == 0
    assert "(0 run now, 8 already done)" in capsys.readouterr().out
    after = {path.relative_to(again): read_scalars(path.parent) for path in again.rglob(EVENT_FILE)}
    assert after.keys() == before.keys()
    for path, scalars in after.items():
        assert scalars.keys() == before[path].keys()
        for tag, series in scalars.items():
            assert series["step"].is_unique
            pd.testing.assert_series_equal(series["value"], before[path][tag]["value"])


def test_without_tensorboard_the_run_is_refused_before_any_work(
    tiny_config_file: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setitem(sys.modules, "tensorboard", None)  # import tensorboard now fails
    out, logs = tmp_path / "results", tmp_path / "logs"
    code = main(["run", str(tiny_config_file), "--out", str(out), "--tensorboard", str(logs)])
    assert code == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        "skidnav: error: --tensorboard needs the logging extra (no module 'tensorboard'): "
        'pip install "skidnav[logging]"'
    ]
    assert not out.exists() and not logs.exists()


def test_an_unwritable_log_directory_is_refused_before_any_work(
    tiny_config_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "file").write_text("")
    out, logs = tmp_path / "results", tmp_path / "file" / "logs"
    code = main(["run", str(tiny_config_file), "--out", str(out), "--tensorboard", str(logs)])
    assert code == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and "choose another --tensorboard" in error[0]
    assert not out.exists()


@given(st.lists(st.text(min_size=1, max_size=12), min_size=2, max_size=6, unique=True))
def test_distinct_labels_get_distinct_plain_directory_names(labels: list[str]) -> None:
    names = [path_label(label) for label in labels]
    assert len(set(names)) == len(names)
    for name in names:
        assert "/" not in name and "\x00" not in name and not name.startswith(".")
