"""Image files are sized from their header before OpenCV decodes them: the size of every format
OpenCV writes is read right, a header claiming 60000 × 60000 px is refused in one line without
decoding, and the lines OpenCV and its libraries print on standard error never come before
skidnav's one-line error. ``--fps`` must be a finite number."""

from __future__ import annotations

import re
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

from skidnav.cli import main
from skidnav.errors import UserError
from skidnav.realtime.camera import imagefile
from skidnav.realtime.camera.imagefile import MAX_IMAGE_PIXELS, image_size, read_image
from skidnav.realtime.camera.opencv import cv2
from tests.realtime.realtime_helpers import SRC

IMAGE = (np.arange(30 * 41 * 3) % 251).astype(np.uint8).reshape(30, 41, 3)


@pytest.mark.parametrize(
    ("suffix", "options"),
    [
        (".png", []),
        (".jpg", []),
        (".jpg", [cv2.IMWRITE_JPEG_PROGRESSIVE, 1]),
        (".bmp", []),
        (".tiff", []),
        (".tiff", [cv2.IMWRITE_TIFF_COMPRESSION, 1]),
    ],
)
def test_the_header_size_is_the_image_size(suffix: str, options: list[int]) -> None:
    ok, encoded = cv2.imencode(suffix, IMAGE, options)
    assert ok
    data = encoded.tobytes()
    assert image_size(data) == (41, 30)
    for cut in (0, 1, 5, 12, 20):  # a header cut short: one ValueError, whatever the cut
        with pytest.raises(ValueError, match=r"cut short|not a PNG|without|not IHDR"):
            image_size(data[:cut])


def png_header(width: int, height: int) -> bytes:
    """The first bytes of a PNG announcing ``width`` × ``height`` px (its data missing)."""
    fields = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    chunk = struct.pack(">I", 13) + b"IHDR" + fields
    return b"\x89PNG\r\n\x1a\n" + chunk + struct.pack(">I", zlib.crc32(chunk[4:])) + bytes(64)


def jpeg_header(width: int, height: int) -> bytes:
    """A JPEG start: an APP0 segment, then a baseline frame header of ``width`` × ``height``."""
    app0 = b"\xff\xe0" + struct.pack(">H", 16) + b"JFIF\x00" + bytes(9)
    frame = b"\xff\xc0" + struct.pack(">HBHHB", 11, 8, height, width, 1) + b"\x01\x11\x00"
    return b"\xff\xd8" + app0 + b"\xff\xff" + frame + bytes(64)


def bmp_header(width: int, height: int) -> bytes:
    return b"BM" + bytes(12) + struct.pack("<Iii", 40, width, -height) + bytes(64)


def tiff_header(width: int, height: int) -> bytes:
    entries = struct.pack("<HHII", 256, 4, 1, width) + struct.pack("<HHII", 257, 4, 1, height)
    return b"II*\x00" + struct.pack("<IH", 8, 2) + entries + bytes(64)


@pytest.mark.parametrize("header", [png_header, jpeg_header, bmp_header, tiff_header])
def test_a_huge_image_is_refused_before_decoding(
    header: object, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    assert callable(header)
    path = tmp_path / "huge.img"
    path.write_bytes(header(60000, 60000))
    assert image_size(path.read_bytes()) == (60000, 60000)

    def never(*args: object) -> None:
        raise AssertionError("decoded")

    monkeypatch.setattr(imagefile.cv2, "imdecode", never)
    with pytest.raises(UserError) as error:
        read_image(path)
    assert str(error.value) == (
        f"{path}: an image of 60000×60000 px, expected 1 to {MAX_IMAGE_PIXELS:,} pixels"
    )


def test_images_that_are_not_images_are_one_line(tmp_path: Path) -> None:
    cases = {
        "gif.png": (b"GIF89a" + bytes(20), "unreadable image (not a PNG, JPEG, BMP or TIFF image)"),
        "empty.png": (png_header(0, 5), "an image of 0×5 px"),
        "cut.jpg": (b"\xff\xd8\xff\xe0\x00", "unreadable image (a header cut short)"),
        "scan.jpg": (b"\xff\xd8\xff\xda" + bytes(8), "(a JPEG without a frame header)"),
        "broken.png": (png_header(4, 4), "unreadable image"),
    }
    for name, (data, message) in cases.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(UserError, match=re.escape(message)):
            read_image(tmp_path / name)
    assert read_image_round_trip(tmp_path).shape == IMAGE.shape


def read_image_round_trip(tmp_path: Path) -> np.ndarray:
    path = tmp_path / "fine.png"
    cv2.imwrite(str(path), IMAGE)
    image = read_image(path)
    np.testing.assert_array_equal(image, IMAGE)
    return image


def _broken_png(path: Path) -> None:
    """A PNG whose header is right and whose compressed data libpng refuses (libpng prints a
    line of its own on standard error)."""
    _, encoded = cv2.imencode(".png", IMAGE)
    data = bytearray(encoded.tobytes())
    at = data.find(b"IDAT")
    data[at + 10 : at + 30] = b"\xff" * 20
    path.write_bytes(bytes(data))


@pytest.mark.parametrize("case", ["huge image", "broken image", "not a video"])
def test_only_the_error_line_reaches_standard_error(case: str, tmp_path: Path) -> None:
    """In a fresh process, as a user runs it: OpenCV's, FFmpeg's and libpng's own lines are
    silenced, so standard error holds the one ``skidnav: error:`` line."""
    source = tmp_path / {"huge image": "huge.png", "broken image": "broken.png"}.get(
        case, "bad.mp4"
    )
    if case == "huge image":
        source.write_bytes(png_header(60000, 60000))
    elif case == "broken image":
        _broken_png(source)
    else:
        source.write_text("not a video")
    out = tmp_path / "out.json"
    command = ["camera", "calibrate", "--source", str(source)]
    if case != "not a video":
        command = ["camera", "intrinsics", "--images", str(source)]
    result = subprocess.run(
        [sys.executable, "-m", "skidnav.cli", *command, "--out", str(out)],
        env={"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"},
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and result.stderr.startswith(f"skidnav: error: {source}")
    assert not out.exists()


@pytest.mark.parametrize("fps", ["nan", "inf", "-1", "0", "fast"])
def test_fps_must_be_a_finite_positive_number(
    fps: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["camera", "calibrate", "--source", str(tmp_path), "--out", str(tmp_path / "c.json")]
    with pytest.raises(SystemExit) as leave:
        main([*argv, "--fps", fps])
    assert leave.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    expected = "expected a number" if fps == "fast" else "expected a finite number > 0"
    assert lines == [f"skidnav: error: camera calibrate: argument --fps: {expected}, got {fps!r}"]
