"""Property: every loader of a user's file (:mod:`tests.saved_loaders`), given random bytes or a
valid file damaged at random (bytes flipped, cut short, bytes inserted or overwritten), either
loads it or raises :class:`~skidnav.errors.UserError` in one line — never another exception,
never a hang."""

from __future__ import annotations

import itertools
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from skidnav.errors import UserError
from tests.saved_file_support import within
from tests.saved_loaders import DEEP_LOADERS, LOADERS, fresh_copy, pristine

MAX_SECONDS = 10.0
"""Longest a load may take (the slowest valid one takes well under a second)."""
PROPERTY = settings(
    max_examples=25,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
_copies = itertools.count()


def _load(name: str, path: Path) -> None:
    """Load ``path`` with loader ``name``: success, or one UserError line, within the time."""
    try:
        with within(MAX_SECONDS):
            LOADERS[name].load(path)
    except UserError as error:
        assert "\n" not in str(error), str(error)


@st.composite
def damage(draw: st.DrawFn, data: bytes) -> bytes:
    """``data`` with one random kind of damage."""
    kind = draw(st.sampled_from(["flip", "cut", "insert", "overwrite", "random"]))
    at = draw(st.integers(0, max(len(data) - 1, 0)))
    if kind == "random":
        return draw(st.binary(max_size=4096))
    if kind == "cut":
        return data[:at]
    if kind == "flip":
        flipped = bytearray(data)
        for position in draw(st.lists(st.integers(0, max(len(data) - 1, 0)), max_size=8)):
            if flipped:
                flipped[position] ^= draw(st.integers(1, 255))
        return bytes(flipped)
    chunk = draw(st.binary(min_size=1, max_size=64))
    end = at if kind == "insert" else at + len(chunk)
    return data[:at] + chunk + data[end:]


def _fresh(name: str, tmp_path: Path) -> tuple[Path, list[Path]]:
    return fresh_copy(name, Path(tempfile.mkdtemp(dir=tmp_path)) / f"copy-{next(_copies)}")


@pytest.mark.parametrize("name", LOADERS)
def test_a_damaged_file_loads_or_is_one_line(name: str, tmp_path: Path) -> None:
    if name in DEEP_LOADERS:
        pytest.importorskip("stable_baselines3")
    _, _, files = pristine(name)

    @PROPERTY
    @given(index=st.integers(0, len(files) - 1), data=st.data())
    def check(index: int, data: st.DataObject) -> None:
        path, copies = _fresh(name, tmp_path)
        target = copies[index]
        target.write_bytes(data.draw(damage(target.read_bytes()), label="damaged"))
        _load(name, path)

    check()


@pytest.mark.parametrize("name", LOADERS)
def test_random_bytes_load_or_are_one_line(name: str, tmp_path: Path) -> None:
    if name in DEEP_LOADERS:
        pytest.importorskip("stable_baselines3")
    _, _, files = pristine(name)

    @PROPERTY
    @given(index=st.integers(0, len(files) - 1), content=st.binary(max_size=8192))
    def check(index: int, content: bytes) -> None:
        path, copies = _fresh(name, tmp_path)
        copies[index].write_bytes(content)
        _load(name, path)

    check()
