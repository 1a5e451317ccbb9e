"""OpenCV for the camera modules, imported here first so that its own log lines stay quiet.

OpenCV and the FFmpeg inside it print warnings and errors of their own on standard error (a
malformed PNG chunk, a video without its index) before the call returns the failure that skidnav
reports in one line; those lines would precede it. So FFmpeg's log level is set to quiet in
the environment before OpenCV is imported (``OPENCV_FFMPEG_LOGLEVEL``, read when the first video
is opened) and OpenCV's own logger is silenced, unless the user set ``OPENCV_LOG_LEVEL`` or
``OPENCV_FFMPEG_LOGLEVEL`` to see them. The image libraries inside OpenCV (libpng's "IDAT:
invalid code lengths set") write to the process's standard error past any logger:
:func:`native_stderr_quiet` points it at ``/dev/null`` while an image is decoded. Every camera
module takes ``cv2`` from here.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator

FFMPEG_QUIET = "-8"
"""FFmpeg's ``AV_LOG_QUIET``."""

os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", FFMPEG_QUIET)

import cv2  # noqa: E402  (after the environment is set)

if "OPENCV_LOG_LEVEL" not in os.environ:
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)

__all__ = ["cv2", "native_stderr_quiet"]


@contextlib.contextmanager
def native_stderr_quiet() -> Iterator[None]:
    """Send what native code writes to file descriptor 2 to ``/dev/null`` for the block (a few
    milliseconds of decoding; unless the user set ``OPENCV_LOG_LEVEL``)."""
    if "OPENCV_LOG_LEVEL" in os.environ:
        yield
        return
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
