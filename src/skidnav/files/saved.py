"""Saved files and configs read without trusting them.

Saved state (agents, kinematic models, run files, the oracle cache) is NumPy ``.npz`` plus JSON,
never pickle. A damaged or hostile file must end in one :class:`~skidnav.errors.CorruptFileError`
line (a config: one :class:`~skidnav.errors.UserError` line), never in a traceback, a
MemoryError, a RecursionError, an OverflowError or a hang, so nothing in a file is used before
it is checked against what the reader expects:

* every file is opened by :func:`skidnav.files.user.open_user_file` (a regular file; a FIFO, a
  device or a socket refused without blocking) and read by :func:`~skidnav.files.user.read_limited`
  (at most a given number of bytes);
* :func:`parse_json` / :func:`read_json`: a size limit, a nesting limit checked before parsing
  (:func:`skidnav.files.jsondepth.json_depth`, in memory linear in the text), no
  ``NaN``/``Infinity``
  or overflowing numbers unless asked for, a JSON object;
* :func:`read_config_text` / :func:`parse_toml`: the same limits for a TOML config (which may
  come through a pipe);
* :func:`shown`: a value of a file quoted in an error message (40 characters at most);
* :class:`SavedArchive`: an ``.npz`` whose zip directory is checked first (at most
  :data:`MAX_MEMBERS` members in at most :data:`MAX_DIRECTORY_BYTES`, their declared sizes within
  the budget), then whose member names are checked against the expected arrays
  (unknown or missing ones refused) before anything is decompressed, then every member's ``.npy``
  header (read with :func:`numpy.lib.format.read_magic` and ``read_array_header_1_0/2_0``, itself
  at most :data:`MAX_HEADER_BYTES`) against its :class:`ArraySpec` (dtype, shape) and its
  uncompressed size in the zip directory against the header, and the total against a byte
  budget: only then is data read, exactly the bytes the header announced (no zip bomb).

Writing is :mod:`skidnav.files.atomic`.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import re
import struct
import tokenize
import tomllib
import zipfile
import zlib
from collections.abc import Collection, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO, NamedTuple

import numpy as np
from numpy.lib import format as npy_format

from skidnav.errors import CorruptFileError, UserError, excerpt, first_line
from skidnav.files.jsondepth import json_depth
from skidnav.files.user import open_user_file, read_limited

MAX_JSON_BYTES = 64 * 2**20
"""Largest JSON file read [bytes] (an agent's is a few kilobytes, metadata a few megabytes)."""
MAX_JSON_DEPTH = 32
"""Deepest nesting of JSON arrays and objects, and of TOML arrays and tables, accepted (saved
files nest 5 levels or fewer, configs 6)."""
MAX_CONFIG_BYTES = 4_000_000
"""Largest config file read [bytes]: a config is a few kilobytes; this holds 1,000,000
characters of up to 4 UTF-8 bytes each."""
MAX_ARCHIVE_BYTES = 2 * 2**30
"""Largest total of uncompressed array data an ``.npz`` may announce [bytes]."""
MAX_HEADER_BYTES = 10_000
"""Largest ``.npy`` header accepted [bytes] (NumPy writes about 128)."""
MAX_MEMBERS = 1000
"""Most members an ``.npz`` may hold."""
MAX_DIRECTORY_BYTES = MAX_MEMBERS * 1024
"""Largest zip directory of an ``.npz`` read [bytes] (NumPy's entries take about 100 bytes)."""
READ_ERRORS = (
    OSError, ValueError, TypeError, EOFError, zipfile.BadZipFile, zlib.error,
    NotImplementedError, MemoryError, RecursionError, OverflowError, SyntaxError,
    tokenize.TokenError,
)  # fmt: skip
"""What decoding a damaged file can raise (zipfile raises NotImplementedError for a damaged
compression-method field; NumPy parses a ``.npy`` header as a Python literal, and one that is
not raises SyntaxError, or TokenError from its second try); readers turn them into one
CorruptFileError line."""


@contextlib.contextmanager
def loading(
    path: Path, what: str, errors: tuple[type[Exception], ...] = (*READ_ERRORS, UserError)
) -> Iterator[None]:
    """Read and check a part of a saved ``what`` (an agent…) from ``path`` inside the block; what
    it raises becomes one CorruptFileError line naming ``path``: ``"PATH: cannot load WHAT:
    missing 'KEY'"`` for a missing key, ``"PATH: cannot load WHAT: PROBLEM"`` for ``errors``. A
    CorruptFileError already naming ``path`` passes unchanged."""
    try:
        yield
    except KeyError as error:
        raise CorruptFileError(f"{path}: cannot load {what}: missing {error.args[0]!r}") from None
    except errors as error:
        if isinstance(error, CorruptFileError) and str(error).startswith(f"{path}: "):
            raise
        raise CorruptFileError(f"{path}: cannot load {what}: {first_line(error)}") from None


def _refuse_constant(name: str) -> Any:
    raise ValueError(f"non-finite number {name}")


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"number {excerpt(text, 20)} out of range")
    return value


