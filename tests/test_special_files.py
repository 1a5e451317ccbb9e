"""Paths that name no regular file, given to every loader: a FIFO nobody writes, a socket, a
device that never ends, a directory. Each is refused in one line at once, before anything is
read (a FIFO used to block the open forever, ``/dev/urandom`` to fill the memory); configs may
come through a pipe, which is read up to its limit. Also: the descriptor is checked after the
open, a zip directory is checked before ``zipfile`` reads it, and ``--policy-file`` through the
command line."""

from __future__ import annotations

import os
import struct
import threading
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest
from numpy.lib import format as npy_format

from skidnav.cli import main
from skidnav.errors import CorruptFileError, UserError
from skidnav.experiments.configfile import load_config
from skidnav.files import user as userfile
from skidnav.files.saved import MAX_DIRECTORY_BYTES, MAX_MEMBERS, ArraySpec, SavedArchive
from skidnav.files.user import open_user_file, read_limited
from tests.saved_file_support import replace_with, within, write_npz
from tests.saved_loaders import DEEP_LOADERS, LOADERS, fresh_copy

KINDS = ("fifo", "socket", "device", "directory")
REFUSED = {
    "fifo": "(a FIFO, not a regular file)",
    "socket": "(a socket, not a regular file)",
    "device": "(a character device, not a regular file)",
    "directory": "(a directory, not a regular file)",
}
PIPE_READERS = ("experiment config", "tune config", "realtime config")
"""Loaders of text a pipe may carry: a FIFO is waited on for its writer, up to a time limit."""


