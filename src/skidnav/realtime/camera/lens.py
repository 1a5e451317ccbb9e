"""The lens model at work: undistorted marker corners, the camera's place, a marker's height.

With a :class:`~skidnav.realtime.camera.intrinsics.CameraIntrinsics` the floor homography is fitted
and applied to *undistorted* pixels (those of an ideal pinhole camera with the same K), where
straight lines stay straight and the homography is exact for the corner-marker plane. K and that
homography then give the camera's position over the floor, and with it the correction for a
marker that rides at a height above that plane (docs/camera.md, "Marker height").
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from skidnav.realtime.camera.intrinsics import CameraIntrinsics
from skidnav.realtime.camera.markers import FloatArray
from skidnav.realtime.camera.opencv import cv2

# OpenCV's default stops after 5 fixed-point iterations, which leaves 0.87 px at the corners of
# the k1 = -0.25 test lens (docs/camera.md); these criteria converge to 2e-12 px on it.
UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-12)


def undistort_pixels(intrinsics: CameraIntrinsics, pixels: FloatArray) -> FloatArray:
    """Ideal pinhole pixels (n, 2) of the distorted pixels ``pixels`` (n, 2) (same K: P = K)."""
    points = np.asarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
    matrix, coefficients = intrinsics.camera_matrix, intrinsics.distortion
    iterative = getattr(cv2, "undistortPointsIter", None)  # OpenCV 4's name for the same call
    if iterative is not None:
        ideal = iterative(points, matrix, coefficients, None, matrix, UNDISTORT_CRITERIA)
    else:
        ideal = cv2.undistortPoints(
            points, matrix, coefficients, P=matrix, criteria=UNDISTORT_CRITERIA
        )
    return np.asarray(ideal, dtype=np.float64).reshape(-1, 2)


class CameraPose(NamedTuple):
    """Where the camera is over the arena.

    Attributes:
        rotation: 3×3, arena-frame vectors → camera-frame vectors (camera x right, y down in the
            image, z along the optical axis).
        position: camera centre (x, y, z) [m] in the arena frame; z is the height above the
            corner-marker plane (arena z = x × y points up, towards the camera).
    """

    rotation: FloatArray
    position: FloatArray


def camera_pose(camera_matrix: FloatArray, homography: FloatArray) -> CameraPose:
    """The camera pose from K and the (undistorted) pixel → floor ``homography``, both 3×3.

    The floor → pixel map inv(homography) is λ K [r1 r2 t] for the floor plane z = 0 (Zhang (2000)
    §3.1): r1 = K⁻¹h1 / λ, r2 = K⁻¹h2 / λ, r3 = r1 × r2, t = K⁻¹h3 / λ with |λ| the mean length
    of K⁻¹h1 and K⁻¹h2, its sign putting the floor in front of the camera (t_z > 0); the noisy
    [r1 r2 r3] is replaced by the nearest rotation (Zhang (2000) appendix C). Centre = −Rᵀ t.

    Raises:
        ValueError: a pose with the camera below the floor (a mirrored layout or a wrong K).
    """
    columns = np.linalg.solve(camera_matrix, np.linalg.inv(homography))
    scale = 0.5 * (np.linalg.norm(columns[:, 0]) + np.linalg.norm(columns[:, 1]))
    scale *= np.sign(columns[2, 2])
    r1, r2, translation = columns[:, 0] / scale, columns[:, 1] / scale, columns[:, 2] / scale
    left, _singular, right = np.linalg.svd(np.column_stack([r1, r2, np.cross(r1, r2)]))
    rotation = left @ right
    position = -rotation.T @ translation
    if not position[2] > 0:
        raise ValueError(
            f"expected the camera above the floor, got height {position[2]:.3f} m; "
            "check the corner-marker order and the intrinsics"
        )
    return CameraPose(np.asarray(rotation, np.float64), np.asarray(position, np.float64))


def correct_for_height(floor: FloatArray, camera_position: FloatArray, height: float) -> FloatArray:
    """Arena positions (n, 2) [m] of points ``height`` [m] up that the homography put at ``floor``.

    The homography maps a pixel to where its ray meets the corner-marker plane. The ray from the
    camera centre C through a point M at height h meets that plane at
    P = N + (M − N)·C_z/(C_z − h) in the plane's coordinates, N = (C_x, C_y) being the camera's
    nadir, so M = N + (P − N)(1 − h/C_z): a scaling about the nadir, which keeps headings.

    >>> correct_for_height(np.array([[1.0, 0.0]]), np.array([0.0, 0.0, 1.0]), 0.2)
    array([[0.8, 0. ]])
    """
    nadir, camera_height = camera_position[:2], float(camera_position[2])
    if not height < camera_height:
        raise ValueError(
            f"expected a height below the camera ({camera_height:.3f} m), got {height}"
        )
    points = np.asarray(floor, dtype=np.float64).reshape(-1, 2)
    return np.asarray(nadir + (points - nadir) * (1.0 - height / camera_height), np.float64)