def parse_json(
    text: str | bytes,
    where: Path | str,
    *,
    max_depth: int = MAX_JSON_DEPTH,
    allow_nonfinite: bool = False,
) -> dict[str, Any]:
    """The JSON object in ``text`` (or in its UTF-8 bytes); CorruptFileError ``"where: problem"``
    when it is not UTF-8, malformed, nested deeper than ``max_depth``, not an object, or (unless
    ``allow_nonfinite``) holds ``NaN``, ``Infinity`` or a number too large for a float (e.g.
    ``1e400``)."""
    depth = json_depth(text)
    if depth > max_depth:
        raise CorruptFileError(f"{where}: JSON nested {depth} deep, expected at most {max_depth}")
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError:
            raise CorruptFileError(f"{where}: not UTF-8 text") from None
    options: dict[str, Any] = {}
    if not allow_nonfinite:
        options = {"parse_constant": _refuse_constant, "parse_float": _finite_float}
    try:
        data = json.loads(text, **options)
    except (ValueError, RecursionError) as error:
        raise CorruptFileError(f"{where}: invalid JSON ({first_line(error, 80)})") from None
    if not isinstance(data, dict):
        raise CorruptFileError(f"{where}: expected a JSON object, got {type(data).__name__}")
    return data


def read_json(
    path: Path | str,
    *,
    max_bytes: int = MAX_JSON_BYTES,
    max_depth: int = MAX_JSON_DEPTH,
    allow_nonfinite: bool = False,
    what: str = "file",
) -> dict[str, Any]:
    """:func:`parse_json` of a regular file of at most ``max_bytes`` bytes (UTF-8)."""
    data = read_limited(path, max_bytes, what)
    return parse_json(data, path, max_depth=max_depth, allow_nonfinite=allow_nonfinite)


def nesting_depth(value: object) -> int:
    """Deepest nesting of dicts and lists in parsed data (a scalar: 0), without recursion.

    >>> nesting_depth({"a": [1, {"b": "x"}]}), nesting_depth(3)
    (3, 0)
    """
    deepest, pending = 0, [(value, 1)]
    while pending:
        item, depth = pending.pop()
        if isinstance(item, dict):
            item = list(item.values())
        if isinstance(item, list):
            deepest = max(deepest, depth)
            pending.extend((child, depth + 1) for child in item)
    return deepest


def read_config_text(path: Path | str) -> str:
    """The text of a config file of at most :data:`MAX_CONFIG_BYTES` bytes, a regular file or a
    pipe (read up to that limit instead of filling the memory, its writer given
    :data:`~skidnav.files.user.PIPE_TIMEOUT_S` to finish); UserError naming the file otherwise (a
    device, a directory, a socket)."""
    data = read_limited(path, MAX_CONFIG_BYTES, "config file", UserError, pipes=True)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise UserError(f"{path}: cannot read config (UnicodeDecodeError)") from None


_TOML_POSITION = re.compile(r"^(?P<message>.*) \(at line (?P<line>\d+), column (?P<column>\d+)\)$")


