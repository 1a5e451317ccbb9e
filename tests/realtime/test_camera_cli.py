"""``skidnav camera`` subcommands end to end on a folder of synthetic images."""

from __future__ import annotations

import argparse
import json
import math

import cv2
import pytest
from conftest_camera import heading_error, render_scene

from skidnav.commands import camera as camera_command
from skidnav.errors import UserError
from skidnav.realtime.camera import ArenaLayout, MarkerDetector

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
