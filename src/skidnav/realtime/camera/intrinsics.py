"""Camera intrinsics: the lens model, its JSON file, and its calibration from ChArUco board views.

The model is OpenCV's pinhole camera with radial-tangential distortion (Brown (1966); Zhang
(2000)): a camera-frame point (X, Y, Z) has normalised coordinates x = X/Z, y = Y/Z, r² = x² + y²,
is distorted to

    x_d = x (1 + k1 r² + k2 r⁴ + k3 r⁶) + 2 p1 x y + p2 (r² + 2 x²)
    y_d = y (1 + k1 r² + k2 r⁴ + k3 r⁶) + p1 (r² + 2 y²) + 2 p2 x y

and seen at the pixel (u, v) = (fx x_d + s y_d + cx, fy y_d + cy). :class:`CameraIntrinsics` holds
the camera matrix K = [[fx, s, cx], [0, fy, cy], [0, 0, 1]] and (k1, k2, p1, p2, k3) for one image
size; :func:`calibrate_intrinsics` fits them with ``cv2.calibrateCamera`` from the chessboard
corners that ``cv2.aruco.CharucoDetector`` finds in views of a :class:`CharucoBoardSpec`.
Files are JSON (never pickle) and are validated on loading (docs/camera.md, "Lens model").
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skidnav.errors import CorruptFileError, UserError, first_line
from skidnav.realtime.camera.defaults import (
    BOARD_MARKER_SIZE,
    BOARD_SQUARE_SIZE,
    BOARD_SQUARES,
    DEFAULT_BOARD_DICTIONARY,
    MIN_VIEWS,
)
from skidnav.realtime.camera.markers import FloatArray, aruco_dictionary
from skidnav.realtime.camera.opencv import cv2
from skidnav.realtime.camera.sources import read_json_file, write_json_file

LOGGER = logging.getLogger(__name__)

FORMAT_NAME = "skidnav-camera-intrinsics"
FORMAT_VERSION = 1
DISTORTION_MODEL = "k1 k2 p1 p2 k3"
MIN_CORNERS = 6  # ChArUco corners, not all on one line, for a view to count
RMS_WARNING = 1.0  # [px] reprojection error above which the views are probably poor


@dataclass(frozen=True)
class CharucoBoardSpec:
    """A ChArUco board: a chessboard with an ArUco marker in each white square.

    Attributes:
        squares: (columns, rows) of chessboard squares, each ≥ 3.
        square_size: side of one square [m] (as printed; it scales only the board poses, so an
            error in it leaves K and the distortion unchanged).
        marker_size: side of one marker [m], less than ``square_size``.
        dictionary: OpenCV ArUco dictionary name of the markers.

    >>> CharucoBoardSpec().corners
    24
    >>> CharucoBoardSpec(marker_size=0.03)
    Traceback (most recent call last):
    ...
    ValueError: expected 0 < marker_size < square_size = 0.03 m, got 0.03 m
    """

    squares: tuple[int, int] = BOARD_SQUARES
    square_size: float = BOARD_SQUARE_SIZE
    marker_size: float = BOARD_MARKER_SIZE
    dictionary: str = DEFAULT_BOARD_DICTIONARY

    def __post_init__(self) -> None:
        columns, rows = self.squares
        if not (3 <= columns <= 100 and 3 <= rows <= 100):
            raise ValueError(f"expected 3 to 100 squares per side, got {columns} × {rows}")
        if not (math.isfinite(self.square_size) and self.square_size > 0):
            raise ValueError(f"expected a positive square_size [m], got {self.square_size}")
        if not 0 < self.marker_size < self.square_size:
            raise ValueError(
                f"expected 0 < marker_size < square_size = {self.square_size} m, "
                f"got {self.marker_size} m"
            )
        available = aruco_dictionary(self.dictionary).bytesList.shape[0]
        if columns * rows // 2 > available:
            raise ValueError(
                f"expected at most {available} markers for {self.dictionary}, "
                f"a {columns} × {rows} board needs {columns * rows // 2}"
            )

    @property
    def corners(self) -> int:
        """Number of inner chessboard corners, the points a full view yields."""
        return (self.squares[0] - 1) * (self.squares[1] - 1)

    def board(self) -> cv2.aruco.CharucoBoard:
        """The OpenCV board; its corner coordinates [m] start at the board's top-left corner."""
        dictionary = aruco_dictionary(self.dictionary)
        return cv2.aruco.CharucoBoard(self.squares, self.square_size, self.marker_size, dictionary)

    def image(self, pixels_per_square: int = 120) -> NDArray[np.uint8]:
        """Grey printable image of the board with a white margin of half a square, uint8 (h, w)."""
        if pixels_per_square < 20:
            raise ValueError(f"expected pixels_per_square >= 20, got {pixels_per_square}")
        columns, rows = self.squares
        size = (columns * pixels_per_square, rows * pixels_per_square)
        image = self.board().generateImage(size, marginSize=0, borderBits=1)
        margin = pixels_per_square // 2
        padded = cv2.copyMakeBorder(
            image, margin, margin, margin, margin, cv2.BORDER_CONSTANT, value=255
        )
        return np.asarray(padded, np.uint8)

    def to_json(self) -> dict[str, Any]:
        """The JSON-ready description stored in an intrinsics file."""
        return {
            "squares": list(self.squares),
            "square_size": self.square_size,
            "marker_size": self.marker_size,
            "dictionary": self.dictionary,
        }

    @classmethod
    def from_json(cls, data: Any) -> CharucoBoardSpec:
        """Rebuild from :meth:`to_json` output (``KeyError``, ``TypeError``, ``ValueError``)."""
        columns, rows = (_integer(value, "board squares") for value in data["squares"])
        return cls(
            squares=(columns, rows),
            square_size=float(data["square_size"]),
            marker_size=float(data["marker_size"]),
            dictionary=str(data["dictionary"]),
        )