def parse_toml(text: str, where: Path | str, max_depth: int = MAX_JSON_DEPTH) -> dict[str, Any]:
    """The tables of TOML ``text``; UserError ``"where:LINE:COLUMN: malformed TOML: problem"``
    when it is malformed, ``"where: malformed TOML: nested too deeply"`` when its arrays and
    tables nest deeper than ``max_depth`` (inline ones past a few hundred levels exhaust the
    parser's recursion; dotted keys nest without limit), or when an integer has more digits
    than Python converts (4300)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        match = _TOML_POSITION.match(first_line(error))
        if match is None:
            raise UserError(f"{where}: malformed TOML: {first_line(error)}") from None
        position = f"{where}:{match['line']}:{match['column']}"
        raise UserError(f"{position}: malformed TOML: {match['message']}") from None
    except RecursionError:
        raise UserError(f"{where}: malformed TOML: nested too deeply") from None
    except ValueError as error:
        raise UserError(f"{where}: malformed TOML: {first_line(error, 80)}") from None
    depth = nesting_depth(data)
    if depth > max_depth:
        raise UserError(
            f"{where}: malformed TOML: nested too deeply ({depth} levels, at most {max_depth})"
        )
    return data


def up_to(length: int) -> range:
    """An axis of any length from 0 to ``length`` (for :attr:`ArraySpec.shape`)."""
    return range(length + 1)


@dataclass(frozen=True)
class ArraySpec:
    """What one array of a saved archive may be.

    Attributes:
        shape: per axis its exact length, or a ``range`` of lengths (see :func:`up_to`).
        dtype: the exact dtype (e.g. ``"<f8"``), or ``""`` to accept any of ``kinds``.
        kinds: NumPy dtype kinds accepted when ``dtype`` is ``""`` (e.g. ``"fiub"``, ``"U"``);
            never ``"O"`` (objects would need pickle).
    """

    shape: tuple[int | range, ...]
    dtype: str = ""
    kinds: str = ""

    def problem(self, shape: tuple[int, ...], dtype: np.dtype[Any]) -> str | None:
        """What is wrong with an array of ``shape`` and ``dtype`` (None if it fits)."""
        if self.dtype:
            dtype_ok = dtype == np.dtype(self.dtype)
        else:
            dtype_ok = dtype.kind in self.kinds and dtype.kind != "O" and not dtype.fields
        shape_ok = len(shape) == len(self.shape) and all(
            length == axis if isinstance(axis, int) else length in axis
            for length, axis in zip(shape, self.shape, strict=False)
        )
        if dtype_ok and shape_ok:
            return None
        wanted = np.dtype(self.dtype).name if self.dtype else f"kind {self.kinds}"
        axes = ", ".join(str(a) if isinstance(a, int) else f"≤{a.stop - 1}" for a in self.shape) + (
            "," if len(self.shape) == 1 else ""
        )
        return f"is {dtype.name} of shape {shape}, expected {wanted} of shape ({axes})"


class NpyHeader(NamedTuple):
    """The checked ``.npy`` header of one archive member."""

    shape: tuple[int, ...]
    dtype: np.dtype[Any]
    fortran_order: bool
    nbytes: int
    """Bytes of array data the header announces (shape product × item size)."""


def _label(name: str) -> str:
    """``'model.pair_key'`` → ``"model array 'model.pair_key'"`` (the group before the dot)."""
    group = name.split(".", 1)[0] if "." in name else "array"
    return f"{group} array {excerpt(name)}" if group != "array" else f"array {excerpt(name)}"


class SavedArchive:
    """An ``.npz`` archive opened for checked reading; use as a context manager.

    ``names`` comes from the zip directory alone. :meth:`read_all` checks the member names
    against the expected arrays, then every header against its spec and the announced total
    against ``max_bytes``, before it reads any data. Every problem is a CorruptFileError
    ``"path: problem"``.

    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "a.npz"
    >>> np.savez(path, q=np.zeros((2, 3)))
    >>> with SavedArchive(path) as archive:
    ...     archive.read_all({"q": ArraySpec((2, 3), "<f8")})["q"].shape
    (2, 3)
    >>> with SavedArchive(path) as archive:
    ...     archive.read_all({"q": ArraySpec((up_to(10),), "<f8")})
    Traceback (most recent call last):
    ...
    skidnav.errors.CorruptFileError: ...: array 'q' is float64 of shape (2, 3), expected ... (≤10,)
    """

    def __init__(self, path: Path | str, max_bytes: int = MAX_ARCHIVE_BYTES) -> None:
        self.path = Path(path)
        self.max_bytes = max_bytes
        self._handle: BinaryIO | None = None
        self._zip: zipfile.ZipFile | None = None
        self._members: dict[str, zipfile.ZipInfo] = {}

    def __enter__(self) -> SavedArchive:
        self._handle = open_user_file(self.path)
        try:
            try:
                _check_directory(self._handle)
                self._zip = zipfile.ZipFile(self._handle)
            except READ_ERRORS as error:
                problem = first_line(error, 80)
                raise self._error(f"not a readable .npz archive ({problem})") from None
            self._list_members(self._zip.infolist())
        except BaseException:
            self.__exit__()
            raise
        return self

    def _list_members(self, members: list[zipfile.ZipInfo]) -> None:
        if len(members) > MAX_MEMBERS:
            raise self._error(f"{len(members)} members, expected at most {MAX_MEMBERS}")
        declared = sum(info.file_size for info in members)
        if declared > self.max_bytes + len(members) * MAX_HEADER_BYTES:
            raise self._error(f"members of {declared:,} bytes, expected at most {self.max_bytes:,}")
        for info in members:
            name = info.filename.removesuffix(".npy")
            if name == info.filename or name in self._members:
                raise self._error(f"unexpected member {excerpt(info.filename)}")
            self._members[name] = info

    def __exit__(self, *exc_info: object) -> None:
        for resource in (self._zip, self._handle):
            if resource is not None:
                resource.close()
        self._zip = self._handle = None

    @property
    def names(self) -> frozenset[str]:
        """The array names in the archive (member names without ``.npy``)."""
        return frozenset(self._members)

    def _error(self, problem: str) -> CorruptFileError:
        return CorruptFileError(f"{self.path}: {problem}")

    def check_names(self, expected: Collection[str], optional: Collection[str] = ()) -> None:
        """Refuse a member not in ``expected`` and a missing one not in ``optional``."""
        unknown = sorted(self.names - set(expected))
        if unknown:
            raise self._error(f"unexpected {_label(unknown[0])}")
        missing = sorted(set(expected) - self.names - set(optional))
        if missing:
            raise self._error(f"missing {_label(missing[0])}")

    def header(self, name: str, spec: ArraySpec) -> NpyHeader:
        """The header of member ``name``, checked against ``spec`` and the member's size."""
        info = self._members.get(name)
        if info is None:
            raise self._error(f"missing {_label(name)}")
        if info.file_size > self.max_bytes + MAX_HEADER_BYTES:
            raise self._error(f"{_label(name)} of {info.file_size:,} bytes is too large")
        try:
            with self._open(info) as stream:
                header, offset = _read_header(stream)
        except READ_ERRORS as error:
            raise self._error(
                f"{_label(name)}: bad .npy header ({first_line(error, 80)})"
            ) from None
        problem = spec.problem(header.shape, header.dtype)
        if problem is not None:
            raise self._error(f"{_label(name)} {problem}")
        if info.file_size != offset + header.nbytes:
            raise self._error(
                f"{_label(name)}: {info.file_size:,} bytes stored, its header announces "
                f"{offset + header.nbytes:,}"
            )
        return header

    def read_all(
        self, specs: Mapping[str, ArraySpec], optional: Collection[str] = ()
    ) -> dict[str, np.ndarray]:
        """Every array of ``specs`` (those in ``optional`` may be absent), all checked first."""
        self.check_names(specs, optional)
        headers = {name: self.header(name, specs[name]) for name in sorted(self.names)}
        total = sum(header.nbytes for header in headers.values())
        if total > self.max_bytes:
            raise self._error(f"arrays of {total:,} bytes, expected at most {self.max_bytes:,}")
        return {name: self._data(name, header) for name, header in headers.items()}

    def read(self, name: str, spec: ArraySpec) -> np.ndarray:
        """One array, checked first (missing: CorruptFileError)."""
        return self._data(name, self.header(name, spec))

    def _open(self, info: zipfile.ZipInfo) -> Any:
        assert self._zip is not None, "use SavedArchive as a context manager"
        return self._zip.open(info)

    def _data(self, name: str, header: NpyHeader) -> np.ndarray:
        """Read exactly the announced bytes after the header (the zip CRC checked at its end)."""
        try:
            with self._open(self._members[name]) as stream:
                _read_header(stream)
                data = np.empty(header.nbytes, dtype=np.uint8)
                filled = stream.readinto(data.data) if header.nbytes else 0
                if filled != header.nbytes or stream.read(1):
                    raise ValueError("array data do not match the header")
        except READ_ERRORS as error:
            raise self._error(f"{_label(name)}: unreadable ({first_line(error, 80)})") from None
        if header.nbytes == 0:
            return np.zeros(header.shape, dtype=header.dtype)
        return data.view(header.dtype).reshape(
            header.shape, order="F" if header.fortran_order else "C"
        )


