"""``skidnav camera`` subcommands end to end on a folder of synthetic images."""

from __future__ import annotations

import argparse
import json
import math

import cv2
import numpy as np
import pytest

from skidnav import cli
from skidnav.commands import camera as camera_command
from skidnav.errors import UserError
from skidnav.realtime.camera.tracking import ArenaLayout, CharucoBoardSpec, MarkerDetector
from tests.realtime.camera_scenes import (
    LensCamera,
    heading_error,
    lens_board_views,
    render_lens_scene,
    render_scene,
)

LAYOUT = ArenaLayout()
POSES = [(0.1, 0.1, 0.5), None, (0.5, 0.4, -2.5)]


def run(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="skidnav")
    camera_command.add_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return int(args.func(args))


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    path = tmp_path_factory.mktemp("frames")
    for index, pose in enumerate(POSES):
        cv2.imwrite(str(path / f"{index:02d}.png"), render_scene(LAYOUT, pose))
    return path


def test_calibrate_then_track_prints_one_pose_per_frame(tmp_path, folder, capsys):
    out = tmp_path / "calibration.json"
    assert run(["camera", "calibrate", "--source", str(folder), "--out", str(out)]) == 0
    assert json.loads(out.read_text())["frames_used"] == 3
    capsys.readouterr()
    command = ["camera", "track", "--source", str(folder), "--calibration", str(out)]
    assert run([*command, "--fps", "10"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("#") and len(lines) == 4
    assert lines[2] == "0.100 lost"
    for line, truth in zip(lines[1:], POSES, strict=True):
        if truth is None:
            continue
        _stamp, x, y, heading = (float(v) for v in line.split())
        assert math.hypot(x - truth[0], y - truth[1]) < 0.005
        assert heading_error(heading, truth[2]) < math.radians(2)


def test_track_stops_after_max_frames(tmp_path, folder, capsys):
    out = tmp_path / "calibration.json"
    run(["camera", "calibrate", "--source", str(folder), "--out", str(out), "--frames", "1"])
    capsys.readouterr()
    run(
        ["camera", "track", "--source", str(folder), "--calibration", str(out), "--max-frames", "1"]
    )
    assert len(capsys.readouterr().out.splitlines()) == 2


def test_user_errors(tmp_path, folder):
    with pytest.raises(UserError, match="calibration file not found"):
        run(["camera", "track", "--source", str(folder), "--calibration", str(tmp_path / "x")])
    with pytest.raises(UserError, match="distinct"):
        run(
            [
                "camera",
                "calibrate",
                "--source",
                str(folder),
                "--out",
                str(tmp_path / "c.json"),
                "--corner-ids",
                "0",
                "0",
                "1",
                "2",
            ]
        )
    with pytest.raises(UserError, match=r"corner markers \[7\] not found"):
        run(
            [
                "camera",
                "calibrate",
                "--source",
                str(folder),
                "--out",
                str(tmp_path / "c.json"),
                "--corner-ids",
                "0",
                "1",
                "2",
                "7",
            ]
        )


def test_markers_are_detectable_when_printed(tmp_path):
    assert run(["camera", "markers", "--out", str(tmp_path), "--ids", "3", "4"]) == 0
    for marker_id in (3, 4):
        image = cv2.imread(str(tmp_path / f"marker_{marker_id}.png"))
        assert list(MarkerDetector().detect(image)) == [marker_id]


# --- the lens model ---------------------------------------------------------------------------
LENS_POSES = [(0.2, 0.2, 0.3), (0.45, 0.3, -1.9)]
MARKER_HEIGHT = 0.08  # m
BOARD_ARGUMENTS = ["--squares", "9", "7", "--square-size", "0.03", "--marker-size", "0.022"]


def fails_in_one_line(argv: list[str], capsys) -> str:
    """Run the real entry point; assert exit code 2 and one ``skidnav: error:`` line."""
    capsys.readouterr()
    assert cli.main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("skidnav: error: "), captured.err
    return lines[0]


@pytest.fixture(scope="module")
def lens_folders(tmp_path_factory):
    """Board views, and arena frames (floor only, then the robot marker 8 cm up), both lens."""
    boards = tmp_path_factory.mktemp("boards")
    for index, image in enumerate(lens_board_views()):
        cv2.imwrite(str(boards / f"board_{index}.png"), image)
    arena = tmp_path_factory.mktemp("arena")
    camera = LensCamera.over_arena()
    cv2.imwrite(str(arena / "00.png"), render_lens_scene(camera, LAYOUT, None))
    for index, pose in enumerate(LENS_POSES, start=1):
        image = render_lens_scene(camera, LAYOUT, pose, robot_height=MARKER_HEIGHT)
        cv2.imwrite(str(arena / f"{index:02d}.png"), image)
    return boards, arena


def test_board_is_detectable_when_printed(tmp_path, capsys):
    out = tmp_path / "prints" / "board.png"
    argv = [
        "camera",
        "board",
        "--out",
        str(out),
        "--squares",
        "5",
        "4",
        "--pixels-per-square",
        "60",
    ]
    assert run(argv) == 0
    assert "5×4 squares, 360×300 px" in capsys.readouterr().out
    spec = CharucoBoardSpec(squares=(5, 4))
    _corners, ids, _, _ = cv2.aruco.CharucoDetector(spec.board()).detectBoard(cv2.imread(str(out)))
    assert ids is not None and sorted(ids.ravel()) == list(range(spec.corners))


def test_lens_calibration_then_floor_then_tracking_at_a_height(tmp_path, lens_folders, capsys):
    boards, arena = lens_folders
    intrinsics, calibration = tmp_path / "intrinsics.json", tmp_path / "calibration.json"
    argv = ["camera", "intrinsics", "--images", str(boards), "--out", str(intrinsics)]
    assert run([*argv, *BOARD_ARGUMENTS]) == 0
    assert "8 of 8 views, 640×480 px, RMS" in capsys.readouterr().out
    data = json.loads(intrinsics.read_text())
    assert data["format"] == "skidnav-camera-intrinsics" and data["views_used"] == 8
    argv = ["camera", "calibrate", "--source", str(arena), "--out", str(calibration)]
    assert run([*argv, "--intrinsics", str(intrinsics), "--frames", "1"]) == 0
    assert "m above the corner markers" in capsys.readouterr().out
    argv = ["camera", "track", "--source", str(arena), "--calibration", str(calibration)]
    assert run([*argv, "--intrinsics", str(intrinsics), "--marker-height", "0.08"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[1].endswith("lost") and len(lines) == 2 + len(LENS_POSES)
    for line, (x, y, heading) in zip(lines[2:], LENS_POSES, strict=True):
        _stamp, *measured = (float(v) for v in line.split())
        assert math.hypot(measured[0] - x, measured[1] - y) < 0.003
        assert heading_error(measured[2], heading) < math.radians(2)


def test_lens_user_errors_end_in_one_line(tmp_path, lens_folders, folder, capsys):
    boards, arena = lens_folders
    out = str(tmp_path / "intrinsics.json")
    few = [str(boards / f"board_{index}.png") for index in range(3)]
    argv = ["camera", "intrinsics", "--images", *few, "--out", out]
    assert "only 3 of the 3 images" in fails_in_one_line([*argv, *BOARD_ARGUMENTS], capsys)
    assert "(7×5 squares, DICT_5X5_100) not found" in fails_in_one_line(argv, capsys)
    # The 9 × 7 board is not in the arena images, nor a 7 × 5 one in the board views.
    argv = ["camera", "intrinsics", "--images", str(arena), "--out", out, *BOARD_ARGUMENTS]
    assert "not found in any of the 3 images" in fails_in_one_line(argv, capsys)
    junk = tmp_path / "junk.png"
    junk.write_bytes(b"not a png")
    argv = ["camera", "intrinsics", "--images", str(boards), str(junk), "--out", out]
    assert "junk.png: unreadable image" in fails_in_one_line(argv, capsys)
    argv = ["camera", "board", "--out", str(tmp_path / "board.xyz")]
    assert "cannot write the image" in fails_in_one_line(argv, capsys)
    argv = ["camera", "board", "--out", str(tmp_path / "b.png"), "--marker-size", "0.05"]
    assert "marker_size < square_size" in fails_in_one_line(argv, capsys)


def test_bad_intrinsics_for_tracking_end_in_one_line(tmp_path, lens_folders, folder, capsys):
    boards, arena = lens_folders
    intrinsics = tmp_path / "intrinsics.json"
    run(
        [
            "camera",
            "intrinsics",
            "--images",
            str(boards),
            "--out",
            str(intrinsics),
            *BOARD_ARGUMENTS,
        ]
    )
    plain = tmp_path / "plain.json"  # 1280 × 960 px scenes, no lens model
    run(["camera", "calibrate", "--source", str(folder), "--out", str(plain), "--frames", "1"])
    track = ["camera", "track", "--source", str(folder), "--calibration", str(plain)]
    line = fails_in_one_line([*track, "--intrinsics", str(intrinsics)], capsys)
    assert "for 640×480 px images but the calibration" in line and "1280×960 px" in line
    data = json.loads(intrinsics.read_text())
    data["camera_matrix"][0][0] = float("nan")
    broken = tmp_path / "broken.json"
    broken.write_text(json.dumps(data))
    line = fails_in_one_line([*track, "--intrinsics", str(broken)], capsys)
    assert "broken.json: invalid JSON (non-finite number NaN)" in line
    line = fails_in_one_line([*track, "--marker-height", "0.08"], capsys)
    assert "needs a floor calibration made with intrinsics" in line
    lens = tmp_path / "lens.json"
    argv = ["camera", "calibrate", "--source", str(arena), "--out", str(lens), "--frames", "1"]
    assert run([*argv, "--intrinsics", str(intrinsics)]) == 0
    argv = ["camera", "calibrate", "--source", str(folder), "--out", str(lens)]
    line = fails_in_one_line([*argv, "--intrinsics", str(intrinsics)], capsys)
    assert "but frame 0 is 1280×960 px" in line
    assert np.isfinite(json.loads(lens.read_text())["homography"]).all()  # not overwritten