def _integer(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"expected an integer {name}, got {value!r}")
    return value


def _image_size(value: Any) -> tuple[int, int]:
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise ValueError(f"expected image_size [width, height], got {value!r}")
    width, height = (_integer(v, "image_size") for v in value)
    return width, height


@dataclass(frozen=True)
class CameraIntrinsics:
    """A calibrated lens model for one image size (see the module docstring for the equations).

    Attributes:
        camera_matrix: K, 3×3 float64 [px]: focal lengths fx, fy, skew s, principal point cx, cy.
        distortion: (k1, k2, p1, p2, k3), shape (5,), dimensionless (of normalised coordinates).
        image_size: (width, height) [px] of the images it describes.
        rms_error: RMS reprojection error [px] of the calibration.
        views_used: how many board views the calibration used.
        board: the board it was calibrated with (None if not recorded).
    """

    camera_matrix: FloatArray
    distortion: FloatArray
    image_size: tuple[int, int]
    rms_error: float
    views_used: int
    board: CharucoBoardSpec | None = None

    def __post_init__(self) -> None:
        matrix = np.asarray(self.camera_matrix, dtype=np.float64)
        coefficients = np.asarray(self.distortion, dtype=np.float64)
        width, height = self.image_size
        if not (width > 0 and height > 0):
            raise ValueError(f"expected a positive image_size, got {self.image_size}")
        if matrix.shape != (3, 3) or not np.all(np.isfinite(matrix)):
            raise ValueError(f"expected a finite 3×3 camera_matrix, got shape {matrix.shape}")
        if not np.allclose(matrix[[1, 2, 2], [0, 0, 1]], 0) or not math.isclose(matrix[2, 2], 1):
            raise ValueError("expected camera_matrix rows [fx, s, cx], [0, fy, cy], [0, 0, 1]")
        if not (matrix[0, 0] > 0 and matrix[1, 1] > 0):
            raise ValueError(f"expected positive focal lengths, got {matrix[0, 0]}, {matrix[1, 1]}")
        if not (0 <= matrix[0, 2] <= width and 0 <= matrix[1, 2] <= height):
            raise ValueError(f"expected the principal point inside the {width}×{height} px image")
        if coefficients.shape != (5,) or not np.all(np.isfinite(coefficients)):
            raise ValueError(f"expected 5 finite distortion coefficients ({DISTORTION_MODEL})")
        if not (math.isfinite(self.rms_error) and self.rms_error >= 0):
            raise ValueError(f"expected a finite rms_error >= 0 px, got {self.rms_error}")
        if self.views_used < 1:
            raise ValueError(f"expected views_used >= 1, got {self.views_used}")
        object.__setattr__(self, "camera_matrix", matrix)
        object.__setattr__(self, "distortion", coefficients)

    def check_image_size(self, image_size: tuple[int, int], what: str) -> None:
        """Raise ``UserError`` unless ``image_size`` (width, height) [px] is the model's."""
        if tuple(image_size) != tuple(self.image_size):
            raise UserError(
                f"the intrinsics are for {self.image_size[0]}×{self.image_size[1]} px images "
                f"but {what} is {image_size[0]}×{image_size[1]} px"
            )

    def same_model(self, other: CameraIntrinsics) -> bool:
        """Whether ``other`` has the same image size, camera matrix and distortion."""
        return (
            tuple(self.image_size) == tuple(other.image_size)
            and np.allclose(self.camera_matrix, other.camera_matrix, rtol=1e-9, atol=1e-9)
            and np.allclose(self.distortion, other.distortion, rtol=1e-9, atol=1e-12)
        )

    def to_json(self) -> dict[str, Any]:
        """The JSON-ready dictionary written by :meth:`save` (docs/camera.md)."""
        return {
            "format": FORMAT_NAME,
            "version": FORMAT_VERSION,
            "image_size": list(self.image_size),
            "camera_matrix": self.camera_matrix.tolist(),
            "distortion_model": DISTORTION_MODEL,
            "distortion": self.distortion.tolist(),
            "rms_error_px": self.rms_error,
            "views_used": self.views_used,
            "board": None if self.board is None else self.board.to_json(),
        }

    def save(self, path: str | Path) -> None:
        """Write the intrinsics as JSON to ``path``."""
        write_json_file(path, self.to_json(), "intrinsics")

    @classmethod
    def from_json(cls, data: Any, source: str = "intrinsics") -> CameraIntrinsics:
        """Rebuild from :meth:`to_json` output; raises ``CorruptFileError`` naming ``source``."""
        if not isinstance(data, dict) or data.get("format") != FORMAT_NAME:
            raise CorruptFileError(f"{source}: not a skidnav camera intrinsics file")
        if data.get("version") != FORMAT_VERSION:
            raise CorruptFileError(
                f"{source}: intrinsics version {data.get('version')!r}, expected {FORMAT_VERSION}"
            )
        try:
            if data["distortion_model"] != DISTORTION_MODEL:
                raise ValueError(f"expected distortion_model {DISTORTION_MODEL!r}")
            board = data["board"]
            return cls(
                camera_matrix=np.asarray(data["camera_matrix"], dtype=np.float64),
                distortion=np.asarray(data["distortion"], dtype=np.float64),
                image_size=_image_size(data["image_size"]),
                rms_error=float(data["rms_error_px"]),
                views_used=_integer(data["views_used"], "views_used"),
                board=None if board is None else CharucoBoardSpec.from_json(board),
            )
        except KeyError as error:
            raise CorruptFileError(f"{source}: missing field {error.args[0]!r}") from None
        except (TypeError, ValueError) as error:
            raise CorruptFileError(f"{source}: {first_line(error)}") from None


