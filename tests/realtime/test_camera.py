"""Overhead-camera tracking on synthetic images rendered at known poses (camera_scenes.py)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from skidnav.errors import UserError
from skidnav.realtime.camera.markers import apply_homography, quad_centre
from skidnav.realtime.camera.tracking import (
    ArenaLayout,
    CameraPosedDriver,
    CameraPoseSource,
    FloorCalibration,
    Frame,
    MarkerDetector,
    calibrate,
)
from tests.realtime.camera_scenes import (
    IMAGE_SIZE,
    camera_homography,
    degrade,
    heading_error,
    render_scene,
)

LAYOUT = ArenaLayout()
TOP_DOWN_SCALE = 1600.0  # px per m of the orthographic test view
TOP_DOWN_VIEW = tuple(
    (100.0 + x * TOP_DOWN_SCALE, 100.0 + (LAYOUT.arena_height - y) * TOP_DOWN_SCALE)
    for x, y in LAYOUT.corners()
)


@pytest.fixture(scope="module")
def calibration() -> FloorCalibration:
    return calibrate([Frame(0, 0.0, render_scene(LAYOUT, None))], LAYOUT)


def random_poses(rng: np.random.Generator, n: int) -> list[tuple[float, float, float]]:
    """Poses well inside the arena (the robot marker must not cover a corner marker)."""
    return [
        (rng.uniform(0.07, 0.55), rng.uniform(0.07, 0.435), rng.uniform(-math.pi, math.pi))
        for _ in range(n)
    ]


def errors(source: CameraPoseSource, images, poses) -> tuple[float, float]:
    """Largest position error [m] and heading error [rad] over the images."""
    worst_position, worst_heading = 0.0, 0.0
    for index, (image, (x, y, heading)) in enumerate(zip(images, poses, strict=True)):
        pose = source.process(Frame(index, index / 30, image))
        assert pose is not None, f"robot marker not found at {(x, y, heading)}"
        worst_position = max(worst_position, math.hypot(pose.x - x, pose.y - y))
        worst_heading = max(worst_heading, heading_error(pose.heading, heading))
    return worst_position, worst_heading


def test_calibration_recovers_the_true_floor_homography(calibration) -> None:
    true_px_to_floor = np.linalg.inv(camera_homography(LAYOUT))
    floor = np.array([[x, y] for x in np.linspace(0, 0.62, 7) for y in np.linspace(0, 0.505, 6)])
    pixels = apply_homography(np.linalg.inv(true_px_to_floor), floor)
    recovered = apply_homography(calibration.homography, pixels)
    assert np.abs(recovered - floor).max() < 1e-3
    assert calibration.image_size == IMAGE_SIZE


def test_clean_images_within_5_mm_and_2_degrees(calibration) -> None:
    poses = random_poses(np.random.default_rng(1), 8)
    images = [render_scene(LAYOUT, pose) for pose in poses]
    position, heading = errors(CameraPoseSource([], calibration, max_age=1e9), images, poses)
    assert position <= 0.005
    assert heading <= math.radians(2)


def test_blurred_noisy_images_within_15_mm_and_5_degrees(calibration) -> None:
    rng = np.random.default_rng(2)
    poses = random_poses(rng, 6)
    images = [degrade(render_scene(LAYOUT, p), rng, blur_sigma=1.5, noise_sigma=12) for p in poses]
    source = CameraPoseSource([], calibration, max_age=1e9)
    position, heading = errors(source, images, poses)
    assert position <= 0.015
    assert heading <= math.radians(5)


def test_calibration_from_noisy_frames_uses_the_median() -> None:
    rng = np.random.default_rng(3)
    clean = render_scene(LAYOUT, None)
    frames = [Frame(i, i / 30, degrade(clean, rng, 1.0, 10)) for i in range(3)]
    fitted = calibrate(frames, LAYOUT, max_frames=3)
    assert fitted.frames_used == 3
    truth = np.linalg.inv(camera_homography(LAYOUT))
    pixels = np.array([[640.0, 480.0], [300.0, 700.0], [1000.0, 200.0]])
    error = apply_homography(fitted.homography, pixels) - apply_homography(truth, pixels)
    assert np.abs(error).max() < 2e-3


@pytest.mark.parametrize(
    ("rotation", "expected_heading"),
    [
        (None, math.pi / 2),
        (cv2.ROTATE_90_CLOCKWISE, 0.0),
        (cv2.ROTATE_180, -math.pi / 2),
        (cv2.ROTATE_90_COUNTERCLOCKWISE, math.pi),
    ],
)
def test_heading_convention_with_a_marker_pasted_into_a_top_down_view(rotation, expected_heading):
    """Independent of the renderer's geometry: image up is +y, image right is +x."""
    image = render_scene(LAYOUT, None, view=TOP_DOWN_VIEW)
    fitted = calibrate([Frame(0, 0.0, image)], LAYOUT)
    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    pattern = cv2.aruco.generateImageMarker(dictionary, LAYOUT.robot_id, 64)
    if rotation is not None:
        pattern = cv2.rotate(pattern, rotation)
    top, left = 420, 500
    image[top : top + 64, left : left + 64] = pattern[:, :, None]
    pose = CameraPoseSource([], fitted).process(Frame(0, 0.0, image))
    assert pose is not None
    centre_u, centre_v = left + 31.5, top + 31.5
    assert pose.x == pytest.approx((centre_u - 100) / TOP_DOWN_SCALE, abs=1e-3)
    assert pose.y == pytest.approx(
        LAYOUT.arena_height - (centre_v - 100) / TOP_DOWN_SCALE, abs=1e-3
    )
    assert heading_error(pose.heading, expected_heading) < math.radians(1)


