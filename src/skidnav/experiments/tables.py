"""Reading back the tidy Parquet tables of a results directory as saved files: size-checked
before anything is parsed (:mod:`skidnav.experiments.store` writes them)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import BinaryIO

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
    first); CorruptFileError naming it otherwise."""
    import pyarrow

    with open_user_file(path, "table") as handle:
        try:
            announced = _announced_bytes(handle)
            if announced > MAX_TABLE_BYTES:
                raise ValueError(f"{announced:,} bytes, expected at most {MAX_TABLE_BYTES:,}")
            handle.seek(0)
            return pd.read_parquet(handle)
        except (*READ_ERRORS, pyarrow.ArrowException) as error:
            raise CorruptFileError(f"{path}: unreadable table ({first_line(error, 80)})") from None


def _announced_bytes(handle: BinaryIO) -> int:
    """The larger of a Parquet file's size and the data its row groups announce (the footer is
    read only when the file is within :data:`MAX_TABLE_BYTES`)."""
    import pyarrow.parquet

    size = handle.seek(0, os.SEEK_END)
    if size > MAX_TABLE_BYTES:
        return size
    footer = pyarrow.parquet.ParquetFile(handle).metadata
    groups = range(footer.num_row_groups)
    return max(size, sum(int(footer.row_group(group).total_byte_size) for group in groups))
