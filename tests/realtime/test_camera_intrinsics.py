"""Lens model: ChArUco calibration, undistortion and the marker height, on ray-cast lens images.

The scenes of camera_scenes.LensCamera have a known K and distortion (k1 = -0.25); the intrinsics
used for tracking are the ones *calibrated* from the board views, never the true ones, unless a
test says otherwise.
"""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest

from skidnav.errors import CorruptFileError, UserError
from skidnav.realtime.camera.calibration import check_intrinsics
from skidnav.realtime.camera.intrinsics import board_view
from skidnav.realtime.camera.lens import camera_pose, correct_for_height, undistort_pixels
from skidnav.realtime.camera.tracking import (
    ArenaLayout,
    CameraIntrinsics,
    CameraPoseSource,
    CharucoBoardSpec,
    FloorCalibration,
    Frame,
    MarkerDetector,
    calibrate,
    calibrate_intrinsics,
    load_calibration,
    load_intrinsics,
)
from tests.realtime.camera_scenes import (
    LENS_BOARD,
    LENS_DISTORTION,
    LENS_IMAGE_SIZE,
    LENS_MATRIX,
    ROBOT_MARKER_SIZE,
    LensCamera,
    distort_normalised,
    heading_error,
    lens_board_views,
    marker_floor_corners,
    render_lens_scene,
    true_intrinsics,
    undistort_normalised,
)

LAYOUT = ArenaLayout()
MARKER_HEIGHT = 0.08  # m, the robot marker's height in the height tests


def named(images) -> list[tuple[str, np.ndarray]]:
    return [(f"view_{index}.png", image) for index, image in enumerate(images)]


@pytest.fixture(scope="module")
def intrinsics() -> CameraIntrinsics:
    return calibrate_intrinsics(named(lens_board_views()), LENS_BOARD)


@pytest.fixture(scope="module")
def arena_camera() -> LensCamera:
    return LensCamera.over_arena()


@pytest.fixture(scope="module")
def floor_image(arena_camera) -> np.ndarray:
    return render_lens_scene(arena_camera, LAYOUT, None)


def ideal_in_true_pixels(model: CameraIntrinsics, pixels: np.ndarray) -> np.ndarray:
    """Undistort with ``model``, expressed in the true camera's ideal pixels (K differences out)."""
    ideal = undistort_pixels(model, pixels)
    normalised = (ideal - model.camera_matrix[:2, 2]) / np.diag(model.camera_matrix)[:2]
    return normalised * np.diag(LENS_MATRIX)[:2] + LENS_MATRIX[:2, 2]


def true_ideal(pixels: np.ndarray) -> np.ndarray:
    """Ideal pixels of distorted ``pixels`` under the true lens (the renderer's own inverse)."""
    normalised = (pixels - LENS_MATRIX[:2, 2]) / np.diag(LENS_MATRIX)[:2]
    return (
        undistort_normalised(normalised, LENS_DISTORTION) * np.diag(LENS_MATRIX)[:2]
        + (LENS_MATRIX[:2, 2])
    )


# --- calibration ------------------------------------------------------------------------------
def test_calibration_recovers_the_camera_matrix_and_the_distortion(intrinsics) -> None:
    assert intrinsics.views_used == len(lens_board_views())
    assert intrinsics.image_size == LENS_IMAGE_SIZE
    assert intrinsics.rms_error < 0.5  # px; measured 0.19
    fx, fy = intrinsics.camera_matrix[0, 0], intrinsics.camera_matrix[1, 1]
    cx, cy = intrinsics.camera_matrix[:2, 2]
    assert fx == pytest.approx(LENS_MATRIX[0, 0], abs=2.0)  # px; measured within 0.2
    assert fy == pytest.approx(LENS_MATRIX[1, 1], abs=2.0)
    assert cx == pytest.approx(LENS_MATRIX[0, 2], abs=2.0)  # measured within 0.4
    assert cy == pytest.approx(LENS_MATRIX[1, 2], abs=2.0)
    assert intrinsics.distortion[0] == pytest.approx(LENS_DISTORTION[0], abs=0.02)  # -0.2555
    assert np.abs(intrinsics.distortion[2:4] - LENS_DISTORTION[2:4]).max() < 0.002


