"""Floor calibration of the overhead camera: finding the corner markers, saving, loading.

A calibration is the image → floor homography plus the layout it was made for and, optionally, the
lens model whose undistorted pixels it maps; it is stored as JSON (never pickle). Loading validates
everything and reports a bad file in one line.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.checks import check_magnitude
from skidnav.errors import CorruptFileError, UserError, first_line
from skidnav.realtime.camera.intrinsics import CameraIntrinsics
from skidnav.realtime.camera.lens import (
    CameraPose,
    camera_pose,
    correct_for_height,
    undistort_pixels,
)
from skidnav.realtime.camera.markers import (
    ArenaLayout,
    FloatArray,
    MarkerDetector,
    fit_homography,
    floor_pose,
    quad_centre,
)
from skidnav.realtime.camera.sources import Frame, read_json_file, write_json_file

MAX_HOMOGRAPHY_ENTRY = 1e12
"""Largest entry of a floor homography in magnitude (a pixel-to-metre map has entries of order
1e-4 to 1e3; 1e308 would overflow every pose computed through it)."""
MAX_CONDITION = 1e12
"""Largest condition number of a usable homography (beyond it, a pose is noise)."""
LOGGER = logging.getLogger(__name__)

FORMAT_NAME = "skidnav-camera-calibration"
FORMAT_VERSION = 2  # 2 added "intrinsics"; version 1 files (without a lens model) still load
READABLE_VERSIONS = (1, 2)


@dataclass(frozen=True)
class FloorCalibration:
    """A fitted floor homography.

    Attributes:
        homography: 3×3 float64, maps (u, v, 1) image pixels to (x, y, 1) arena metres.
        layout: the marker layout the homography was fitted for.
        image_size: (width, height) [px] of the images it was fitted on.
        frames_used: how many frames contributed corner-marker positions.
        intrinsics: the lens model whose undistorted pixels ``homography`` maps (None: it maps
            the raw pixels, no lens model).
    """

    homography: FloatArray
    layout: ArenaLayout
    image_size: tuple[int, int]
    frames_used: int = 1
    intrinsics: CameraIntrinsics | None = None

    def __post_init__(self) -> None:
        matrix = np.asarray(self.homography, dtype=np.float64)
        if matrix.shape != (3, 3) or not np.all(np.isfinite(matrix)):
            raise ValueError(f"expected a finite 3×3 homography, got shape {matrix.shape}")
        check_magnitude("homography", matrix, MAX_HOMOGRAPHY_ENTRY)
        if abs(np.linalg.det(matrix)) < 1e-15 or not np.linalg.cond(matrix) < MAX_CONDITION:
            raise ValueError("expected an invertible homography, got a singular matrix")
        if len(self.image_size) != 2 or min(self.image_size) <= 0:
            raise ValueError(
                f"expected a positive (width, height) image_size, got {self.image_size}"
            )
        if self.frames_used < 1:
            raise ValueError(f"expected frames_used >= 1, got {self.frames_used}")
        if self.intrinsics is not None and self.intrinsics.image_size != tuple(self.image_size):
            raise ValueError(
                f"expected intrinsics for the {self.image_size} px images, "
                f"got {self.intrinsics.image_size}"
            )
        object.__setattr__(self, "homography", matrix)

    @cached_property
    def camera_pose(self) -> CameraPose | None:
        """The camera's pose over the arena from K and the homography (None without intrinsics).

        Raises:
            ValueError: the homography and K put the camera below the floor.
        """
        if self.intrinsics is None:
            return None
        return camera_pose(self.intrinsics.camera_matrix, self.homography)

    def ideal_pixels(self, pixels: FloatArray) -> FloatArray:
        """The pixels (n, 2) the homography applies to: undistorted if there is a lens model."""
        return _ideal_pixels(self.intrinsics, pixels)

    def marker_pose(self, corners: FloatArray, height: float = 0.0) -> tuple[float, float, float]:
        """Pose (x [m], y [m], heading [rad]) of a marker from its detected pixel corners (4, 2).

        Args:
            corners: the marker's corners as detected (distorted pixels), OpenCV order.
            height: the marker's height [m] above the corner-marker plane; non-zero needs the
                intrinsics (the correction scales about the camera's nadir, see
                :func:`~skidnav.realtime.camera.lens.correct_for_height`).
        """
        x, y, heading = floor_pose(self.homography, self.ideal_pixels(corners))
        if height != 0.0:
            pose = self.camera_pose
            if pose is None:
                raise ValueError("a marker height correction needs a calibration with intrinsics")
            x, y = correct_for_height(np.array([[x, y]]), pose.position, height)[0]
        return float(x), float(y), heading

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
            "intrinsics": None if self.intrinsics is None else self.intrinsics.to_json(),
        }

    def save(self, path: str | Path) -> None:
        """Write the calibration as JSON to ``path``."""
        write_json_file(path, self.to_json(), "calibration")

    @classmethod
    def from_json(cls, data: Any, source: str = "calibration") -> FloorCalibration:
        """Rebuild from :meth:`to_json` output; raises ``CorruptFileError`` naming ``source``."""
        if not isinstance(data, dict) or data.get("format") != FORMAT_NAME:
            raise CorruptFileError(f"{source}: not a skidnav camera calibration")
        version = data.get("version")
        if version not in READABLE_VERSIONS:
            raise CorruptFileError(
                f"{source}: calibration version {version!r}, expected one of {READABLE_VERSIONS}"
            )
        intrinsics = _intrinsics_field(data, version, source)
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
                intrinsics=intrinsics,
            )
        except KeyError as error:
            raise CorruptFileError(f"{source}: missing field {error.args[0]!r}") from None
        except (TypeError, ValueError) as error:
            raise CorruptFileError(f"{source}: {first_line(error)}") from None


def _intrinsics_field(data: dict[str, Any], version: int, source: str) -> CameraIntrinsics | None:
    """The embedded lens model: required (maybe null) from version 2 on, absent in version 1."""
    if version >= 2 and "intrinsics" not in data:
        raise CorruptFileError(f"{source}: missing field 'intrinsics'")
    lens = data.get("intrinsics")
    return None if lens is None else CameraIntrinsics.from_json(lens, f"{source}: intrinsics")


def load_calibration(path: str | Path, expected: ArenaLayout | None = None) -> FloorCalibration:
    """Read and validate a calibration file.

    Args:
        path: JSON file written by :meth:`FloorCalibration.save`.
        expected: if given, the layout the caller wants; any difference (arena size, ids,
            positions, dictionary) is a ``UserError``.

    Raises:
        UserError: missing file or layout mismatch. CorruptFileError: unreadable or invalid content.
    """
    data = read_json_file(path, "calibration")
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
    frames: Iterable[Frame],
    layout: ArenaLayout | None = None,
    max_frames: int = 10,
    intrinsics: CameraIntrinsics | None = None,
) -> FloorCalibration:
    """Fit the floor homography from the corner markers seen in up to ``max_frames`` frames.

    Each corner marker's image centre (diagonal intersection) is the per-axis median over the
    frames in which all four corner markers were found, which rejects an occasional bad detection.
    With ``intrinsics`` the marker corners are undistorted first, so the homography maps ideal
    pinhole pixels (where the diagonal intersection is the true centre) and the lens model is
    stored with it.

    Raises:
        UserError: no frame showed all four corner markers (names the ones missing last), or a
            frame's size is not the intrinsics' size.
    """
    layout = layout or ArenaLayout()
    if max_frames < 1:
        raise ValueError(f"expected max_frames >= 1, got {max_frames}")
    centres, image_size = _corner_centres(frames, layout, max_frames, intrinsics)
    pixels = np.median(np.stack(centres), axis=0)
    homography = fit_homography(pixels, np.asarray(layout.corners()))
    LOGGER.info("calibrated from %d frames, image %s", len(centres), image_size)
    if not math.isfinite(float(np.linalg.cond(homography))):
        raise UserError("degenerate corner-marker view; check the camera view")
    return FloorCalibration(
        homography, layout, image_size, frames_used=len(centres), intrinsics=intrinsics
    )


def _corner_centres(
    frames: Iterable[Frame],
    layout: ArenaLayout,
    max_frames: int,
    intrinsics: CameraIntrinsics | None,
) -> tuple[list[FloatArray], tuple[int, int]]:
    """Corner-marker centres (4, 2) [px] per usable frame, and the frames' (width, height) [px]."""
    detector = MarkerDetector(layout.dictionary)
    centres: list[FloatArray] = []
    image_size = (0, 0)
    missing: list[int] = list(layout.corner_ids)
    for count, frame in enumerate(frames, start=1):
        size = (int(frame.image.shape[1]), int(frame.image.shape[0]))
        if intrinsics is not None:
            intrinsics.check_image_size(size, f"frame {frame.number}")
        found = detector.detect(frame.image)
        missing = [i for i in layout.corner_ids if i not in found]
        if not missing:
            ideal = [_ideal_pixels(intrinsics, found[i]) for i in layout.corner_ids]
            centres.append(np.stack([quad_centre(corners) for corners in ideal]))
            image_size = size
        if len(centres) >= max_frames or count >= 10 * max_frames:
            break
    if not centres:
        raise UserError(f"corner markers {missing} not found in any frame; check the camera view")
    return centres, image_size


def _ideal_pixels(intrinsics: CameraIntrinsics | None, pixels: FloatArray) -> FloatArray:
    """``pixels`` (n, 2) undistorted through ``intrinsics``, or unchanged without a lens model."""
    if intrinsics is None:
        return np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
    return undistort_pixels(intrinsics, pixels)


def check_intrinsics(
    calibration: FloorCalibration, intrinsics: CameraIntrinsics | None, source: str
) -> None:
    """Raise ``UserError`` unless ``intrinsics`` (if given) is the lens model of ``calibration``.

    A homography fitted on raw pixels is wrong on undistorted ones and vice versa, so tracking
    must use exactly the lens model the floor was calibrated with (``source`` names the file).
    """
    if intrinsics is None:
        return
    if calibration.intrinsics is None:
        raise UserError(
            f"{source}: calibration was made without intrinsics; "
            "re-run `skidnav camera calibrate --intrinsics ...`"
        )
    if not calibration.intrinsics.same_model(intrinsics):
        raise UserError(
            f"{source}: calibration was made with other intrinsics; "
            "re-run `skidnav camera calibrate` with these"
        )
