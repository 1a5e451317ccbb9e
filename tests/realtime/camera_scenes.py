"""Synthetic overhead-camera images for the camera tests (imported explicitly, not a conftest).

A scene is rendered by drawing each ArUco marker (``cv2.aruco.generateImageMarker``) straight into
the camera image through a known floor → pixel perspective homography, at twice the resolution,
then area-averaged down (a cheap stand-in for a lens's blur and pixel integration).

The lens scenes (:class:`LensCamera`, below) are ray-cast through a pinhole camera with a known
lens distortion instead, for the intrinsics and height-correction tests.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from typing import NamedTuple

import cv2
import numpy as np
from numpy.typing import NDArray

from skidnav.realtime.camera.tracking import ArenaLayout, CameraIntrinsics, CharucoBoardSpec

IMAGE_SIZE = (1280, 960)  # (width, height) px
CORNER_MARKER_SIZE = 0.05  # m
ROBOT_MARKER_SIZE = 0.04  # m
FLOOR_GREY = 205

# Where the arena corners (0,0), (W,0), (W,H), (0,H) appear: a trapezoid, as a tilted camera sees.
TILTED_VIEW = ((170.0, 860.0), (1110.0, 885.0), (1015.0, 110.0), (245.0, 85.0))


def camera_homography(layout: ArenaLayout, view: Sequence[tuple[float, float]] = TILTED_VIEW):
    """The true floor [m] → image [px] homography (3×3) putting the arena corners at ``view``."""
    floor = np.asarray(ArenaLayout(layout.arena_width, layout.arena_height).corners(), np.float32)
    return cv2.getPerspectiveTransform(floor, np.asarray(view, np.float32)).astype(np.float64)


def marker_floor_corners(x: float, y: float, heading: float, size: float) -> NDArray[np.float64]:
    """Floor corners (4, 2) [m] of a marker centred at (x, y) whose printed top faces ``heading``.

    Order top-left, top-right, bottom-right, bottom-left as seen from above (y up), so the
    top-left corner is forward-and-left of the centre.
    """
    forward = np.array([math.cos(heading), math.sin(heading)]) * size / 2
    left = np.array([-math.sin(heading), math.cos(heading)]) * size / 2
    centre = np.array([x, y])
    return np.stack(
        [
            centre + forward + left,
            centre + forward - left,
            centre - forward - left,
            centre - forward + left,
        ]
    )


def _draw_marker(canvas, marker_id, floor_corners, floor_to_px, dictionary) -> None:
    pattern = cv2.aruco.generateImageMarker(dictionary, marker_id, 240)
    n = pattern.shape[0]
    source = np.array([[-0.5, -0.5], [n - 0.5, -0.5], [n - 0.5, n - 0.5], [-0.5, n - 0.5]])
    mapped = np.hstack([floor_corners, np.ones((4, 1))]) @ floor_to_px.T
    target = mapped[:, :2] / mapped[:, 2:3]
    warp = cv2.getPerspectiveTransform(source.astype(np.float32), target.astype(np.float32))
    size = (canvas.shape[1], canvas.shape[0])
    drawn = cv2.warpPerspective(pattern.astype(np.float32), warp, size, flags=cv2.INTER_LINEAR)
    mask = cv2.warpPerspective(
        np.ones_like(pattern, np.float32), warp, size, flags=cv2.INTER_LINEAR
    )
    canvas[:] = canvas * (1.0 - mask) + drawn * mask


def render_scene(
    layout: ArenaLayout,
    robot: tuple[float, float, float] | None,
    view: Sequence[tuple[float, float]] = TILTED_VIEW,
    supersample: int = 2,
) -> NDArray[np.uint8]:
    """BGR image (960, 1280, 3) of the corner markers and the robot at (x, y, heading), if any."""
    scale = np.array(
        [
            [supersample, 0, (supersample - 1) / 2],
            [0, supersample, (supersample - 1) / 2],
            [0, 0, 1.0],
        ]
    )
    floor_to_px = scale @ camera_homography(layout, view)
    width, height = IMAGE_SIZE
    canvas = np.full((height * supersample, width * supersample), float(FLOOR_GREY), np.float32)
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, layout.dictionary))
    for marker_id, (x, y) in zip(layout.corner_ids, layout.corners(), strict=True):
        corners = marker_floor_corners(x, y, math.pi / 2, CORNER_MARKER_SIZE)
        _draw_marker(canvas, marker_id, corners, floor_to_px, dictionary)
    if robot is not None:
        corners = marker_floor_corners(*robot, ROBOT_MARKER_SIZE)
        _draw_marker(canvas, layout.robot_id, corners, floor_to_px, dictionary)
    small = cv2.resize(canvas, IMAGE_SIZE, interpolation=cv2.INTER_AREA)
    grey = np.clip(np.rint(small), 0, 255).astype(np.uint8)
    return cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)


def degrade(
    image: NDArray[np.uint8], rng: np.random.Generator, blur_sigma: float, noise_sigma: float
) -> NDArray[np.uint8]:
    """Gaussian blur (σ [px]) then additive Gaussian pixel noise (σ [grey levels]), clipped."""
    blurred = cv2.GaussianBlur(image.astype(np.float32), (0, 0), blur_sigma)
    noisy = blurred + rng.normal(0.0, noise_sigma, size=image.shape)
    return np.clip(np.rint(noisy), 0, 255).astype(np.uint8)


def heading_error(a: float, b: float) -> float:
    """Smallest absolute angle between two headings [rad]."""
    return abs(math.atan2(math.sin(a - b), math.cos(a - b)))


# --- A 3-D pinhole camera with lens distortion ------------------------------------------------
# The lens scenes are ray-cast: every (supersampled) pixel of the *distorted* image is turned into
# its camera ray by inverting the distortion model (Newton's method, written here independently of
# OpenCV), the ray is intersected with each textured plane (a marker, or the ChArUco board) and
# the texture is sampled there. Markers can therefore sit at any height, and the image has exactly
# the distortion of LENS_MATRIX / LENS_DISTORTION.

LENS_IMAGE_SIZE = (640, 480)  # (width, height) px
LENS_MATRIX = np.array([[480.0, 0.0, 323.0], [0.0, 478.5, 237.5], [0.0, 0.0, 1.0]])
LENS_DISTORTION = np.array([-0.25, 0.05, 0.0005, -0.0004, 0.0])  # k1 k2 p1 p2 k3
LENS_CAMERA_POSITION = (0.31, 0.10, 0.55)  # arena frame [m]: 0.55 m up, south of the centre
LENS_CAMERA_TARGET = (0.31, 0.26, 0.0)  # the point the optical axis meets on the floor [m]
BOARD_BACKGROUND = 120


def distort_normalised(points: NDArray[np.float64], distortion) -> NDArray[np.float64]:
    """OpenCV's radial-tangential model on normalised coordinates (..., 2)."""
    k1, k2, p1, p2, k3 = distortion
    x, y = points[..., 0], points[..., 1]
    r2 = x * x + y * y
    radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return np.stack([xd, yd], axis=-1)