def test_recovered_lens_undistorts_like_the_true_one_where_the_board_was_seen(intrinsics) -> None:
    """k2 and k3 trade off against each other, so compare what the model does, not them."""
    board = LENS_BOARD.board()
    detector = cv2.aruco.CharucoDetector(board)
    seen = np.vstack([board_view(detector, board, image)[1] for image in lens_board_views()])
    hull = cv2.convexHull(seen.astype(np.float32))
    grid = np.array([[u, v] for u in np.linspace(0, 639, 49) for v in np.linspace(0, 479, 37)])
    inside = grid[[cv2.pointPolygonTest(hull, (float(u), float(v)), False) >= 0 for u, v in grid]]
    assert len(inside) > 0.6 * len(grid)  # the views cover most of the image
    correction = np.abs(true_ideal(inside) - inside).max()
    difference = np.abs(ideal_in_true_pixels(intrinsics, inside) - true_ideal(inside)).max()
    assert correction > 30  # px: the lens matters (measured up to 38 px) ...
    assert difference < 2.5  # ... and the model gets it right to a few percent (measured 1.2 px)


def test_undistort_pixels_inverts_the_distortion_model() -> None:
    """Against the test's own implementation of the model, to 1e-6 px even near the corners."""
    rng = np.random.default_rng(4)
    ideal_normalised = rng.uniform([-0.75, -0.55], [0.75, 0.55], size=(200, 2))
    distorted = distort_normalised(ideal_normalised, LENS_DISTORTION)
    pixels = distorted * np.diag(LENS_MATRIX)[:2] + LENS_MATRIX[:2, 2]
    ideal = undistort_pixels(true_intrinsics(), pixels)
    expected = ideal_normalised * np.diag(LENS_MATRIX)[:2] + LENS_MATRIX[:2, 2]
    assert np.abs(ideal - expected).max() < 1e-6


def test_too_few_views_are_refused() -> None:
    with pytest.raises(UserError, match=r"only 3 of the 3 images show the board.*at least 4"):
        calibrate_intrinsics(named(lens_board_views()[:3]), LENS_BOARD)


def test_a_board_in_no_image_is_refused() -> None:
    blank = [np.full((480, 640, 3), 128, np.uint8)] * 2
    other = CharucoBoardSpec(squares=(9, 7), dictionary="DICT_4X4_50")  # not the printed one
    with pytest.raises(UserError, match=r"board \(9×7 squares, DICT_4X4_50\) not found in any"):
        calibrate_intrinsics(named(lens_board_views()[:2]), other)
    with pytest.raises(UserError, match="not found in any of the 2 images"):
        calibrate_intrinsics(named(blank), LENS_BOARD)


def test_views_with_too_few_corners_are_skipped() -> None:
    views = list(lens_board_views()[:4])
    views[0] = views[0].copy()
    views[0][:, :] = 120  # board painted over
    with pytest.raises(UserError, match="only 3 of the 4 images"):
        calibrate_intrinsics(named(views), LENS_BOARD)


def test_images_of_different_sizes_are_refused() -> None:
    views = named(lens_board_views()[:4])
    views[2] = ("small.png", cv2.resize(views[2][1], (320, 240)))
    with pytest.raises(UserError, match=r"small\.png: image is 320×240 px, the first is 640×480"):
        calibrate_intrinsics(views, LENS_BOARD)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"squares": (2, 5)}, "3 to 100 squares"),
        ({"square_size": -0.03}, "positive square_size"),
        ({"marker_size": 0.04}, "marker_size < square_size"),
        ({"dictionary": "DICT_NONE"}, "ArUco dictionary name"),
        ({"squares": (15, 15), "dictionary": "DICT_4X4_50"}, "at most 50 markers"),
    ],
)
def test_board_validation(kwargs, message) -> None:
    with pytest.raises(ValueError, match=message):
        CharucoBoardSpec(**kwargs)


