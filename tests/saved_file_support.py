"""Helpers of the saved-file tests: hand-made ``.npz`` archives (forged headers, zip bombs,
strangers), special files (FIFOs, sockets), a watchdog for calls that must not hang, directory
listings, and commands run on a disk that fills up."""

from __future__ import annotations

import contextlib
import io
import os
import resource
import signal
import socket
import subprocess
import sys
import zipfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from types import FrameType

import numpy as np
from numpy.lib import format as npy_format

SRC = Path(__file__).resolve().parents[1] / "src"
BOMB_BYTES = 16 * 2**20
"""Zeros appended to a zip-bomb member (16 MiB that deflate to about 16 KiB)."""


def npy_bytes(array: np.ndarray) -> bytes:
    """``array`` as the bytes of a ``.npy`` file."""
    buffer = io.BytesIO()
    npy_format.write_array(buffer, np.asarray(array), allow_pickle=False)
    return buffer.getvalue()


def forged_npy(shape: tuple[int, ...], dtype: str = "<f8", payload: bytes = b"") -> bytes:
    """A ``.npy`` whose header announces ``shape`` and ``dtype`` but whose data is ``payload``."""
    buffer = io.BytesIO()
    header = {"descr": dtype, "fortran_order": False, "shape": shape}
    npy_format.write_array_header_1_0(buffer, header)
    return buffer.getvalue() + payload


def forged_header_length(length: int) -> bytes:
    """A version-2 ``.npy`` whose header claims to be ``length`` bytes long."""
    return npy_format.magic(2, 0) + length.to_bytes(4, "little") + b"{" * 64


def arrays_of(path: Path) -> dict[str, np.ndarray]:
    """Every array of an ``.npz`` (a test's own, trusted file)."""
    with np.load(path, allow_pickle=False) as archive:
        return {name: archive[name] for name in archive.files}


def write_npz(path: Path, members: Mapping[str, np.ndarray | bytes], bomb: str = "") -> None:
    """Write an ``.npz`` of ``members`` (arrays, or raw ``.npy`` bytes); the member ``bomb`` gets
    :data:`BOMB_BYTES` zeros after its data (a zip bomb: tiny compressed, huge uncompressed)."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for name, value in members.items():
            data = value if isinstance(value, bytes) else npy_bytes(value)
            with archive.open(f"{name}.npy", "w", force_zip64=True) as stream:
                stream.write(data)
                if name == bomb:
                    chunk = bytes(2**20)
                    for _ in range(BOMB_BYTES // len(chunk)):
                        stream.write(chunk)


def listing(root: Path) -> list[tuple[str, int]]:
    """Every file and folder under ``root`` with its size [bytes], sorted: equal listings before
    and after a refused command mean nothing was written and nothing left behind."""
    return sorted((str(p.relative_to(root)), p.stat().st_size) for p in root.rglob("*"))


def run_with_full_disk(
    arguments: list[str], max_file_bytes: int
) -> subprocess.CompletedProcess[str]:
    """``python ARGUMENTS`` in a subprocess that cannot grow any file past ``max_file_bytes``
    (``RLIMIT_FSIZE``: such a write fails with EFBIG, "File too large", as on a full disk;
    Python ignores the SIGXFSZ that comes with it). Its output goes to pipes, not files.
    Matplotlib's font cache is built here first: written from the subprocess, it would be cut
    short at the limit and break every later run."""
    import matplotlib.font_manager  # noqa: F401  (builds and writes the font cache)

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (max_file_bytes, max_file_bytes))

    environment = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1", "PYTHONPATH": str(SRC)}
    return subprocess.run(
        [sys.executable, *arguments], preexec_fn=limit, env=environment,
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip


def skidnav_with_full_disk(
    args: list[str], max_file_bytes: int
) -> subprocess.CompletedProcess[str]:
    """``skidnav ARGS`` through :func:`run_with_full_disk`."""
    return run_with_full_disk(["-m", "skidnav.cli", *args], max_file_bytes)


POINTER = '{"episode": 0, "directory": "ep-00000"}'
"""The ``latest.json`` of a run whose newest checkpoint is that of episode 0."""


def write_checkpoint(
    out: Path,
    agent: tuple[str, Mapping[str, np.ndarray]] | None = None,
    loop_state: str = '{"results": [], "wheel_speed_stats": []}',
    pointer: str = POINTER,
) -> Path:
    """A real-time run directory ``out`` whose ``checkpoints/latest.json`` is ``pointer`` and
    whose ``checkpoints/ep-00000`` holds ``loop.json`` and, when given, the agent's JSON text and
    ``.npz`` members as ``agent.json`` / ``agent.npz``; returns ``checkpoints/ep-00000``. With
    its ``run.jsonl`` and without ``robot-run.json`` it is a run of any config to ``--resume``
    (realtime/control/run_folder.py)."""
    directory = out / "checkpoints" / "ep-00000"
    directory.mkdir(parents=True, exist_ok=True)
    (out / "run.jsonl").touch()
    (directory / "loop.json").write_text(loop_state)
    (out / "checkpoints" / "latest.json").write_text(pointer)
    if agent is not None:
        (directory / "agent.json").write_text(agent[0])
        write_npz(directory / "agent.npz", agent[1])
    return directory


class Hung(BaseException):
    """A call that did not return in time (a BaseException: no loader's handler takes it)."""


@contextlib.contextmanager
def within(seconds: float) -> Iterator[None]:
    """Raise :class:`Hung` in the block if it runs longer than ``seconds`` (SIGALRM, which
    also interrupts a blocking ``open`` or ``read``)."""

    def expire(signum: int, frame: FrameType | None) -> None:
        raise Hung(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def replace_with(path: Path, kind: str) -> contextlib.AbstractContextManager[None]:
    """Replace the file ``path`` by a special file for the duration: ``"fifo"`` (no writer),
    ``"socket"`` (a listening Unix socket), ``"device"`` (a link to ``/dev/urandom``) or
    ``"directory"``."""
    stack = contextlib.ExitStack()
    if path.exists() or path.is_symlink():
        path.unlink()
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "socket":
        server = stack.enter_context(socket.socket(socket.AF_UNIX, socket.SOCK_STREAM))
        server.bind(str(path))
        server.listen(1)
    elif kind == "device":
        path.symlink_to("/dev/urandom")
    else:
        path.mkdir()
    return stack
