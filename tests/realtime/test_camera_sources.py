"""Frame sources (image folder, video file) and calibration files, on synthetic images."""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest

from skidnav.errors import CorruptFileError, UserError
from skidnav.realtime.camera.tracking import (
    ArenaLayout,
    CameraPoseSource,
    FloorCalibration,
    Frame,
    calibrate,
    load_calibration,
    open_frames,
)
from tests.realtime.camera_scenes import IMAGE_SIZE, heading_error, render_scene

LAYOUT = ArenaLayout()
POSES = [(0.12, 0.15, 0.0), (0.2, 0.2, 0.8), (0.3, 0.26, 1.6), (0.4, 0.3, 2.4)]


@pytest.fixture(scope="module")
def scenes() -> list[np.ndarray]:
    """The arena without the robot, then the robot at each of POSES."""
    return [render_scene(LAYOUT, None)] + [render_scene(LAYOUT, pose) for pose in POSES]


@pytest.fixture(scope="module")
def calibration(scenes) -> FloorCalibration:
    return calibrate([Frame(0, 0.0, scenes[0])], LAYOUT)


def test_image_folder_yields_sorted_frames_with_nominal_stamps(tmp_path, scenes, calibration):
    # Written out of order, and with a file that is not an image.
    for index in reversed(range(1, len(scenes))):
        cv2.imwrite(str(tmp_path / f"frame_{index:03d}.png"), scenes[index])
    (tmp_path / "notes.txt").write_text("not an image")
    with open_frames(tmp_path, fps=10.0) as source:
        frames = list(source)
        assert [f.number for f in list(source)] == [0, 1, 2, 3]  # a folder can be re-read
    assert [f.stamp for f in frames] == pytest.approx([0.0, 0.1, 0.2, 0.3])
    assert frames[0].image.shape == (IMAGE_SIZE[1], IMAGE_SIZE[0], 3)
    tracker = CameraPoseSource([], calibration, max_age=1e9)
    for frame, (x, y, heading) in zip(frames, POSES, strict=True):
        pose = tracker.process(frame)
        assert pose is not None
        assert math.hypot(pose.x - x, pose.y - y) < 0.005
        assert heading_error(pose.heading, heading) < math.radians(2)


def test_video_file_in_a_background_tracker(tmp_path, scenes, calibration):
    path = tmp_path / "run.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 20.0, IMAGE_SIZE)
    assert writer.isOpened(), "MJPG/AVI writer unavailable"
    for image in scenes[1:]:
        writer.write(image)
    writer.release()
    source = open_frames(str(path))
    assert source.fps == pytest.approx(20.0)
    tracker = CameraPoseSource(source, calibration, max_age=60.0)
    tracker.start()
    assert tracker.join(timeout=20)
    tracker.close()
    assert tracker.error is None
    assert (tracker.frames_processed, tracker.frames_with_robot) == (4, 4)
    pose = tracker.latest_pose()
    assert pose is not None
    x, y, heading = POSES[-1]
    # JPEG compression: the "usable" thresholds of the noisy-image test.
    assert math.hypot(pose.x - x, pose.y - y) < 0.015
    assert heading_error(pose.heading, heading) < math.radians(5)


def test_video_frames_have_stamps_from_the_frame_rate(tmp_path, scenes):
    path = tmp_path / "short.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, IMAGE_SIZE)
    for _ in range(3):
        writer.write(scenes[0])
    writer.release()
    with open_frames(path) as source:
        stamps = [frame.stamp for frame in source]
    assert stamps == pytest.approx([0.0, 0.04, 0.08])


@pytest.mark.parametrize(
    ("make", "message"),
    [("missing", "no such camera"), ("empty_dir", "no images"), ("not_video", "cannot open")],
)
def test_unusable_sources_are_user_errors(tmp_path, make, message):
    target = tmp_path / "x"
    if make == "empty_dir":
        target.mkdir()
    elif make == "not_video":
        target = tmp_path / "junk.avi"
        target.write_bytes(b"\x00garbage" * 10)
    with pytest.raises(UserError, match=message) as caught:
        open_frames(target)
    assert "\n" not in str(caught.value)


def test_calibration_json_round_trip(tmp_path, calibration):
    path = tmp_path / "calibration.json"
    calibration.save(path)
    loaded = load_calibration(path, expected=LAYOUT)
    assert np.array_equal(loaded.homography, calibration.homography)
    assert loaded.layout == ArenaLayout(corner_positions=LAYOUT.corners())
    assert loaded.image_size == calibration.image_size
    data = json.loads(path.read_text())
    assert data["corner_ids"] == [0, 1, 2, 3] and data["robot_id"] == 4


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda text, data: "{ not json", "invalid JSON"),
        (lambda text, data: text[: len(text) // 2], "invalid JSON"),
        (lambda text, data: json.dumps({**data, "format": "other"}), "not a skidnav camera"),
        (lambda text, data: json.dumps({**data, "version": 9}), "version 9"),
        (
            lambda text, data: json.dumps({k: v for k, v in data.items() if k != "homography"}),
            "missing field 'homography'",
        ),
        (lambda text, data: json.dumps({**data, "homography": [[1, 0], [0, 1]]}), "3×3"),
        (lambda text, data: json.dumps({**data, "homography": [[0] * 3] * 3}), "singular"),
        (
            lambda text, data: json.dumps({**data, "homography": [[1e308] * 3] * 3}),
            "'homography' holds a value that is NaN or not below 1e\\+12",
        ),
        (
            lambda text, data: json.dumps(
                {**data, "homography": [[1, 0, 0], [0, 1e-14, 0], [0, 0, 1]]}
            ),
            "singular",
        ),
        (lambda text, data: json.dumps({**data, "corner_ids": [0, 0, 1, 2]}), "distinct"),
    ],
)
def test_corrupt_calibration_files_fail_in_one_line(tmp_path, calibration, edit, message):
    path = tmp_path / "calibration.json"
    calibration.save(path)
    text = path.read_text()
    path.write_text(edit(text, json.loads(text)))
    with pytest.raises(CorruptFileError, match=message) as caught:
        load_calibration(path)
    assert "\n" not in str(caught.value) and str(path) in str(caught.value)


def test_missing_or_mismatched_calibration_is_a_user_error(tmp_path, calibration):
    with pytest.raises(UserError, match="calibration file not found"):
        load_calibration(tmp_path / "nope.json")
    path = tmp_path / "calibration.json"
    calibration.save(path)
    with pytest.raises(UserError, match=r"arena size is \(0.62, 0.505\), expected \(1.0, 0.505\)"):
        load_calibration(path, expected=ArenaLayout(arena_width=1.0))
    with pytest.raises(UserError, match="robot_id is 4, expected 9"):
        load_calibration(path, expected=ArenaLayout(robot_id=9))