# --- the intrinsics file ----------------------------------------------------------------------
def test_intrinsics_json_round_trip(tmp_path, intrinsics) -> None:
    path = tmp_path / "intrinsics.json"
    intrinsics.save(path)
    loaded = load_intrinsics(path, image_size=LENS_IMAGE_SIZE)
    assert np.array_equal(loaded.camera_matrix, intrinsics.camera_matrix)
    assert np.array_equal(loaded.distortion, intrinsics.distortion)
    assert loaded.rms_error == intrinsics.rms_error and loaded.board == LENS_BOARD
    data = json.loads(path.read_text())
    assert data["distortion_model"] == "k1 k2 p1 p2 k3" and len(data["distortion"]) == 5
    assert data["image_size"] == [640, 480] and data["board"]["squares"] == [9, 7]


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda data: "{", "invalid JSON"),
        (
            lambda data: json.dumps({**data, "format": "skidnav-camera-calibration"}),
            "not a skidnav",
        ),
        (lambda data: json.dumps({**data, "version": 3}), "intrinsics version 3"),
        (lambda data: json.dumps({k: v for k, v in data.items() if k != "distortion"}), "missing"),
        (lambda data: json.dumps({**data, "camera_matrix": [[1, 0], [0, 1]]}), "3×3"),
        (lambda data: json.dumps({**data, "camera_matrix": [[1, 0, 1], [0, 1]]}), "inhomogeneous"),
        (lambda data: json.dumps(data).replace("0.0, 1.0]]", "0.0, NaN]]", 1), "non-finite"),
        (lambda data: json.dumps({**data, "distortion": [0.1, 0, 0, 0]}), "5 finite distortion"),
        (lambda data: json.dumps({**data, "distortion": [1e999, 0, 0, 0, 0]}), "non-finite"),
        (lambda data: json.dumps(data).replace("-0.25", "-1e400", 1), "out of range"),
        (lambda data: json.dumps({**data, "distortion_model": "k1 k2"}), "distortion_model"),
        (lambda data: json.dumps({**data, "image_size": [640]}), "image_size"),
        (lambda data: json.dumps({**data, "image_size": [640.5, 480]}), "integer image_size"),
        (lambda data: json.dumps({**data, "rms_error_px": -1}), "rms_error"),
        (lambda data: json.dumps({**data, "board": {"squares": [1, 1]}}), "missing field"),
    ],
)
def test_corrupt_intrinsics_files_fail_in_one_line(tmp_path, edit, message) -> None:
    path = tmp_path / "intrinsics.json"
    true_intrinsics().save(path)
    path.write_text(edit(json.loads(path.read_text())))
    with pytest.raises(CorruptFileError, match=message) as caught:
        load_intrinsics(path)
    assert "\n" not in str(caught.value) and str(path) in str(caught.value)


def test_bad_camera_matrices_are_refused() -> None:
    matrix = LENS_MATRIX.copy()
    matrix[0, 0] = -480.0
    with pytest.raises(ValueError, match="positive focal lengths"):
        CameraIntrinsics(matrix, LENS_DISTORTION, LENS_IMAGE_SIZE, 0.1, 5)
    with pytest.raises(ValueError, match="principal point inside"):
        CameraIntrinsics(LENS_MATRIX, LENS_DISTORTION, (320, 240), 0.1, 5)
    matrix = LENS_MATRIX.copy()
    matrix[2, 0] = 0.1
    with pytest.raises(ValueError, match=r"\[0, 0, 1\]"):
        CameraIntrinsics(matrix, LENS_DISTORTION, LENS_IMAGE_SIZE, 0.1, 5)
    matrix[2, 0] = math.nan
    with pytest.raises(ValueError, match="finite 3×3 camera_matrix"):
        CameraIntrinsics(matrix, LENS_DISTORTION, LENS_IMAGE_SIZE, 0.1, 5)
    with pytest.raises(ValueError, match="5 finite distortion"):
        CameraIntrinsics(LENS_MATRIX, [math.inf, 0, 0, 0, 0], LENS_IMAGE_SIZE, 0.1, 5)


def test_intrinsics_of_another_image_size_are_refused(tmp_path) -> None:
    path = tmp_path / "intrinsics.json"
    true_intrinsics().save(path)
    with pytest.raises(UserError, match=r"for 640×480 px images but the camera .* 1280×960 px"):
        load_intrinsics(path, image_size=(1280, 960))
    with pytest.raises(UserError, match="intrinsics file not found"):
        load_intrinsics(tmp_path / "missing.json")
    big = np.zeros((960, 1280, 3), np.uint8)
    with pytest.raises(UserError, match="but frame 0 is 1280×960 px"):
        calibrate([Frame(0, 0.0, big)], LAYOUT, intrinsics=true_intrinsics())


# --- floor calibration and tracking through the lens -----------------------------------------
def robot_poses(n: int, seed: int, inset: float = 0.07) -> list[tuple[float, float, float]]:
    """Random poses at least ``inset`` [m] inside the arena (clear of the corner markers)."""
    rng = np.random.default_rng(seed)
    width, height = LAYOUT.arena_width, LAYOUT.arena_height
    return [
        (
            rng.uniform(inset, width - inset),
            rng.uniform(inset, height - inset),
            rng.uniform(-math.pi, math.pi),
        )
        for _ in range(n)
    ]


