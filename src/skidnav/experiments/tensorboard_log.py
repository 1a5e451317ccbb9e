"""Per-episode TensorBoard logs of a sweep (``skidnav run CONFIG --tensorboard DIR``,
docs/experiments.md "TensorBoard").

Written by the process running the sweep from each finished run's results (the workers only
compute): one TensorBoard *run* per run of the grid, in the directory
``DIR/AGENT/MAP/PRESET/seed-N`` (labels percent-encoded where a character could not stand in a
path: ``/`` becomes ``%2F``, so two labels never share a directory), holding one event file,
``events.out.tfevents.skidnav``. Its scalars are the run's episode columns, episode ``e``
(1 … N, as in ``episodes.parquet``) at step ``e``: the training columns under ``train/``
(``train/return``, ``train/length``, ``train/success``, ``train/collisions``,
``train/planning_updates``, ``train/wall_time``), the greedy evaluation's under ``greedy/``
(``greedy/length``, ``greedy/success``, ``greedy/cost``). Each event's wall time is the time the
file was written plus the run's training time up to that episode, so TensorBoard's *Relative*
axis shows training seconds. A study's runs log their own episode columns the same way.

A file is written whole (:func:`skidnav.files.atomic.write_user_file`), so a resumed sweep writes
the same directory again without duplicating a point. TensorBoard stores scalars as float32:
the values read back equal the episodes table's after rounding to float32.

The ``tensorboard`` package (the ``logging`` extra) writes the records; without it
``skidnav.extras.require("logging", …)`` refuses in one line.
"""

from __future__ import annotations

import importlib
import importlib.util
import io
import time
from pathlib import Path
from typing import Any
from urllib.parse import quote

import numpy as np

from skidnav.errors import UserError
from skidnav.experiments.store import TrialResult
from skidnav.extras import require
from skidnav.files.atomic import write_user_file

EVENT_FILE = "events.out.tfevents.skidnav"
"""The event file of a run's directory (TensorBoard reads every file named ``*tfevents*``)."""
"""The command that installs the ``logging`` extra."""
_SAFE = "[]=,+-_.@"
"""Characters of a label kept as they are in a directory name (letters and digits always)."""


def path_label(label: object) -> str:
    """``label`` as one directory name: percent-encoded except letters, digits and
    ``[]=,+-_.@``, a leading dot encoded too (no hidden, ``.`` or ``..`` directory); distinct
    labels give distinct names.

    >>> path_label("dyna-q[planning_steps=5]"), path_label("a/b"), path_label("..")
    ('dyna-q[planning_steps=5]', 'a%2Fb', '%2E.')
    """
    name = quote(str(label), safe=_SAFE)
    return "%2E" + name[1:] if name.startswith(".") else name


def run_directory(root: Path, coordinates: dict[str, Any]) -> Path:
    """The TensorBoard run directory of a run at ``coordinates`` (agent, map, preset, seed)."""
    return (
        root
        / path_label(coordinates["agent"])
        / path_label(coordinates["map"])
        / path_label(coordinates["preset"])
        / f"seed-{int(coordinates['seed'])}"
    )


def scalar_tag(column: str) -> str:
    """The TensorBoard tag of an episode column: ``greedy_X`` → ``greedy/X``, else
    ``train/COLUMN``.

    >>> scalar_tag("greedy_length"), scalar_tag("planning_updates")
    ('greedy/length', 'train/planning_updates')
    """
    if column.startswith("greedy_"):
        return "greedy/" + column.removeprefix("greedy_")
    return "train/" + column


def event_records(episodes: dict[str, np.ndarray], written_at: float) -> bytes:
    """The event file of a run's ``episodes`` (column → (N,) array): the file-version event,
    then one event per episode with every column's value at step 1 … N, its wall time
    ``written_at`` [s since the epoch] plus the cumulative ``wall_time`` column [s] (0 without
    one), as TensorBoard's record format (length, masked CRC-32C, data, masked CRC-32C)."""
    event_pb2 = importlib.import_module("tensorboard.compat.proto.event_pb2")
    summary_pb2 = importlib.import_module("tensorboard.compat.proto.summary_pb2")
    record_writer = importlib.import_module("tensorboard.summary.writer.record_writer")
    columns = {name: np.asarray(values, dtype=np.float64) for name, values in episodes.items()}
    n_episodes = max((len(values) for values in columns.values()), default=0)
    elapsed = np.cumsum(columns.get("wall_time", np.zeros(n_episodes)))
    buffer = io.BytesIO()
    writer = record_writer.RecordWriter(buffer)
    writer.write(
        event_pb2.Event(wall_time=written_at, file_version="brain.Event:2").SerializeToString()
    )
    for index in range(n_episodes):
        values = [
            summary_pb2.Summary.Value(tag=scalar_tag(name), simple_value=float(column[index]))
            for name, column in columns.items()
        ]
        event = event_pb2.Event(
            wall_time=written_at + float(elapsed[index]),
            step=index + 1,
            summary=summary_pb2.Summary(value=values),
        )
        writer.write(event.SerializeToString())
    return buffer.getvalue()


class TensorBoardLog:
    """Writes each finished run's episodes as a TensorBoard run under ``root`` (module doc);
    call it with a :class:`~skidnav.experiments.store.TrialResult` (the runner's ``on_run``).

    Raises:
        UserError: from the constructor without the ``tensorboard`` package; from a call when
            the file cannot be written (one line naming it).
    """

    def __init__(self, root: Path) -> None:
        require("logging", "--tensorboard")
        self.root = Path(root)

    def __call__(self, result: TrialResult) -> None:
        directory = run_directory(self.root, result.coordinates)
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise UserError(
                f"{directory}: cannot create the TensorBoard log ({error.strerror or error})"
            ) from None
        data = event_records(result.episodes, time.time())
        write_user_file(directory / EVENT_FILE, data, "TensorBoard log")