def undistort_normalised(
    distorted: NDArray[np.float64], distortion, start: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """Inverse of :func:`distort_normalised` by Newton's method from ``start`` (default: the
    distorted points); raises if it does not converge to 1e-13."""
    k1, k2, p1, p2, k3 = distortion
    points = (distorted if start is None else start).copy()
    for _ in range(20):
        residual = distort_normalised(points, distortion) - distorted
        if np.abs(residual).max() < 1e-13:
            return points
        x, y = points[..., 0], points[..., 1]
        r2 = x * x + y * y
        radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        slope = 2 * (k1 + r2 * (2 * k2 + 3 * k3 * r2))  # d radial / d(x or y), over x or y
        a = radial + x * x * slope + 2 * p1 * y + 6 * p2 * x
        b = x * y * slope + 2 * p1 * x + 2 * p2 * y
        d = radial + y * y * slope + 6 * p1 * y + 2 * p2 * x
        determinant = a * d - b * b
        points[..., 0] -= (d * residual[..., 0] - b * residual[..., 1]) / determinant
        points[..., 1] -= (a * residual[..., 1] - b * residual[..., 0]) / determinant
    raise AssertionError("distortion not invertible over the image")


@functools.lru_cache(maxsize=4)
def _rays(matrix: tuple, distortion: tuple, image_size: tuple, supersample: int):
    """Camera-frame ray (x, y, 1) of every supersampled pixel centre, (h·s, w·s, 3)."""
    (fx, _, cx), (_, fy, cy), _ = matrix
    width, height = image_size
    u = (np.arange(width * supersample) + 0.5) / supersample - 0.5
    v = (np.arange(height * supersample) + 0.5) / supersample - 0.5
    grid = np.stack(np.meshgrid((u - cx) / fx, (v - cy) / fy), axis=-1)
    # Solve every 4th pixel, interpolate, then let Newton polish the whole grid (1-2 steps).
    coarse = undistort_normalised(grid[::4, ::4], distortion)
    size = (grid.shape[1], grid.shape[0])
    start = np.stack(
        [cv2.resize(coarse[..., i], size, interpolation=cv2.INTER_CUBIC) for i in (0, 1)], -1
    )
    ideal = undistort_normalised(grid, distortion, start)
    return np.concatenate([ideal, np.ones((*ideal.shape[:2], 1))], axis=-1)


class TexturedPlane(NamedTuple):
    """A flat picture in the camera frame: texture pixel (row, col) covers the square with corner
    ``origin + (col·e_col + row·e_row)·pixel_size`` [m]; e_col and e_row are unit vectors."""

    origin: NDArray[np.float64]
    e_col: NDArray[np.float64]
    e_row: NDArray[np.float64]
    pixel_size: float
    texture: NDArray[np.float32]

    def corners(self) -> NDArray[np.float64]:
        """The texture rectangle's four corners (4, 3) [m], camera frame."""
        rows, cols = self.texture.shape
        across, down = cols * self.pixel_size * self.e_col, rows * self.pixel_size * self.e_row
        return self.origin + np.array([0 * across, across, across + down, down])


class LensCamera:
    """A camera with K = LENS_MATRIX and LENS_DISTORTION unless told otherwise.

    ``rotation`` (3×3, world → camera) and ``position`` (3,) place it in a world frame (arena
    metres); the default world is the camera frame itself (used for board views).
    """

    def __init__(
        self,
        matrix=LENS_MATRIX,
        distortion=LENS_DISTORTION,
        image_size=LENS_IMAGE_SIZE,
        rotation=None,
        position=None,
        supersample: int = 2,
    ) -> None:
        self.matrix, self.distortion = np.asarray(matrix, float), np.asarray(distortion, float)
        self.image_size, self.supersample = tuple(image_size), supersample
        self.rotation = np.eye(3) if rotation is None else np.asarray(rotation, float)
        self.position = np.zeros(3) if position is None else np.asarray(position, float)
        key = tuple(map(tuple, self.matrix)), tuple(self.distortion), self.image_size, supersample
        self.rays = _rays(*key)

    @classmethod
    def over_arena(cls, position=LENS_CAMERA_POSITION, target=LENS_CAMERA_TARGET, **kwargs):
        """A camera at ``position`` [m] looking at ``target`` [m], image right ≈ arena +x."""
        position, target = np.asarray(position, float), np.asarray(target, float)
        axis = (target - position) / np.linalg.norm(target - position)
        right = np.array([1.0, 0.0, 0.0]) - axis[0] * axis
        right /= np.linalg.norm(right)
        rotation = np.stack([right, np.cross(axis, right), axis])  # rows: camera x, y, z in arena
        return cls(rotation=rotation, position=position, **kwargs)

    def to_camera(self, points) -> NDArray[np.float64]:
        """World points (n, 3) [m] in the camera frame."""
        return (np.asarray(points, float) - self.position) @ self.rotation.T

    def project_camera(self, camera_points) -> NDArray[np.float64]:
        """Distorted pixels (n, 2) of camera-frame points (n, 3) [m]."""
        camera_points = np.asarray(camera_points, float)
        normalised = camera_points[:, :2] / camera_points[:, 2:3]
        distorted = distort_normalised(normalised, self.distortion)
        return distorted * np.diag(self.matrix)[:2] + self.matrix[:2, 2]

    def project(self, points) -> NDArray[np.float64]:
        """Distorted pixels (n, 2) of world points (n, 3) [m]."""
        return self.project_camera(self.to_camera(points))

    def plane(self, origin, e_col, e_row, pixel_size: float, texture) -> TexturedPlane:
        """A :class:`TexturedPlane` given in world coordinates."""
        return TexturedPlane(
            self.to_camera([origin])[0],
            self.rotation @ np.asarray(e_col, float),
            self.rotation @ np.asarray(e_row, float),
            pixel_size,
            np.asarray(texture, np.float32),
        )

    def _window(self, plane: TexturedPlane) -> tuple[slice, slice]:
        """The supersampled rows and columns the plane can cover (all if it reaches behind)."""
        corners = plane.corners()
        height, width = self.rays.shape[:2]
        if not np.all(corners[:, 2] > 1e-3):
            return slice(0, height), slice(0, width)
        pixels = (self.project_camera(corners) + 0.5) * self.supersample
        margin = 0.02 * width + 8  # distortion bends the edges between the corners
        low = np.floor(pixels.min(axis=0) - margin).astype(int).clip(0, [width, height])
        high = np.ceil(pixels.max(axis=0) + margin).astype(int).clip(0, [width, height])
        return slice(low[1], high[1]), slice(low[0], high[0])

    def render(self, planes: Sequence[TexturedPlane], background: float) -> NDArray[np.uint8]:
        """BGR image of the planes (later ones in front) over a uniform ``background``."""
        canvas = np.full(self.rays.shape[:2], float(background), np.float32)
        for plane in planes:
            rows_window, cols_window = self._window(plane)
            rays = self.rays[rows_window, cols_window]
            if rays.size == 0:
                continue
            normal = np.cross(plane.e_col, plane.e_row)
            depth = float(plane.origin @ normal) / (rays @ normal)
            offset = rays * depth[..., None] - plane.origin
            outside = ~(depth > 0)
            cols = np.where(outside, -2.0, offset @ plane.e_col / plane.pixel_size - 0.5)
            rows = np.where(outside, -2.0, offset @ plane.e_row / plane.pixel_size - 0.5)
            maps = (cols.astype(np.float32), rows.astype(np.float32))
            drawn = cv2.remap(plane.texture, *maps, cv2.INTER_LINEAR, borderValue=0.0)
            mask = cv2.remap(np.ones_like(plane.texture), *maps, cv2.INTER_LINEAR, borderValue=0.0)
            region = canvas[rows_window, cols_window]
            region[:] = region * (1.0 - mask) + drawn * mask
        small = cv2.resize(canvas, self.image_size, interpolation=cv2.INTER_AREA)
        grey = np.clip(np.rint(small), 0, 255).astype(np.uint8)
        return cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)