def _cases() -> list[tuple[str, int]]:
    """(loader, index of the file to replace): every file of every loader (the counts are
    those of :mod:`tests.saved_loaders`' valid files)."""
    pairs = {"tabular agent", "linear agent", "kinematic model", "tanh policy", *DEEP_LOADERS}
    pairs |= {"linear policy"}
    pairs |= {"CMA-ES checkpoint", "real-time checkpoint", "tidy tables"}
    return [(name, index) for name in LOADERS for index in range(2 if name in pairs else 1)]


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize(("name", "index"), _cases())
def test_a_special_file_is_refused_in_one_line_at_once(
    name: str, index: int, kind: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    if name in DEEP_LOADERS:
        pytest.importorskip("stable_baselines3")
    monkeypatch.setattr(userfile, "PIPE_TIMEOUT_S", 0.2)
    path, files = fresh_copy(name, tmp_path / "copy")
    target = files[index]
    expected = REFUSED[kind]
    if kind == "fifo" and name in PIPE_READERS:
        expected = "(its writer did not finish within 0.2 s)"
    with replace_with(target, kind), within(5.0), pytest.raises(UserError) as error:
        LOADERS[name].load(path)
    message = str(error.value)
    assert "\n" not in message and str(target) in message and expected in message, message


def test_the_opened_descriptor_is_checked_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A path swapped for a FIFO between the check and the open: the open does not block
    (``O_NONBLOCK``) and the descriptor's own kind refuses it."""
    regular, fifo = tmp_path / "regular.json", tmp_path / "swapped.json"
    regular.write_text("{}")
    os.mkfifo(fifo)
    real_stat = os.stat
    monkeypatch.setattr(userfile.os, "stat", lambda path: real_stat(regular))
    with within(5.0), pytest.raises(CorruptFileError, match=r"swapped.json: .*\(a FIFO, not"):
        open_user_file(fifo, "policy file")


def test_a_pipe_that_never_ends_is_read_up_to_the_limit(tmp_path: Path) -> None:
    pipe = tmp_path / "config.toml"
    os.mkfifo(pipe)

    def endless() -> None:
        chunk = b"#" * 65536
        try:
            with open(pipe, "wb") as stream:
                while True:
                    stream.write(chunk)
        except BrokenPipeError:
            return

    writer = threading.Thread(target=endless, daemon=True)
    writer.start()
    with within(20.0), pytest.raises(UserError, match="config file larger than 4,000,000 bytes"):
        load_config(pipe)
    writer.join(5)
    assert not writer.is_alive()


def test_a_pipe_is_waited_on_for_its_writer_within_a_limit(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pipe = tmp_path / "actions.txt"
    os.mkfifo(pipe)
    monkeypatch.setattr(userfile, "PIPE_TIMEOUT_S", 0.3)
    with within(5.0):
        with pytest.raises(UserError, match=r"actions.txt: cannot read action file \(a FIFO"):
            read_limited(pipe, 100, "action file", UserError)
        with pytest.raises(UserError, match=r"\(its writer did not finish within 0.3 s\)$"):
            read_limited(pipe, 100, "action file", UserError, pipes=True)

    def late_writer() -> None:
        time.sleep(0.1)  # after the reader opened the FIFO
        with open(pipe, "wb") as stream:
            stream.write(b"f f l")

    writer = threading.Thread(target=late_writer, daemon=True)
    writer.start()
    with within(5.0):
        assert read_limited(pipe, 100, "action file", UserError, pipes=True) == b"f f l"
    writer.join(5)


def test_a_file_longer_than_its_size_says_is_cut_at_the_limit() -> None:
    """Files of ``/proc`` report size 0: the read itself stops at the limit."""
    environment = Path("/proc/self/environ")
    assert environment.stat().st_size == 0
    with pytest.raises(CorruptFileError, match=r"environ: file larger than 8 bytes"):
        read_limited(environment, 8)
    assert len(read_limited(environment, 10**6)) > 8


@pytest.mark.parametrize("suffix", [".json", ".npz"])
@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_policy_file_through_the_command_line(
    suffix: str, kind: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The reported hang (a FIFO) and memory exhaustion (``/dev/urandom`` as the ``.npz``)."""
    copy, files = fresh_copy("tanh policy", tmp_path / "policy")
    target = next(file for file in files if file.suffix == suffix)
    argv = ["robot", "run", "--driver", "tcp", "--policy-file", str(copy)]
    with replace_with(target, kind), within(20.0):
        code = main([*argv, "--out", str(tmp_path / "out")])
    lines = capsys.readouterr().err.strip().splitlines()
    what = "policy file" if suffix == ".json" else "file"
    assert code == 2 and lines == [f"skidnav: error: {target}: cannot read {what} {REFUSED[kind]}"]
    assert not (tmp_path / "out").exists()


def _end_record(entries: int, directory_bytes: int) -> bytes:
    """A zip end-of-directory record announcing ``entries`` entries in ``directory_bytes``."""
    return b"PK\x05\x06" + struct.pack("<HHHHIIH", 0, 0, entries, entries, directory_bytes, 0, 0)


@pytest.mark.parametrize(
    ("tail", "message"),
    [
        (_end_record(MAX_MEMBERS + 1, 100), f"a directory of {MAX_MEMBERS + 1:,} entries"),
        (_end_record(3, MAX_DIRECTORY_BYTES + 1), f"3 entries in {MAX_DIRECTORY_BYTES + 1:,}"),
        (b"PK\x06\x07" + bytes(16) + _end_record(1, 46), "a ZIP64 directory"),
        (b"just bytes", "no zip directory"),
    ],
    ids=["entries", "bytes", "zip64", "none"],
)
def test_a_zip_directory_is_checked_before_zipfile_reads_it(
    tail: bytes, message: str, tmp_path: Path
) -> None:
    path = tmp_path / "forged.npz"
    path.write_bytes(bytes(3 * 2**20) + tail)  # zipfile would read the 3 MiB as its directory
    with pytest.raises(CorruptFileError, match=f"not a readable .npz archive \\(.*{message}"):
        SavedArchive(path).__enter__()  # refused on entering: nothing to close


def test_members_announcing_more_than_the_budget_are_refused_from_the_directory(
    tmp_path: Path,
) -> None:
    path = tmp_path / "big.npz"
    with zipfile.ZipFile(path, "w") as archive:
        for name in ("a.npy", "b.npy"):
            archive.writestr(name, b"x")
    data = bytearray(path.read_bytes())
    for at in range(len(data) - 4):  # each central directory entry: uncompressed size at +24
        if data[at : at + 4] == b"PK\x01\x02":
            data[at + 24 : at + 28] = struct.pack("<I", 2**31)
    path.write_bytes(bytes(data))
    with (
        pytest.raises(CorruptFileError, match=r"members of 4,294,967,296 bytes, expected at"),
        SavedArchive(path, max_bytes=2**20),
    ):
        pass


def test_an_archive_within_the_limits_still_reads(tmp_path: Path) -> None:
    path = tmp_path / "fine.npz"
    np.savez(path, q=np.arange(6.0), **{f"m{i}": np.zeros(1) for i in range(MAX_MEMBERS - 1)})
    with SavedArchive(path) as archive:
        assert archive.read("q", ArraySpec((6,), "<f8")).tolist() == list(range(6))


@pytest.mark.parametrize("header", ["{" * 100, "'''", "{" * 3000 + "}" * 3000])
def test_a_npy_header_that_is_no_literal_is_one_line(header: str, tmp_path: Path) -> None:
    """NumPy parses the header as a Python literal; what its tokenizer raises is caught too."""
    path = tmp_path / "odd.npz"
    text = header.encode("latin1") + b"\n"
    write_npz(path, {"q": npy_format.magic(1, 0) + len(text).to_bytes(2, "little") + text})
    with (
        pytest.raises(CorruptFileError, match=r"array 'q': bad .npy header"),
        SavedArchive(path) as archive,
    ):
        archive.read("q", ArraySpec((6,), "<f8"))
