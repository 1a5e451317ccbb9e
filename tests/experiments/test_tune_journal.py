"""The tune journal is checked before Optuna replays it and before anything repairs it: a file
that is not a journal is one line and is never changed; only a valid journal whose last line a
kill cut short loses that line."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from skidnav.cli import main
from skidnav.errors import CorruptFileError
from skidnav.experiments.journalfile import check_journal
from skidnav.studies.tuning.optuna_setup import open_storage
from skidnav.studies.tuning.search import JOURNAL
from tests.saved_loaders import fresh_copy

LINE = b'{"op_code":4,"worker_id":"w","study_id":0,"datetime_start":null}\n'
"""A whole, valid line: a trial created in the first study."""

CASES: dict[str, tuple[bytes, str]] = {
    # name: (what follows the valid journal, the error)
    "unknown op code": (b'{"op_code":42,"worker_id":"w"}\n', ":10: unknown op code 42"),
    "op code as text": (b'{"op_code":"4","worker_id":"w"}\n', ":10: unknown op code '4'"),
    "no worker id": (b'{"op_code":4,"study_id":0}\n', ":10: expected a string worker_id"),
    "missing field": (b'{"op_code":5,"worker_id":"w"}\n', ":10: cannot be replayed (KeyError"),
    "unknown study": (LINE.replace(b'"study_id":0', b'"study_id":[1]'), ":10: cannot be replayed"),
    "not JSON": (b"op_code 4\n", ":10: invalid JSON"),
    "not an object": (b"[4]\n", ":10: expected a JSON object"),
    "nested": (
        b'{"op_code":4,"worker_id":"w","x":' + b"[" * 100 + b"\n",
        ":10: JSON nested 101 deep",
    ),
    "not UTF-8": (b'{"op_code":4,"worker_id":"\xff"}\n', ":10: not UTF-8 text"),
    "garbage after": (LINE + b"\x00\x01garbage", ":11: not an Optuna journal line"),
}


def _journal(tmp_path: Path) -> Path:
    path, _ = fresh_copy("tune journal", tmp_path / "study")
    assert check_journal(path).lines == 9
    return path


@pytest.mark.parametrize("case", CASES)
def test_a_damaged_journal_is_one_line_and_left_as_it_is(case: str, tmp_path: Path) -> None:
    journal = _journal(tmp_path)
    tail, message = CASES[case]
    journal.write_bytes(journal.read_bytes() + tail)
    before = journal.read_bytes()
    with pytest.raises(CorruptFileError) as error:
        open_storage(journal)
    assert message in str(error.value) and "\n" not in str(error.value)
    assert journal.read_bytes() == before


def test_random_bytes_are_never_truncated(tmp_path: Path) -> None:
    journal = tmp_path / JOURNAL
    for seed in range(20):
        data = os.urandom(200 + seed) + b"\n" + os.urandom(17)  # a "last line" of 17 bytes
        journal.write_bytes(data)
        with pytest.raises(CorruptFileError):
            open_storage(journal)
        assert journal.read_bytes() == data


@pytest.mark.parametrize("cut", [1, 5, 11, 30, len(LINE) - 1])
def test_a_line_cut_short_is_dropped_and_the_rest_kept(cut: int, tmp_path: Path) -> None:
    journal = _journal(tmp_path)
    whole = journal.read_bytes()
    journal.write_bytes(whole + LINE[:cut])
    assert check_journal(journal).torn_bytes == cut
    open_storage(journal, repair=False)  # a reader leaves it
    assert journal.read_bytes() == whole + LINE[:cut]
    open_storage(journal)
    assert journal.read_bytes() == whole


def test_a_directory_as_journal_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from tests.experiments.test_tune import TINY_TUNE

    config, out = tmp_path / "tune.toml", tmp_path / "out"
    config.write_text(TINY_TUNE)
    (out / JOURNAL).mkdir(parents=True)
    assert main(["tune", str(config), "--out", str(out), "--backend", "serial"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines == [
        f"skidnav: error: {out / JOURNAL}: cannot read tune journal (a directory, not a regular "
        "file)"
    ]


def test_an_unknown_op_code_through_the_command_line_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from tests.experiments.test_tune import TINY_TUNE

    config, out = tmp_path / "tune.toml", tmp_path / "out"
    config.write_text(TINY_TUNE)
    out.mkdir()
    (out / JOURNAL).write_bytes(b'{"op_code":99,"worker_id":"w"}\n')
    assert main(["tune", str(config), "--out", str(out), "--backend", "serial"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and f"{out / JOURNAL}:1: unknown op code 99" in lines[0], lines