def position_errors(calibration, images, poses, marker_height=0.0) -> np.ndarray:
    """Position error [m] of the tracked robot marker in each image."""
    source = CameraPoseSource([], calibration, max_age=1e9, marker_height=marker_height)
    errors = []
    for index, (image, (x, y, _heading)) in enumerate(zip(images, poses, strict=True)):
        pose = source.process(Frame(index, 0.0, image))
        assert pose is not None, f"robot marker not found at {(x, y)}"
        errors.append(math.hypot(pose.x - x, pose.y - y))
    return np.array(errors)


def test_lens_model_cuts_the_position_error_at_least_5_times(floor_image, intrinsics, arena_camera):
    poses = robot_poses(10, seed=5)
    images = [render_lens_scene(arena_camera, LAYOUT, pose) for pose in poses]
    without = position_errors(calibrate([Frame(0, 0.0, floor_image)], LAYOUT), images, poses)
    lens = calibrate([Frame(0, 0.0, floor_image)], LAYOUT, intrinsics=intrinsics)
    with_lens = position_errors(lens, images, poses)
    assert without.max() > 0.01  # m: k1 = -0.25 matters (measured 19.8 mm max, 17.2 mm mean)
    assert with_lens.max() < 0.002  # m (measured 0.54 mm max, 0.34 mm mean)
    assert with_lens.max() * 5 <= without.max()
    assert np.sqrt(np.mean(with_lens**2)) * 5 <= np.sqrt(np.mean(without**2))


def test_heading_through_the_lens(floor_image, intrinsics, arena_camera) -> None:
    lens = calibrate([Frame(0, 0.0, floor_image)], LAYOUT, intrinsics=intrinsics)
    source = CameraPoseSource([], lens)
    for pose in robot_poses(4, seed=8):
        measured = source.process(Frame(0, 0.0, render_lens_scene(arena_camera, LAYOUT, pose)))
        assert measured is not None
        assert heading_error(measured.heading, pose[2]) < math.radians(2)


def test_camera_pose_from_the_lens_and_the_floor_homography(floor_image, intrinsics, arena_camera):
    lens = calibrate([Frame(0, 0.0, floor_image)], LAYOUT, intrinsics=intrinsics)
    assert lens.camera_pose is not None
    assert np.abs(lens.camera_pose.position - arena_camera.position).max() < 0.005  # m
    assert calibrate([Frame(0, 0.0, floor_image)], LAYOUT).camera_pose is None


def test_camera_pose_is_exact_for_an_exact_homography(arena_camera) -> None:
    """inv(H) = K [r1 r2 t] for the floor plane; the decomposition must give back R and C."""
    rotation, translation = arena_camera.rotation, -arena_camera.rotation @ arena_camera.position
    floor_to_pixels = LENS_MATRIX @ np.column_stack([rotation[:, 0], rotation[:, 1], translation])
    homography = np.linalg.inv(floor_to_pixels * -3.7)  # any scale, either sign
    pose = camera_pose(LENS_MATRIX, homography)
    assert np.allclose(pose.position, arena_camera.position, atol=1e-9)
    assert np.allclose(pose.rotation, rotation, atol=1e-9)
    mirrored = np.diag([1.0, -1.0, 1.0]) @ homography  # arena y flipped: camera under the floor
    with pytest.raises(ValueError, match="camera above the floor"):
        camera_pose(LENS_MATRIX, mirrored)


def test_height_correction_is_exact_geometry(arena_camera) -> None:
    """A point h up seen through the camera lands, on the floor plane, where the docs say."""
    rng = np.random.default_rng(9)
    centre = arena_camera.position
    marker = np.column_stack([rng.uniform(0, 0.6, 20), rng.uniform(0, 0.5, 20), np.full(20, 0.08)])
    on_floor = centre + (marker - centre) * (centre[2] / (centre[2] - marker[:, 2:3]))
    assert np.allclose(on_floor[:, 2], 0.0)
    assert np.allclose(correct_for_height(on_floor[:, :2], centre, 0.08), marker[:, :2])