def load_intrinsics(
    path: str | Path, image_size: tuple[int, int] | None = None, what: str = "the camera"
) -> CameraIntrinsics:
    """Read and validate an intrinsics file.

    Args:
        path: JSON file written by :meth:`CameraIntrinsics.save`.
        image_size: if given, the (width, height) [px] of the images it will be used on.
        what: names those images in the size-mismatch message.

    Raises:
        UserError: missing file or other image size. CorruptFileError: unreadable or invalid.
    """
    intrinsics = CameraIntrinsics.from_json(read_json_file(path, "intrinsics"), source=str(path))
    if image_size is not None:
        intrinsics.check_image_size(image_size, f"{what} ({path})")
    return intrinsics


def board_view(
    detector: cv2.aruco.CharucoDetector, board: cv2.aruco.CharucoBoard, image: NDArray[np.uint8]
) -> tuple[NDArray[np.float32], NDArray[np.float32]] | None:
    """Board points (n, 3) [m] and their pixels (n, 2) in ``image``, or None if too few corners.

    A view counts with at least :data:`MIN_CORNERS` corners that are not all on one line (a line
    constrains no homography, and ``cv2.calibrateCamera`` starts from one per view).
    """
    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
    corners, ids, _marker_corners, _marker_ids = detector.detectBoard(grey)
    if ids is None or len(ids) < MIN_CORNERS:
        return None
    # A ChArUco corner's id is its index in the board's inner-corner list.
    board_points = np.asarray(board.getChessboardCorners(), np.float32).reshape(-1, 3)
    object_points = board_points[np.asarray(ids, np.intp).ravel()]
    spread = object_points[:, :2] - object_points[:, :2].mean(axis=0)
    if np.linalg.matrix_rank(spread, tol=1e-6) < 2:
        return None
    return object_points, np.asarray(corners, np.float32).reshape(-1, 2)