def test_missing_robot_marker_gives_none(calibration) -> None:
    source = CameraPoseSource([], calibration, max_age=1e9)
    assert source.process(Frame(0, 0.0, render_scene(LAYOUT, (0.3, 0.25, 0.0)))) is not None
    assert source.latest_pose() is not None
    assert source.process(Frame(1, 0.1, render_scene(LAYOUT, None))) is None
    assert source.latest_pose() is None
    other = ArenaLayout(robot_id=7)
    image = render_scene(other, (0.3, 0.25, 0.0))  # a different robot id in view
    assert source.process(Frame(2, 0.2, image)) is None


def test_stale_pose_gives_none(calibration) -> None:
    now = [100.0]
    source = CameraPoseSource([], calibration, max_age=0.25, clock=lambda: now[0])
    pose = source.process(Frame(0, 0.0, render_scene(LAYOUT, (0.2, 0.2, 1.0))))
    assert pose is not None and pose.stamp == 100.0
    now[0] = 100.2
    assert source.latest_pose() == pose
    now[0] = 100.3
    assert source.latest_pose() is None


def test_frame_size_mismatch_is_a_user_error(calibration) -> None:
    source = CameraPoseSource([], calibration)
    small = np.zeros((480, 640, 3), np.uint8)
    with pytest.raises(UserError, match="640×480 px but the calibration was made for 1280×960"):
        source.process(Frame(0, 0.0, small))


def test_background_thread_records_error_and_reports_no_pose(calibration) -> None:
    frames = [Frame(0, 0.0, np.zeros((480, 640, 3), np.uint8))]
    with CameraPoseSource(frames, calibration) as source:
        source.start()
        assert source.join(timeout=10)
    assert isinstance(source.error, UserError)
    assert source.latest_pose() is None