def marker_plane(camera: LensCamera, marker_id, x, y, heading, size, height, dictionary):
    """The plane of a marker centred at (x, y) [m], ``height`` [m] up, top edge towards heading."""
    pattern = cv2.aruco.generateImageMarker(dictionary, marker_id, 240)
    top_left, top_right, _, bottom_left = marker_floor_corners(x, y, heading, size)
    e_col = np.append(top_right - top_left, 0.0) / size
    e_row = np.append(bottom_left - top_left, 0.0) / size
    origin = np.append(top_left, height)
    return camera.plane(origin, e_col, e_row, size / pattern.shape[0], pattern)


def render_lens_scene(
    camera: LensCamera,
    layout: ArenaLayout,
    robot: tuple[float, float, float] | None,
    robot_height: float = 0.0,
) -> NDArray[np.uint8]:
    """The corner markers on the floor, the robot marker ``robot_height`` [m] up, by ``camera``."""
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, layout.dictionary))
    planes = [
        marker_plane(camera, marker_id, x, y, math.pi / 2, CORNER_MARKER_SIZE, 0.0, dictionary)
        for marker_id, (x, y) in zip(layout.corner_ids, layout.corners(), strict=True)
    ]
    if robot is not None:
        robot_id, size = layout.robot_id, ROBOT_MARKER_SIZE
        planes.append(marker_plane(camera, robot_id, *robot, size, robot_height, dictionary))
    return camera.render(planes, FLOOR_GREY)


