"""ArUco marker detection and the floor geometry of an overhead camera.

The arena is seen by a fixed camera looking down. Four *corner markers* lie flat on the floor at
known positions (by default centred on the arena corners); one more marker rides on the robot. A
planar homography maps image pixels to arena metres (Hartley & Zisserman (2004) §4.1, the direct
linear transform); the robot's pose is read from its marker through that homography.

Conventions (docs/camera.md):

- Arena frame: x to the right, **y up**, metres, heading counter-clockwise from +x (as everywhere in
  skidnav). Image frame: u to the right, **v down**, pixels. The flip is absorbed by the homography,
  which is fitted from pixel positions to arena positions.
- A marker's corners are reported by OpenCV in the order top-left, top-right, bottom-right,
  bottom-left of the printed pattern (Garrido-Jurado et al. (2014)). The robot marker is mounted
  with the printed pattern's top edge towards the robot's front, so the heading is the direction
  from the bottom edge's midpoint to the top edge's midpoint.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from skidnav.realtime.camera.defaults import DEFAULT_DICTIONARY
from skidnav.realtime.camera.opencv import cv2

FloatArray = NDArray[np.float64]


def aruco_dictionary(name: str) -> cv2.aruco.Dictionary:
    """The predefined OpenCV ArUco dictionary called ``name`` (e.g. ``"DICT_4X4_50"``)."""
    if not name.startswith("DICT_") or not hasattr(cv2.aruco, name):
        raise ValueError(f"expected an OpenCV ArUco dictionary name like DICT_4X4_50, got {name!r}")
    return cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name))


@dataclass(frozen=True)
class ArenaLayout:
    """Where the markers are: the physical set-up that a calibration is made for.

    Attributes:
        arena_width: arena extent along x [m].
        arena_height: arena extent along y [m].
        corner_ids: ids of the four floor markers, in the order of ``corner_positions``.
        corner_positions: arena position [m] of each floor marker's centre, shape (4, 2); ``None``
            means the arena corners (0, 0), (W, 0), (W, H), (0, H).
        robot_id: id of the marker carried by the robot.
        dictionary: OpenCV ArUco dictionary name.

    >>> ArenaLayout().corners()[2]
    (0.62, 0.505)
    >>> ArenaLayout(robot_id=2)
    Traceback (most recent call last):
    ...
    ValueError: expected robot_id distinct from corner_ids (0, 1, 2, 3), got 2
    """

    arena_width: float = 0.62
    arena_height: float = 0.505
    corner_ids: tuple[int, int, int, int] = (0, 1, 2, 3)
    corner_positions: tuple[tuple[float, float], ...] | None = None
    robot_id: int = 4
    dictionary: str = DEFAULT_DICTIONARY

    def __post_init__(self) -> None:
        if not (self.arena_width > 0 and self.arena_height > 0):
            raise ValueError(
                f"expected a positive arena size, got {self.arena_width} × {self.arena_height} m"
            )
        if len(self.corner_ids) != 4 or len(set(self.corner_ids)) != 4:
            raise ValueError(f"expected 4 distinct corner_ids, got {self.corner_ids}")
        if self.robot_id in self.corner_ids:
            raise ValueError(
                f"expected robot_id distinct from corner_ids {self.corner_ids}, got {self.robot_id}"
            )
        size = aruco_dictionary(self.dictionary).bytesList.shape[0]
        if (
            min((*self.corner_ids, self.robot_id)) < 0
            or max((*self.corner_ids, self.robot_id)) >= size
        ):
            raise ValueError(f"expected marker ids in [0, {size}) for {self.dictionary}")
        if self.corner_positions is not None:
            points = np.asarray(self.corner_positions, dtype=np.float64)
            if points.shape != (4, 2) or not np.all(np.isfinite(points)):
                raise ValueError(
                    f"expected 4 finite (x, y) corner_positions, got {self.corner_positions}"
                )
            if abs(_signed_area(points)) < 1e-6:
                raise ValueError("expected corner_positions spanning an area, got collinear points")

    def corners(self) -> tuple[tuple[float, float], ...]:
        """Arena positions [m] of the four floor-marker centres, in ``corner_ids`` order."""
        if self.corner_positions is not None:
            return tuple((float(x), float(y)) for x, y in self.corner_positions)
        width, height = self.arena_width, self.arena_height
        return ((0.0, 0.0), (width, 0.0), (width, height), (0.0, height))


def _signed_area(points: FloatArray) -> float:
    """Shoelace area of the polygon ``points`` (n, 2)."""
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


class MarkerDetector:
    """Finds ArUco markers in images (OpenCV ``cv2.aruco.ArucoDetector``).

    Corners are refined to sub-pixel precision (``CORNER_REFINE_SUBPIX``), which the millimetre
    accuracy of docs/camera.md relies on.
    """

    def __init__(self, dictionary: str = DEFAULT_DICTIONARY) -> None:
        parameters = cv2.aruco.DetectorParameters()
        parameters.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
        self._detector = cv2.aruco.ArucoDetector(aruco_dictionary(dictionary), parameters)

    def detect(self, image: NDArray[np.uint8]) -> dict[int, FloatArray]:
        """Markers in ``image`` (grey (h, w) or BGR (h, w, 3)) as id → pixel corners (4, 2).

        Corners are (u, v) pixels in OpenCV order (top-left, top-right, bottom-right, bottom-left
        of the printed pattern). An id seen twice keeps its first detection.
        """
        grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
        corners, ids, _rejected = self._detector.detectMarkers(grey)
        found: dict[int, FloatArray] = {}
        if ids is None:
            return found
        for marker_id, marker_corners in zip(ids.ravel(), corners, strict=True):
            found.setdefault(int(marker_id), np.asarray(marker_corners, np.float64).reshape(4, 2))
        return found


def quad_centre(corners: FloatArray) -> FloatArray:
    """Intersection of the diagonals of the quadrilateral ``corners`` (4, 2), shape (2,).

    Under a perspective view this is the image of the square's true centre (a homography maps lines
    to lines), unlike the mean of the corners.
    """
    p0, p1, p2, p3 = (np.append(corner, 1.0) for corner in corners)
    point = np.cross(np.cross(p0, p2), np.cross(p1, p3))
    if abs(point[2]) < 1e-12:
        raise ValueError("expected a convex marker quadrilateral, got parallel diagonals")
    return np.asarray(point[:2] / point[2], dtype=np.float64)


def apply_homography(homography: FloatArray, points: FloatArray) -> FloatArray:
    """Map points (n, 2) through the 3×3 ``homography``; returns (n, 2)."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    mapped = np.hstack([points, np.ones((len(points), 1))]) @ homography.T
    return np.asarray(mapped[:, :2] / mapped[:, 2:3], dtype=np.float64)


