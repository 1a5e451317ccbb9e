"""A full disk while ``skidnav run`` writes (a run file, its tables, its metadata) is one line
naming the file, leaves no temporary behind and loses nothing: the same command, with room
again, resumes to the results of a run never interrupted."""

from __future__ import annotations

import errno
from pathlib import Path

import pandas as pd
import pytest

from skidnav.cli import main
from skidnav.experiments.store import ResultStore
from skidnav.files import atomic as atomicfile
from tests.experiments.exp_support import comparable


def _full_disk(monkeypatch: pytest.MonkeyPatch, name: str) -> None:
    """Writes of the file called ``name`` fail with "No space left on device"."""
    real = atomicfile.write_atomic

    def write(path: Path | str, data: bytes) -> None:
        if Path(path).name == name:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(path, data)

    monkeypatch.setattr(atomicfile, "write_atomic", write)


@pytest.mark.parametrize(
    ("full", "what"),
    [("run-000003.npz", "run file"), ("episodes.parquet", "table"), ("metadata.json", "metadata")],
)
def test_a_full_disk_during_a_run_is_one_line_and_the_run_resumes(
    full: str,
    what: str,
    serial_results: Path,
    tiny_config_file: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = tmp_path / "out"
    argv = ["run", str(tiny_config_file), "--out", str(out), "--backend", "serial", "--no-progress"]
    with monkeypatch.context() as patch:
        _full_disk(patch, full)
        assert main(argv) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"skidnav: error: {out}"), lines
    assert lines[0].endswith(f"{full}: cannot write the {what} (No space left on device)")
    assert not list(out.rglob("*.tmp"))
    assert main(argv) == 0
    pd.testing.assert_frame_equal(comparable(out), comparable(serial_results))
    summaries = [ResultStore(root).load_tables()[1] for root in (out, serial_results)]
    timeless = [frame.drop(columns=[c for c in frame if "time" in c]) for frame in summaries]
    pd.testing.assert_frame_equal(*timeless)
