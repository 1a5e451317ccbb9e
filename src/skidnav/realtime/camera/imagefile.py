"""Image files read within limits: the size a header announces is checked before OpenCV decodes.

A decoder allocates the image its header announces, so a file of a few bytes claiming
60000 × 60000 px would ask for 10 GB. :func:`read_image` reads the file (a regular file of at most
:data:`MAX_IMAGE_BYTES`, :func:`skidnav.files.user.read_limited`), reads its size with
:func:`image_size` — PNG: the ``IHDR`` chunk; JPEG: the first frame header (``SOF0``–``SOF15`` but
for the ``DHT``, ``JPG`` and ``DAC`` markers); BMP: the DIB header; TIFF: the first image
directory's ``ImageWidth`` and ``ImageLength`` — refuses more than :data:`MAX_IMAGE_PIXELS`, and
only then decodes the bytes (``cv2.imdecode``, as ``cv2.imread`` would; what the decoders print
themselves is silenced). Formats are recognised by their first bytes, not by the file's name; any
other format is refused.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from skidnav.errors import UserError
from skidnav.files.user import read_limited
from skidnav.realtime.camera.opencv import cv2, native_stderr_quiet

MAX_IMAGE_BYTES = 256 * 2**20
"""Largest image file read [bytes]."""
MAX_IMAGE_PIXELS = 2**26
"""Most pixels of an image decoded (67 megapixels: 200 MB as BGR; a 48-megapixel photo fits)."""
_SOF_MARKERS = frozenset(range(0xC0, 0xD0)) - {0xC4, 0xC8, 0xCC}
_STANDALONE_MARKERS = frozenset({0x01, *range(0xD0, 0xD9)})
_TIFF_WIDTH, _TIFF_LENGTH, _TIFF_SHORT = 256, 257, 3


def _png_size(data: bytes) -> tuple[int, int]:
    if data[12:16] != b"IHDR":
        raise ValueError("a PNG whose first chunk is not IHDR")
    width, height = struct.unpack_from(">II", data, 16)
    return width, height


def _jpeg_size(data: bytes) -> tuple[int, int]:
    at = 2  # after the start-of-image marker
    while at + 1 < len(data):
        if data[at] != 0xFF:
            raise ValueError(f"a JPEG without a marker at byte {at}")
        marker = data[at + 1]
        if marker == 0xFF or marker in _STANDALONE_MARKERS:  # a fill byte, a marker alone
            at += 1 if marker == 0xFF else 2
            continue
        if marker in (0xD9, 0xDA):  # end of image, start of scan
            break
        if marker in _SOF_MARKERS:
            height, width = struct.unpack_from(">HH", data, at + 5)
            return width, height
        (length,) = struct.unpack_from(">H", data, at + 2)
        at += 2 + max(length, 2)
    raise ValueError("a JPEG without a frame header")


def _bmp_size(data: bytes) -> tuple[int, int]:
    (header_bytes,) = struct.unpack_from("<I", data, 14)
    if header_bytes == 12:  # the OS/2 header: 16-bit sizes
        width, height = struct.unpack_from("<HH", data, 18)
    else:
        width, height = struct.unpack_from("<ii", data, 18)
    return width, abs(height)  # a negative height: rows stored top-down


def _tiff_size(data: bytes) -> tuple[int, int]:
    order = "<" if data.startswith(b"II") else ">"
    (directory,) = struct.unpack_from(order + "I", data, 4)
    (entries,) = struct.unpack_from(order + "H", data, directory)
    sizes = {}
    for entry in range(directory + 2, directory + 2 + 12 * entries, 12):
        tag, kind = struct.unpack_from(order + "HH", data, entry)
        if tag in (_TIFF_WIDTH, _TIFF_LENGTH):
            (sizes[tag],) = struct.unpack_from(
                order + ("H" if kind == _TIFF_SHORT else "I"), data, entry + 8
            )
    if len(sizes) != 2:
        raise ValueError("a TIFF without its width and length")
    return sizes[_TIFF_WIDTH], sizes[_TIFF_LENGTH]


_FORMATS: tuple[tuple[bytes, Callable[[bytes], tuple[int, int]]], ...] = (
    (b"\x89PNG\r\n\x1a\n", _png_size),
    (b"\xff\xd8", _jpeg_size),
    (b"BM", _bmp_size),
    (b"II*\x00", _tiff_size),
    (b"MM\x00*", _tiff_size),
)


def image_size(data: bytes) -> tuple[int, int]:
    """(width, height) [px] that the header of an image file's bytes announces; ValueError when
    it is not a PNG, JPEG, BMP or TIFF file or its header is cut short or malformed.

    >>> ok, png = cv2.imencode(".png", np.zeros((3, 5, 3), np.uint8))
    >>> image_size(png.tobytes())
    (5, 3)
    >>> image_size(b"GIF89a")
    Traceback (most recent call last):
    ...
    ValueError: not a PNG, JPEG, BMP or TIFF image
    """
    reader = next((read for magic, read in _FORMATS if data.startswith(magic)), None)
    if reader is None:
        raise ValueError("not a PNG, JPEG, BMP or TIFF image")
    try:
        return reader(data)
    except struct.error:
        raise ValueError("a header cut short") from None


def read_image(path: str | Path) -> NDArray[np.uint8]:
    """The BGR image (height, width, 3) of the file ``path`` (module doc).

    Raises:
        UserError: ``"PATH: problem"``: not a regular file, too large, a format not recognised,
            more than :data:`MAX_IMAGE_PIXELS` pixels or none, or data OpenCV cannot decode.
    """
    data = read_limited(path, MAX_IMAGE_BYTES, "image file", UserError)
    try:
        width, height = image_size(data)
    except ValueError as error:
        raise UserError(f"{path}: unreadable image ({error})") from None
    if not (width > 0 and height > 0 and width * height <= MAX_IMAGE_PIXELS):
        raise UserError(
            f"{path}: an image of {width}×{height} px, expected 1 to {MAX_IMAGE_PIXELS:,} pixels"
        )
    try:
        with native_stderr_quiet():
            image = cv2.imdecode(np.frombuffer(data, dtype=np.uint8), cv2.IMREAD_COLOR)
    except cv2.error:
        image = None
    if image is None:
        raise UserError(f"{path}: unreadable image")
    return np.asarray(image, dtype=np.uint8)