def _common_size(images: Sequence[tuple[str, NDArray[np.uint8]]]) -> tuple[int, int]:
    """The (width, height) [px] shared by all images; ``UserError`` naming the first other one."""
    height, width = images[0][1].shape[:2]
    for name, image in images[1:]:
        if image.shape[:2] != (height, width):
            raise UserError(
                f"{name}: image is {image.shape[1]}×{image.shape[0]} px, the first is "
                f"{width}×{height} px; calibrate one camera mode at a time"
            )
    return width, height


def calibrate_intrinsics(
    images: Sequence[tuple[str, NDArray[np.uint8]]],
    spec: CharucoBoardSpec,
    min_views: int = MIN_VIEWS,
) -> CameraIntrinsics:
    """Fit K and (k1, k2, p1, p2, k3) from named views (name, BGR or grey image) of the board.

    Views without enough corners are skipped (logged); the rest go to ``cv2.calibrateCamera``
    (Zhang (2000): a closed-form start from each view's homography, then Levenberg–Marquardt on
    the reprojection error).

    Raises:
        UserError: no images, images of different sizes, the board in no image, fewer than
            ``min_views`` usable views, or a calibration that fails or gives an invalid model.
    """
    if min_views < 3:
        raise ValueError(f"expected min_views >= 3, got {min_views}")
    if not images:
        raise UserError("no images to calibrate from")
    image_size = _common_size(images)
    object_points, image_points = _board_views(images, spec)
    views = len(object_points)
    if views == 0:
        raise UserError(
            f"ChArUco board ({spec.squares[0]}×{spec.squares[1]} squares, {spec.dictionary}) not "
            f"found in any of the {len(images)} images; check --squares and --dictionary"
        )
    if views < min_views:
        raise UserError(
            f"only {views} of the {len(images)} images show the board (≥ {MIN_CORNERS} corners); "
            f"need at least {min_views} views"
        )
    return _fit(object_points, image_points, image_size, spec)


def _board_views(
    images: Sequence[tuple[str, NDArray[np.uint8]]], spec: CharucoBoardSpec
) -> tuple[list[NDArray[np.float32]], list[NDArray[np.float32]]]:
    """Board points (n, 3) [m] and pixels (n, 2) of every usable view (others logged, skipped)."""
    board = spec.board()
    detector = cv2.aruco.CharucoDetector(board)
    object_points, image_points = [], []
    for name, image in images:
        view = board_view(detector, board, image)
        if view is None:
            LOGGER.warning("%s: fewer than %d board corners found, skipped", name, MIN_CORNERS)
            continue
        object_points.append(view[0])
        image_points.append(view[1])
    return object_points, image_points


def _fit(
    object_points: list[NDArray[np.float32]],
    image_points: list[NDArray[np.float32]],
    image_size: tuple[int, int],
    spec: CharucoBoardSpec,
) -> CameraIntrinsics:
    """``cv2.calibrateCamera`` on the collected views, its failures as ``UserError``."""
    try:
        rms, matrix, coefficients, _rvecs, _tvecs = cv2.calibrateCamera(
            object_points, image_points, image_size, None, None
        )
        intrinsics = CameraIntrinsics(
            camera_matrix=np.asarray(matrix, np.float64),
            distortion=np.asarray(coefficients, np.float64).ravel()[:5],
            image_size=image_size,
            rms_error=float(rms),
            views_used=len(object_points),
            board=spec,
        )
    except (cv2.error, ValueError) as error:
        raise UserError(
            f"lens calibration failed ({first_line(error)}); take more views at varied tilts"
        ) from None
    if intrinsics.rms_error > RMS_WARNING:
        LOGGER.warning("RMS reprojection error %.2f px: check the views", intrinsics.rms_error)
    LOGGER.info("lens calibrated from %d views, RMS %.3f px", intrinsics.views_used, rms)
    return intrinsics
