"""Floor calibration of the overhead camera: finding the corner markers, saving, loading.

A calibration is the image → floor homography plus the layout it was made for, stored as JSON
(never pickle). Loading validates everything and reports a bad file in one line.
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.errors import CorruptFileError, UserError
from skidnav.realtime.camera_markers import (
    ArenaLayout,
    FloatArray,
    MarkerDetector,
    fit_homography,
    quad_centre,
)
from skidnav.realtime.camera_sources import Frame

LOGGER = logging.getLogger(__name__)

FORMAT_NAME = "skidnav-camera-calibration"
FORMAT_VERSION = 1


@dataclass(frozen=True)
class FloorCalibration:
    """A fitted floor homography.

    Attributes:
        homography: 3×3 float64, maps (u, v, 1) image pixels to (x, y, 1) arena metres.
        layout: the marker layout the homography was fitted for.
        image_size: (width, height) [px] of the images it was fitted on.
        frames_used: how many frames contributed corner-marker positions.
    """

    homography: FloatArray
    layout: ArenaLayout
    image_size: tuple[int, int]
    frames_used: int = 1

    def __post_init__(self) -> None:
        matrix = np.asarray(self.homography, dtype=np.float64)
        if matrix.shape != (3, 3) or not np.all(np.isfinite(matrix)):
            raise ValueError(f"expected a finite 3×3 homography, got shape {matrix.shape}")
        if abs(np.linalg.det(matrix)) < 1e-15:
            raise ValueError("expected an invertible homography, got a singular matrix")
        if len(self.image_size) != 2 or min(self.image_size) <= 0:
            raise ValueError(
                f"expected a positive (width, height) image_size, got {self.image_size}"
            )
        if self.frames_used < 1:
            raise ValueError(f"expected frames_used >= 1, got {self.frames_used}")
        object.__setattr__(self, "homography", matrix)

    def to_json(self) -> dict[str, Any]:
        """The JSON-ready dictionary written by :meth:`save`."""
        layout = self.layout
        return {
            "format": FORMAT_NAME,
            "version": FORMAT_VERSION,
            "dictionary": layout.dictionary,
            "arena_width": layout.arena_width,
            "arena_height": layout.arena_height,
            "corner_ids": list(layout.corner_ids),
            "corner_positions": [list(point) for point in layout.corners()],
            "robot_id": layout.robot_id,
            "image_size": list(self.image_size),
            "frames_used": self.frames_used,
            "homography": self.homography.tolist(),
        }

    def save(self, path: str | Path) -> None:
        """Write the calibration as JSON to ``path``."""
        Path(path).write_text(json.dumps(self.to_json(), indent=2) + "\n", encoding="utf-8")

    @classmethod
    def from_json(cls, data: Any, source: str = "calibration") -> FloorCalibration:
        """Rebuild from :meth:`to_json` output; raises ``CorruptFileError`` naming ``source``."""
        if not isinstance(data, dict) or data.get("format") != FORMAT_NAME:
            raise CorruptFileError(f"{source}: not a skidnav camera calibration")
        if data.get("version") != FORMAT_VERSION:
            raise CorruptFileError(
                f"{source}: calibration version {data.get('version')!r}, expected {FORMAT_VERSION}"
            )
        try:
            layout = ArenaLayout(
                arena_width=float(data["arena_width"]),
                arena_height=float(data["arena_height"]),
                corner_ids=tuple(int(i) for i in data["corner_ids"]),  # type: ignore[arg-type]
                corner_positions=tuple((float(x), float(y)) for x, y in data["corner_positions"]),
                robot_id=int(data["robot_id"]),
                dictionary=str(data["dictionary"]),
            )
            width, height = (int(v) for v in data["image_size"])
            return cls(
                homography=np.asarray(data["homography"], dtype=np.float64),
                layout=layout,
                image_size=(width, height),
                frames_used=int(data.get("frames_used", 1)),
            )
        except KeyError as error:
            raise CorruptFileError(f"{source}: missing field {error.args[0]!r}") from None
        except (TypeError, ValueError) as error:
            raise CorruptFileError(f"{source}: {_one_line(error)}") from None


def _one_line(error: Exception) -> str:
    return str(error).splitlines()[0] if str(error) else type(error).__name__


def load_calibration(path: str | Path, expected: ArenaLayout | None = None) -> FloorCalibration:
    """Read and validate a calibration file.

    Args:
        path: JSON file written by :meth:`FloorCalibration.save`.
        expected: if given, the layout the caller wants; any difference (arena size, ids,
            positions, dictionary) is a ``UserError``.

    Raises:
        UserError: missing file or layout mismatch. CorruptFileError: unreadable or invalid content.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise UserError(f"{path}: calibration file not found") from None
    except (OSError, UnicodeDecodeError) as error:
        raise CorruptFileError(f"{path}: cannot read calibration ({_one_line(error)})") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise CorruptFileError(f"{path}:{error.lineno}:{error.colno}: invalid JSON") from None
    calibration = FloorCalibration.from_json(data, source=str(path))
    if expected is not None:
        _check_layout(calibration.layout, expected, str(path))
    return calibration


def _check_layout(found: ArenaLayout, expected: ArenaLayout, source: str) -> None:
    """Raise ``UserError`` naming the first field where ``found`` differs from ``expected``."""
    pairs = {
        "arena size": (
            (found.arena_width, found.arena_height),
            (expected.arena_width, expected.arena_height),
        ),
        "corner_ids": (found.corner_ids, expected.corner_ids),
        "robot_id": (found.robot_id, expected.robot_id),
        "dictionary": (found.dictionary, expected.dictionary),
    }
    for name, (have, want) in pairs.items():
        if have != want:
            raise UserError(f"{source}: calibration {name} is {have}, expected {want}")
    if not np.allclose(found.corners(), expected.corners(), atol=1e-9):
        raise UserError(f"{source}: calibration corner_positions differ from the expected layout")


def calibrate(
    frames: Iterable[Frame], layout: ArenaLayout | None = None, max_frames: int = 10
) -> FloorCalibration:
    """Fit the floor homography from the corner markers seen in up to ``max_frames`` frames.

    Each corner marker's image centre (diagonal intersection) is the per-axis median over the
    frames in which all four corner markers were found, which rejects an occasional bad detection.

    Raises:
        UserError: no frame showed all four corner markers (names the ones missing last).
    """
    layout = layout or ArenaLayout()
    if max_frames < 1:
        raise ValueError(f"expected max_frames >= 1, got {max_frames}")
    detector = MarkerDetector(layout.dictionary)
    centres: list[FloatArray] = []
    image_size = (0, 0)
    missing: list[int] = list(layout.corner_ids)
    for count, frame in enumerate(frames, start=1):
        found = detector.detect(frame.image)
        missing = [i for i in layout.corner_ids if i not in found]
        if not missing:
            centres.append(np.stack([quad_centre(found[i]) for i in layout.corner_ids]))
            image_size = (int(frame.image.shape[1]), int(frame.image.shape[0]))
        if len(centres) >= max_frames or count >= 10 * max_frames:
            break
    if not centres:
        raise UserError(f"corner markers {missing} not found in any frame; check the camera view")
    pixels = np.median(np.stack(centres), axis=0)
    homography = fit_homography(pixels, np.asarray(layout.corners()))
    LOGGER.info("calibrated from %d frames, image %s", len(centres), image_size)
    if not math.isfinite(float(np.linalg.cond(homography))):
        raise UserError("degenerate corner-marker view; check the camera view")
    return FloorCalibration(homography, layout, image_size, frames_used=len(centres))
