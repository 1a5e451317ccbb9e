"""``skidnav camera``: calibrate the overhead camera, track the robot, print markers.

- ``skidnav camera calibrate --source SRC --out calibration.json`` finds the four corner markers
  and saves the floor homography (docs/camera.md).
- ``skidnav camera track --source SRC --calibration calibration.json`` prints one pose per frame.
- ``skidnav camera markers --out DIR`` writes the marker images to print.

``SRC`` is a camera index (``0``), a video file, or a folder of images (read in name order).
"""

from __future__ import annotations

import argparse
import itertools
import math
from pathlib import Path
from typing import Any

import cv2

from skidnav.errors import UserError
from skidnav.realtime.camera import (
    ArenaLayout,
    CameraPoseSource,
    calibrate,
    load_calibration,
    open_frames,
)
from skidnav.realtime.camera_markers import DEFAULT_DICTIONARY, aruco_dictionary


def add_parser(subparsers: Any) -> None:
    """Add ``camera`` and its sub-subcommands to the ``skidnav`` parser."""
    parser = subparsers.add_parser("camera", help="overhead-camera calibration and tracking")
    actions = parser.add_subparsers(dest="camera_command", required=True)

    calib = actions.add_parser("calibrate", help="fit the floor homography from corner markers")
    _add_source_arguments(calib)
    calib.add_argument("--out", required=True, type=Path, help="calibration JSON to write")
    calib.add_argument(
        "--frames", type=int, default=10, help="frames to combine by median (default 10)"
    )
    _add_layout_arguments(calib)
    calib.set_defaults(func=run_calibrate)

    track = actions.add_parser("track", help="print the robot pose in every frame")
    _add_source_arguments(track)
    track.add_argument("--calibration", required=True, type=Path, help="calibration JSON")
    track.add_argument("--max-frames", type=int, default=None, help="stop after N frames")
    track.set_defaults(func=run_track)

    markers = actions.add_parser("markers", help="write printable marker images (PNG)")
    markers.add_argument("--out", required=True, type=Path, help="folder to write into")
    markers.add_argument("--ids", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    markers.add_argument("--pixels", type=int, default=600, help="side of each image [px]")
    markers.add_argument("--dictionary", default=DEFAULT_DICTIONARY)
    markers.set_defaults(func=run_markers)


def _add_source_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--source", required=True, help="camera index, video file, or folder of images"
    )
    parser.add_argument("--fps", type=float, default=30.0, help="frame rate of an image folder")


def _add_layout_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--arena-width", type=float, default=0.62, help="[m] (default 0.62)")
    parser.add_argument("--arena-height", type=float, default=0.505, help="[m] (default 0.505)")
    parser.add_argument(
        "--corner-ids",
        type=int,
        nargs=4,
        metavar="ID",
        default=[0, 1, 2, 3],
        help="ids at (0,0), (W,0), (W,H), (0,H) (default 0 1 2 3)",
    )
    parser.add_argument(
        "--corner-positions",
        type=float,
        nargs=8,
        default=None,
        metavar="XY",
        help="x y of each corner marker [m] if not the arena corners",
    )
    parser.add_argument("--robot-id", type=int, default=4, help="robot marker id (default 4)")
    parser.add_argument("--dictionary", default=DEFAULT_DICTIONARY, help="OpenCV ArUco dictionary")


def _layout(args: argparse.Namespace) -> ArenaLayout:
    positions = None
    if args.corner_positions is not None:
        values = args.corner_positions
        positions = tuple((values[i], values[i + 1]) for i in range(0, 8, 2))
    try:
        return ArenaLayout(
            arena_width=args.arena_width,
            arena_height=args.arena_height,
            corner_ids=tuple(args.corner_ids),
            corner_positions=positions,
            robot_id=args.robot_id,
            dictionary=args.dictionary,
        )
    except ValueError as error:
        raise UserError(str(error)) from None


def run_calibrate(args: argparse.Namespace) -> int:
    """Fit and save a calibration; prints where it was written."""
    layout = _layout(args)
    if args.frames < 1:
        raise UserError(f"--frames must be >= 1, got {args.frames}")
    with open_frames(args.source, fps=args.fps) as frames:
        calibration = calibrate(frames, layout, max_frames=args.frames)
    calibration.save(args.out)
    width, height = calibration.image_size
    print(f"wrote {args.out} ({calibration.frames_used} frames, {width}×{height} px)")
    return 0


def run_track(args: argparse.Namespace) -> int:
    """Print ``stamp x y heading`` per frame (``stamp lost`` when the robot marker is not seen)."""
    if args.max_frames is not None and args.max_frames < 1:
        raise UserError(f"--max-frames must be >= 1, got {args.max_frames}")
    calibration = load_calibration(args.calibration)
    with open_frames(args.source, fps=args.fps) as frames:
        tracker = CameraPoseSource([], calibration, max_age=math.inf)
        print("# stamp_s x_m y_m heading_rad")
        origin: float | None = None
        for frame in itertools.islice(frames, args.max_frames):
            pose = tracker.process(frame)
            origin = frame.stamp if origin is None else origin
            stamp = frame.stamp - origin
            if pose is None:
                print(f"{stamp:.3f} lost", flush=True)
            else:
                print(f"{stamp:.3f} {pose.x:.4f} {pose.y:.4f} {pose.heading:.4f}", flush=True)
    return 0


def run_markers(args: argparse.Namespace) -> int:
    """Write ``marker_<id>.png`` images with a white quiet zone, ready to print."""
    try:
        dictionary = aruco_dictionary(args.dictionary)
    except ValueError as error:
        raise UserError(str(error)) from None
    size = dictionary.bytesList.shape[0]
    if any(not 0 <= marker_id < size for marker_id in args.ids) or args.pixels < 20:
        raise UserError(f"expected ids in [0, {size}) and --pixels >= 20")
    args.out.mkdir(parents=True, exist_ok=True)
    margin = args.pixels // 8
    for marker_id in args.ids:
        image = cv2.aruco.generateImageMarker(dictionary, marker_id, args.pixels)
        padded = cv2.copyMakeBorder(
            image, margin, margin, margin, margin, cv2.BORDER_CONSTANT, value=255
        )
        cv2.imwrite(str(args.out / f"marker_{marker_id}.png"), padded)
    print(f"wrote {len(args.ids)} markers to {args.out}")
    return 0