def test_marker_height_is_corrected(floor_image, intrinsics, arena_camera) -> None:
    poses = robot_poses(6, seed=6, inset=0.12)  # the parallax must not push it onto a corner
    images = [
        render_lens_scene(arena_camera, LAYOUT, pose, robot_height=MARKER_HEIGHT) for pose in poses
    ]
    lens = calibrate([Frame(0, 0.0, floor_image)], LAYOUT, intrinsics=intrinsics)
    corrected = position_errors(lens, images, poses, marker_height=MARKER_HEIGHT)
    uncorrected = position_errors(lens, images, poses)
    # The error left uncorrected is the parallax h / (H - h) of the distance from the nadir.
    nadir, height = arena_camera.position[:2], arena_camera.position[2]
    parallax = [
        math.dist((x, y), nadir) * MARKER_HEIGHT / (height - MARKER_HEIGHT) for x, y, _ in poses
    ]
    assert list(uncorrected) == pytest.approx(parallax, abs=0.002)  # measured up to 58 mm
    assert corrected.max() < 0.002  # m (measured 0.78 mm max, 0.56 mm mean)


def test_marker_height_needs_a_lens_and_a_camera_above_it(floor_image, intrinsics) -> None:
    plain = calibrate([Frame(0, 0.0, floor_image)], LAYOUT)
    with pytest.raises(ValueError, match="needs a floor calibration made with intrinsics"):
        CameraPoseSource([], plain, marker_height=0.05)
    lens = calibrate([Frame(0, 0.0, floor_image)], LAYOUT, intrinsics=intrinsics)
    with pytest.raises(ValueError, match="below the camera"):
        CameraPoseSource([], lens, marker_height=0.6)
    with pytest.raises(ValueError, match="finite marker height"):
        CameraPoseSource([], lens, marker_height=math.nan)


def test_robot_marker_corners_through_the_renderer_match_the_projection(arena_camera) -> None:
    """The renderer and LensCamera.project agree (so the scenes have the stated lens)."""
    pose = (0.3, 0.3, 0.4)
    image = render_lens_scene(arena_camera, LAYOUT, pose)
    floor = np.column_stack([marker_floor_corners(*pose, ROBOT_MARKER_SIZE), np.zeros(4)])
    expected = arena_camera.project(floor)
    detected = MarkerDetector().detect(image)[LAYOUT.robot_id]
    assert np.abs(detected - expected).max() < 1.0  # px


# --- calibration files with a lens model ------------------------------------------------------
def test_calibration_with_intrinsics_round_trip(tmp_path, floor_image, intrinsics) -> None:
    lens = calibrate([Frame(0, 0.0, floor_image)], LAYOUT, intrinsics=intrinsics)
    path = tmp_path / "calibration.json"
    lens.save(path)
    loaded = load_calibration(path, expected=LAYOUT)
    assert loaded.intrinsics is not None and loaded.intrinsics.same_model(intrinsics)
    assert np.array_equal(loaded.homography, lens.homography)
    check_intrinsics(loaded, intrinsics, str(path))  # the same model: accepted
    other = CameraIntrinsics(
        intrinsics.camera_matrix, intrinsics.distortion * 0.5, LENS_IMAGE_SIZE, 0.2, 4
    )
    with pytest.raises(UserError, match="made with other intrinsics"):
        check_intrinsics(loaded, other, str(path))
    plain = calibrate([Frame(0, 0.0, floor_image)], LAYOUT)
    with pytest.raises(UserError, match="made without intrinsics"):
        check_intrinsics(plain, intrinsics, str(path))


def test_version_1_calibration_files_still_load(tmp_path, floor_image) -> None:
    plain = calibrate([Frame(0, 0.0, floor_image)], LAYOUT)
    data = plain.to_json()
    del data["intrinsics"]
    path = tmp_path / "old.json"
    path.write_text(json.dumps({**data, "version": 1}))
    assert load_calibration(path).intrinsics is None
    path.write_text(json.dumps(data))  # version 2 must say "intrinsics", even if null
    with pytest.raises(CorruptFileError, match="missing field 'intrinsics'"):
        load_calibration(path)


def test_embedded_intrinsics_are_validated(tmp_path, floor_image, intrinsics) -> None:
    data = calibrate([Frame(0, 0.0, floor_image)], LAYOUT, intrinsics=intrinsics).to_json()
    path = tmp_path / "calibration.json"
    data["intrinsics"]["distortion"] = [0.0, 0.0]
    path.write_text(json.dumps(data))
    with pytest.raises(CorruptFileError, match="intrinsics: expected 5 finite distortion"):
        load_calibration(path)
    data["intrinsics"]["distortion"] = list(LENS_DISTORTION)
    data["image_size"] = [1280, 960]
    path.write_text(json.dumps(data))
    with pytest.raises(CorruptFileError, match="expected intrinsics for the"):
        load_calibration(path)
    with pytest.raises(ValueError, match="expected intrinsics for the"):
        FloorCalibration(np.eye(3), LAYOUT, (1280, 960), intrinsics=intrinsics)