def floor_pose(homography: FloatArray, corners: FloatArray) -> tuple[float, float, float]:
    """Pose (x [m], y [m], heading [rad] in (-π, π]) of a marker from its pixel corners (4, 2).

    The corners are first mapped to the floor, so both the centre (diagonal intersection) and the
    heading (bottom-edge midpoint → top-edge midpoint) are measured in metric arena coordinates.
    """
    floor = apply_homography(homography, corners)
    x, y = quad_centre(floor)
    forward = 0.5 * (floor[0] + floor[1]) - 0.5 * (floor[3] + floor[2])
    return float(x), float(y), math.atan2(float(forward[1]), float(forward[0]))


def fit_homography(pixels: FloatArray, floor: FloatArray) -> FloatArray:
    """The 3×3 homography (pixels → metres) from ≥ 4 point pairs (n, 2), least squares.

    Uses ``cv2.findHomography`` without outlier rejection (all pairs are trusted marker centres).
    """
    homography, _mask = cv2.findHomography(
        np.asarray(pixels, np.float64), np.asarray(floor, np.float64), 0
    )
    if homography is None or not np.all(np.isfinite(homography)):
        raise ValueError("expected corner markers in general position, got a degenerate layout")
    return np.asarray(homography / homography[2, 2], dtype=np.float64)
