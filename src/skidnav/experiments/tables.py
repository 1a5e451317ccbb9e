"""Reading back the tidy Parquet tables of a results directory as saved files: size-checked
before anything is parsed (:mod:`skidnav.experiments.store` writes them)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import pandas as pd

from skidnav.errors import CorruptFileError, first_line
from skidnav.files.saved import READ_ERRORS
from skidnav.files.user import open_user_file

MAX_TABLE_BYTES = 4 * 2**30
"""Largest tidy table read back [bytes], on disk and as announced uncompressed."""


def read_table(path: Path) -> pd.DataFrame:
    """A Parquet table of :meth:`~skidnav.experiments.store.ResultStore.consolidate`, read as a
    saved file: a regular file (:func:`skidnav.files.user.open_user_file`) of at most
    :data:`MAX_TABLE_BYTES` whose row groups announce at most that much data (its footer is read
    first); CorruptFileError naming it otherwise.

    The file's bytes are handed to Arrow as its own buffer and read on one thread: a Python file
    object read by Arrow's thread pool could leave a worker alive at interpreter exit, which
    aborts the process (``terminate called without an active exception``, exit 134) in about
    one run in five."""
    import pyarrow
    import pyarrow.parquet

    with open_user_file(path, "table") as handle:
        try:
            size = handle.seek(0, os.SEEK_END)
            if size > MAX_TABLE_BYTES:
                raise ValueError(f"{size:,} bytes, expected at most {MAX_TABLE_BYTES:,}")
            handle.seek(0)
            buffer = pyarrow.BufferReader(handle.read())
            announced = _announced_bytes(pyarrow.parquet.ParquetFile(buffer).metadata, size)
            if announced > MAX_TABLE_BYTES:
                raise ValueError(f"{announced:,} bytes, expected at most {MAX_TABLE_BYTES:,}")
            buffer.seek(0)
            table: pd.DataFrame = pyarrow.parquet.read_table(buffer, use_threads=False).to_pandas()
            return table
        except (*READ_ERRORS, pyarrow.ArrowException) as error:
            raise CorruptFileError(f"{path}: unreadable table ({first_line(error, 80)})") from None


def _announced_bytes(footer: Any, size: int) -> int:
    """The larger of a Parquet file's ``size`` [bytes] and the data its row groups announce in
    its ``footer`` (``pyarrow.parquet.FileMetaData``)."""
    groups = range(footer.num_row_groups)
    return max(size, sum(int(footer.row_group(group).total_byte_size) for group in groups))
