"""Synthetic overhead-camera images for the camera tests (imported explicitly, not a conftest).

A scene is rendered by drawing each ArUco marker (``cv2.aruco.generateImageMarker``) straight into
the camera image through a known floor → pixel perspective homography, at twice the resolution,
then area-averaged down (a cheap stand-in for a lens's blur and pixel integration).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import cv2
import numpy as np
from numpy.typing import NDArray

from skidnav.realtime.camera import ArenaLayout

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