def test_background_thread_follows_the_newest_frame(calibration) -> None:
    poses = [(0.15, 0.2, 0.3), (0.25, 0.22, 0.5), (0.35, 0.24, 0.7)]
    frames = [Frame(i, i / 30, render_scene(LAYOUT, p)) for i, p in enumerate(poses)]
    source = CameraPoseSource(iter(frames), calibration, max_age=60.0)
    source.start()
    with pytest.raises(RuntimeError):
        source.start()
    assert source.join(timeout=20)
    source.close()
    assert source.error is None
    assert (source.frames_processed, source.frames_with_robot) == (3, 3)
    pose = source.latest_pose()
    assert pose is not None
    assert math.hypot(pose.x - 0.35, pose.y - 0.24) < 0.005


def test_calibration_without_all_corner_markers_names_the_missing_one() -> None:
    image = render_scene(LAYOUT, None)
    corners = MarkerDetector().detect(image)[2]
    u, v = quad_centre(corners).astype(int)
    image[v - 60 : v + 60, u - 60 : u + 60] = 205  # paint marker 2 over
    with pytest.raises(UserError, match=r"corner markers \[2\] not found"):
        calibrate([Frame(0, 0.0, image)], LAYOUT)


def test_custom_layout_with_other_ids_and_positions() -> None:
    layout = ArenaLayout(
        arena_width=1.0,
        arena_height=0.8,
        corner_ids=(10, 11, 12, 13),
        corner_positions=((0.05, 0.05), (0.95, 0.05), (0.95, 0.75), (0.05, 0.75)),
        robot_id=20,
    )
    view = ((200.0, 850.0), (1100.0, 870.0), (1000.0, 120.0), (260.0, 100.0))
    # The renderer places the corner markers at layout.corners(); the view maps the arena box.
    image = render_scene(layout, (0.5, 0.4, -2.0), view=view)
    fitted = calibrate([Frame(0, 0.0, image)], layout)
    pose = CameraPoseSource([], fitted).process(Frame(0, 0.0, image))
    assert pose is not None
    assert math.hypot(pose.x - 0.5, pose.y - 0.4) < 0.005
    assert heading_error(pose.heading, -2.0) < math.radians(2)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"arena_width": 0.0}, "positive arena size"),
        ({"corner_ids": (0, 1, 1, 3)}, "4 distinct corner_ids"),
        ({"robot_id": 50}, r"ids in \[0, 50\)"),
        ({"dictionary": "DICT_NOPE"}, "ArUco dictionary name"),
        ({"corner_positions": ((0, 0), (1, 1), (2, 2), (3, 3))}, "collinear"),
    ],
)
def test_layout_validation(kwargs, message) -> None:
    with pytest.raises(ValueError, match=message):
        ArenaLayout(**kwargs)


class RecordingDriver:
    """A robot link that records calls (the camera supplies the poses)."""

    def __init__(self) -> None:
        self.calls: list[tuple[str, tuple[float, ...]]] = []

    def connect(self) -> None:
        self.calls.append(("connect", ()))

    def command(self, omega_left: float, omega_right: float) -> None:
        self.calls.append(("command", (omega_left, omega_right)))

    def latest_pose(self):
        raise AssertionError("the camera, not the link, supplies poses")

    def stop(self) -> bool:
        self.calls.append(("stop", ()))
        return True

    def close(self) -> None:
        self.calls.append(("close", ()))


def test_camera_posed_driver_routes_commands_to_the_link_and_poses_from_the_camera(calibration):
    frames = [Frame(0, 0.0, render_scene(LAYOUT, (0.3, 0.2, -1.0)))]
    link = RecordingDriver()
    driver = CameraPosedDriver(link, CameraPoseSource(frames, calibration, max_age=60.0))
    driver.connect()
    assert driver.camera.join(timeout=10)
    pose = driver.latest_pose()
    assert pose is not None and math.hypot(pose.x - 0.3, pose.y - 0.2) < 0.005
    driver.command(1.7, -1.7)
    assert driver.stop() is True
    driver.close()
    assert link.calls == [("connect", ()), ("command", (1.7, -1.7)), ("stop", ()), ("close", ())]