_END_RECORD = b"PK\x05\x06"
_END_RECORD_BYTES = 22
_SEARCHED_BYTES = _END_RECORD_BYTES + (1 << 16)
"""Where ``zipfile`` looks for the end record: within reach of the largest comment."""
_ZIP64_LOCATOR = b"PK\x06\x07"
_LOCATOR_BYTES = 20


def _check_directory(handle: BinaryIO) -> None:
    """ValueError unless the end record of the zip file ``handle`` (found where ``zipfile`` finds
    it: the last 22 bytes, else the last match in the searched tail) announces at most
    :data:`MAX_MEMBERS` entries in at most :data:`MAX_DIRECTORY_BYTES`, with no ZIP64 locator
    before it (an archive within the limits never needs one). ``zipfile`` reads the whole
    directory at once and makes an object per entry, so this comes first."""
    size = handle.seek(0, io.SEEK_END)
    window = min(size, _SEARCHED_BYTES + _LOCATOR_BYTES)
    handle.seek(size - window)
    tail = handle.read(window)
    at = len(tail) - _END_RECORD_BYTES
    if not (at >= 0 and tail.startswith(_END_RECORD, at) and tail.endswith(b"\0\0")):
        at = tail.rfind(_END_RECORD, max(0, len(tail) - _SEARCHED_BYTES))
    if at < 0 or at + _END_RECORD_BYTES > len(tail):
        raise ValueError("no zip directory")
    entries, directory_bytes = struct.unpack_from("<HI", tail, at + 10)
    if at >= _LOCATOR_BYTES and tail.startswith(_ZIP64_LOCATOR, at - _LOCATOR_BYTES):
        raise ValueError("a ZIP64 directory")
    if entries > MAX_MEMBERS or directory_bytes > MAX_DIRECTORY_BYTES:
        raise ValueError(f"a directory of {entries:,} entries in {directory_bytes:,} bytes")


def _read_header(stream: Any) -> tuple[NpyHeader, int]:
    """(header, its length in bytes) of the ``.npy`` stream; the header's own length is checked
    before it is read."""
    version = npy_format.read_magic(stream)
    size_bytes = {(1, 0): 2, (2, 0): 4}.get(version)
    if size_bytes is None:
        raise ValueError(f"unsupported .npy version {version}")
    raw_size = stream.read(size_bytes)
    size = int.from_bytes(raw_size, "little")
    if len(raw_size) != size_bytes or size > MAX_HEADER_BYTES:
        raise ValueError(f"header of {size:,} bytes")
    prefix = npy_format.magic(*version) + raw_size
    text = io.BytesIO(prefix + stream.read(size))
    npy_format.read_magic(text)
    reader = (
        npy_format.read_array_header_1_0 if version == (1, 0) else npy_format.read_array_header_2_0
    )
    shape, fortran_order, dtype = reader(text, max_header_size=MAX_HEADER_BYTES)
    nbytes = math.prod(shape) * dtype.itemsize
    return NpyHeader(tuple(shape), dtype, bool(fortran_order), nbytes), len(prefix) + size
