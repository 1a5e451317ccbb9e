"""Where camera frames and files come from: a live camera, a video file, images, JSON files.

:func:`open_frames` takes the user's ``--source`` (``"0"`` for camera 0, a video path, or a folder)
and returns one :class:`FrameSource` that yields :class:`Frame` objects with timestamps.
:func:`read_images` reads a still set of images (the board views of a lens calibration), and
:func:`read_json_file` / :func:`write_json_file` the camera's JSON files (calibration,
intrinsics), each failure in one line.
"""

from __future__ import annotations

import json
import logging
import math
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from skidnav.errors import UserError
from skidnav.files.atomic import write_atomic
from skidnav.files.saved import read_json
from skidnav.realtime.camera.imagefile import read_image
from skidnav.realtime.camera.opencv import cv2

LOGGER = logging.getLogger(__name__)

IMAGE_SUFFIXES = frozenset({".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff"})


class Frame(NamedTuple):
    """One camera image.

    Attributes:
        number: 0-based position of the frame in its source.
        stamp: capture time [s]: ``time.monotonic()`` when a live camera frame was read; the
            position in the recording (``number / fps``) for a video file or an image folder.
        image: BGR image, uint8, shape (height, width, 3).
    """

    number: int
    stamp: float
    image: NDArray[np.uint8]


class FrameSource:
    """Iterable over the frames of a camera index, a video file or an image folder (sorted by name).

    Use as a context manager, or call :meth:`close`. Iterating twice over a camera or video reads
    on from where the first iteration stopped; an image folder starts over.

    Args:
        source: camera index (int, or a string of digits), a video file, or a folder of images.
        fps: frame rate [Hz] assumed for an image folder (and for a video that reports none),
            finite and > 0.
    """

    def __init__(self, source: int | str | Path, fps: float = 30.0) -> None:
        if not 0 < fps < math.inf:  # NaN fails too
            raise ValueError(f"expected a finite fps > 0, got {fps}")
        self.fps = fps
        self.description = str(source)
        self._files: list[Path] | None = None
        self._capture: cv2.VideoCapture | None = None
        self._live = False
        if isinstance(source, int) or (isinstance(source, str) and source.isdigit()):
            self._open_capture(int(source))
            self._live = True
            return
        path = Path(source)
        if path.is_dir():
            self._files = image_files(path)
        elif path.is_file():
            self._open_capture(str(path))
        elif path.exists():  # a FIFO or a device: a video reader would wait on it
            raise UserError(f"{path}: not a video file or an image folder")
        else:
            raise UserError(f"{path}: no such camera, video file or image folder")

    def _open_capture(self, target: int | str) -> None:
        capture = cv2.VideoCapture(target)
        if not capture.isOpened():
            capture.release()
            kind = "camera" if isinstance(target, int) else "video file"
            raise UserError(f"{target}: cannot open {kind}")
        self._capture = capture
        reported = float(capture.get(cv2.CAP_PROP_FPS) or 0.0)
        if reported > 0 and not self._live:
            self.fps = reported

    def __iter__(self) -> Iterator[Frame]:
        if self._files is not None:
            yield from self._iterate_files(self._files)
        else:
            yield from self._iterate_capture()

    def _iterate_files(self, files: list[Path]) -> Iterator[Frame]:
        for index, file in enumerate(files):
            try:
                image = read_image(file)
            except UserError as error:
                LOGGER.warning("%s; skipped", error)
                continue
            yield Frame(index, index / self.fps, image)

    def _iterate_capture(self) -> Iterator[Frame]:
        index = 0
        while self._capture is not None:
            ok, image = self._capture.read()
            if not ok or image is None:
                return
            stamp = time.monotonic() if self._live else index / self.fps
            if image.ndim == 2:
                image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
            yield Frame(index, stamp, np.asarray(image, dtype=np.uint8))
            index += 1

    def close(self) -> None:
        """Release the camera or video file (idempotent)."""
        if self._capture is not None:
            self._capture.release()
            self._capture = None

    def __enter__(self) -> FrameSource:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def open_frames(source: int | str | Path, fps: float = 30.0) -> FrameSource:
    """A :class:`FrameSource` for ``source`` (see there); raises ``UserError`` if unusable."""
    return FrameSource(source, fps=fps)


def image_files(folder: Path) -> list[Path]:
    """The image files (by suffix, :data:`IMAGE_SUFFIXES`) in ``folder``, sorted by name.

    Raises:
        UserError: the folder holds no image.
    """
    files = sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
    if not files:
        raise UserError(f"{folder}: no images ({', '.join(sorted(IMAGE_SUFFIXES))}) in folder")
    return files


def read_images(paths: Sequence[str | Path]) -> list[tuple[str, NDArray[np.uint8]]]:
    """Read image files and folders (each folder's images in name order) as (name, BGR image).

    Unlike a :class:`FrameSource`, which skips an unreadable frame of a recording, a still set is
    all or nothing: every image was chosen by the user.

    Raises:
        UserError: a path that does not exist, a folder without images, or an image
            :func:`~skidnav.realtime.camera.imagefile.read_image` refuses.
    """
    files: list[Path] = []
    for path in map(Path, paths):
        if path.is_dir():
            files.extend(image_files(path))
        elif path.exists():
            files.append(path)
        else:
            raise UserError(f"{path}: no such image file or folder")
    return [(str(file), read_image(file)) for file in files]


def read_json_file(path: str | Path, what: str) -> dict[str, Any]:
    """The JSON object in the file ``path``, read by :func:`skidnav.files.saved.read_json` (size
    and nesting limits, no NaN or Infinity); ``what`` names the kind of file in errors.

    Raises:
        UserError: the file does not exist. CorruptFileError: unreadable, or not a JSON object.
    """
    path = Path(path)
    if not path.exists():
        raise UserError(f"{path}: {what} file not found")
    return read_json(path, what=f"{what} file")


def write_json_file(path: str | Path, data: dict[str, Any], what: str) -> None:
    """Write ``data`` as indented JSON to ``path`` all-or-nothing (``savedfile.write_atomic``).

    Raises:
        UserError: the file cannot be written (e.g. its folder does not exist).
    """
    text = json.dumps(data, indent=2, allow_nan=False) + "\n"
    try:
        write_atomic(path, text.encode("utf-8"))
    except OSError as error:
        raise UserError(f"{path}: cannot write {what} ({error.strerror or error})") from None