def render_board_view(
    camera: LensCamera, spec, tilt: tuple[float, float, float], centre, pixels_per_square: int = 40
) -> NDArray[np.uint8]:
    """The printed board (``spec.image``) with its centre at ``centre`` (camera frame, [m]),
    rotated by the rotation vector ``tilt`` [rad] from facing the camera squarely."""
    texture = spec.image(pixels_per_square)
    rotation, _ = cv2.Rodrigues(np.asarray(tilt, float))
    pixel = spec.square_size / pixels_per_square
    margin = (pixels_per_square // 2) * pixel
    half = np.array([spec.squares[0], spec.squares[1], 0.0]) * spec.square_size / 2
    # Board frame: x along its columns, y along its rows (down the print), origin at its top-left.
    origin = np.asarray(centre, float) + rotation @ (np.array([-margin, -margin, 0.0]) - half)
    plane = camera.plane(origin, rotation[:, 0], rotation[:, 1], pixel, texture)
    return camera.render([plane], BOARD_BACKGROUND)


# The board the lens tests calibrate with, and its views: tilted up to 35°, some cut by the image
# border, reaching towards the image corners where the distortion is strongest.
LENS_BOARD = CharucoBoardSpec(squares=(9, 7), square_size=0.03, marker_size=0.022)
_DEGREE = math.pi / 180
BOARD_VIEWS = (  # (rotation vector [rad], board centre in the camera frame [m])
    ((-15 * _DEGREE, 25 * _DEGREE, 0.0), (-0.13, -0.10, 0.30)),
    ((-15 * _DEGREE, -25 * _DEGREE, 0.1), (0.13, -0.10, 0.30)),
    ((15 * _DEGREE, 25 * _DEGREE, -0.1), (-0.13, 0.10, 0.30)),
    ((15 * _DEGREE, -25 * _DEGREE, 0.0), (0.13, 0.10, 0.30)),
    ((35 * _DEGREE, 0.0, 0.0), (0.0, 0.0, 0.30)),
    ((0.0, 35 * _DEGREE, 0.2), (0.0, 0.0, 0.30)),
    ((-20 * _DEGREE, -30 * _DEGREE, -0.2), (0.0, 0.0, 0.30)),
    ((0.0, 0.0, 0.3), (0.0, 0.0, 0.34)),
)


@functools.lru_cache(maxsize=1)
def lens_board_views() -> tuple[NDArray[np.uint8], ...]:
    """The BOARD_VIEWS of LENS_BOARD through the default LensCamera (rendered once per run)."""
    camera = LensCamera()
    return tuple(render_board_view(camera, LENS_BOARD, tilt, at) for tilt, at in BOARD_VIEWS)


def true_intrinsics() -> CameraIntrinsics:
    """The lens the scenes are rendered with, as a skidnav lens model."""
    return CameraIntrinsics(LENS_MATRIX, LENS_DISTORTION, LENS_IMAGE_SIZE, 0.0, 1)
