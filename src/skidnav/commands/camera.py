"""``skidnav camera``: calibrate the overhead camera, track the robot, print markers.

- ``skidnav camera board --out board.png`` writes a ChArUco board to print, and
  ``skidnav camera intrinsics --images DIR --out intrinsics.json`` fits the lens model from
  photos of it (docs/camera.md, "Lens model").
- ``skidnav camera calibrate --source SRC --out calibration.json [--intrinsics FILE]`` finds the
  four corner markers and saves the floor homography (docs/camera.md).
- ``skidnav camera track --source SRC --calibration calibration.json [--marker-height M]`` prints
  one pose per frame.
- ``skidnav camera markers --out DIR`` writes the marker images to print.

``SRC`` is a camera index (``0``), a video file, or a folder of images (read in name order).
"""

from __future__ import annotations

import argparse
import itertools
import math
from pathlib import Path
from typing import Any

from skidnav.commands.parsing import positive_number
from skidnav.errors import UserError
from skidnav.outputs import check_output_file, make_output_dir
from skidnav.realtime.camera.calibration import check_intrinsics
from skidnav.realtime.camera.intrinsics import DEFAULT_BOARD_DICTIONARY, MIN_VIEWS
from skidnav.realtime.camera.markers import DEFAULT_DICTIONARY, aruco_dictionary
from skidnav.realtime.camera.opencv import cv2
from skidnav.realtime.camera.sources import read_images
from skidnav.realtime.camera.tracking import (
    ArenaLayout,
    CameraPoseSource,
    CharucoBoardSpec,
    FloorCalibration,
    calibrate,
    calibrate_intrinsics,
    load_calibration,
    load_intrinsics,
    open_frames,
)


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
    calib.add_argument("--intrinsics", type=Path, help="lens model JSON: undistort first")
    _add_layout_arguments(calib)
    calib.set_defaults(func=run_calibrate)

    track = actions.add_parser("track", help="print the robot pose in every frame")
    _add_source_arguments(track)
    track.add_argument("--calibration", required=True, type=Path, help="calibration JSON")
    track.add_argument("--max-frames", type=int, default=None, help="stop after N frames")
    track.add_argument(
        "--intrinsics", type=Path, help="lens model JSON (checked against the calibration's)"
    )
    track.add_argument(
        "--marker-height",
        type=float,
        default=0.0,
        help="robot marker height above the corner markers [m] (needs intrinsics; default 0)",
    )
    track.set_defaults(func=run_track)
    _add_lens_parsers(actions)

    markers = actions.add_parser("markers", help="write printable marker images (PNG)")
    markers.add_argument("--out", required=True, type=Path, help="folder to write into")
    markers.add_argument("--ids", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    markers.add_argument("--pixels", type=int, default=600, help="side of each image [px]")
    markers.add_argument("--dictionary", default=DEFAULT_DICTIONARY)
    markers.set_defaults(func=run_markers)


def _add_lens_parsers(actions: Any) -> None:
    """The ``board`` and ``intrinsics`` sub-subcommands (the lens model)."""
    board = actions.add_parser("board", help="write a printable ChArUco board (PNG)")
    board.add_argument("--out", required=True, type=Path, help="PNG file to write")
    board.add_argument(
        "--pixels-per-square", type=int, default=120, help="[px] per square (default 120)"
    )
    _add_board_arguments(board)
    board.set_defaults(func=run_board)

    lens = actions.add_parser("intrinsics", help="calibrate the lens from ChArUco board images")
    lens.add_argument(
        "--images", required=True, nargs="+", help="image files and/or folders of images"
    )
    lens.add_argument("--out", required=True, type=Path, help="intrinsics JSON to write")
    lens.add_argument(
        "--min-views", type=int, default=MIN_VIEWS, help=f"views needed (default {MIN_VIEWS})"
    )
    _add_board_arguments(lens)
    lens.set_defaults(func=run_intrinsics)


def _add_board_arguments(parser: argparse.ArgumentParser) -> None:
    default = CharucoBoardSpec()
    parser.add_argument(
        "--squares",
        type=int,
        nargs=2,
        metavar=("COLUMNS", "ROWS"),
        default=list(default.squares),
        help="chessboard squares (default 7 5)",
    )
    parser.add_argument(
        "--square-size", type=float, default=default.square_size, help="[m] (default 0.03)"
    )
    parser.add_argument(
        "--marker-size", type=float, default=default.marker_size, help="[m] (default 0.022)"
    )
    parser.add_argument(
        "--dictionary",
        default=DEFAULT_BOARD_DICTIONARY,
        help=f"board markers' ArUco dictionary (default {DEFAULT_BOARD_DICTIONARY})",
    )


def _board(args: argparse.Namespace) -> CharucoBoardSpec:
    try:
        return CharucoBoardSpec(
            squares=(args.squares[0], args.squares[1]),
            square_size=args.square_size,
            marker_size=args.marker_size,
            dictionary=args.dictionary,
        )
    except ValueError as error:
        raise UserError(str(error)) from None


def _add_source_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--source", required=True, help="camera index, video file, or folder of images"
    )
    parser.add_argument(
        "--fps", type=positive_number, default=30.0, help="frame rate of an image folder [Hz]"
    )


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
    check_output_file(args.out)
    intrinsics = None if args.intrinsics is None else load_intrinsics(args.intrinsics)
    with open_frames(args.source, fps=args.fps) as frames:
        calibration = calibrate(frames, layout, max_frames=args.frames, intrinsics=intrinsics)
    place = _camera_place(calibration)
    calibration.save(args.out)
    width, height = calibration.image_size
    print(f"wrote {args.out} ({calibration.frames_used} frames, {width}×{height} px{place})")
    return 0


def _camera_place(calibration: FloorCalibration) -> str:
    """Where the lens model and homography put the camera, for the summary ("" without a lens)."""
    try:
        pose = calibration.camera_pose
    except ValueError as error:
        raise UserError(f"calibration inconsistent with the intrinsics: {error}") from None
    if pose is None:
        return ""
    x, y, z = pose.position
    return f", camera at x {x:.3f} y {y:.3f} m, {z:.3f} m above the corner markers"


def _tracker(args: argparse.Namespace) -> CameraPoseSource:
    """The pose source for ``track``: calibration, checked intrinsics, marker height."""
    calibration = load_calibration(args.calibration)
    if args.intrinsics is not None:
        lens = load_intrinsics(args.intrinsics, calibration.image_size, "the calibration")
        check_intrinsics(calibration, lens, str(args.calibration))
    try:
        return CameraPoseSource([], calibration, max_age=math.inf, marker_height=args.marker_height)
    except ValueError as error:
        raise UserError(f"--marker-height {args.marker_height}: {error}") from None


def run_track(args: argparse.Namespace) -> int:
    """Print ``stamp x y heading`` per frame (``stamp lost`` when the robot marker is not seen)."""
    if args.max_frames is not None and args.max_frames < 1:
        raise UserError(f"--max-frames must be >= 1, got {args.max_frames}")
    tracker = _tracker(args)
    with open_frames(args.source, fps=args.fps) as frames:
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
    make_output_dir(args.out)
    margin = args.pixels // 8
    for marker_id in args.ids:
        image = cv2.aruco.generateImageMarker(dictionary, marker_id, args.pixels)
        padded = cv2.copyMakeBorder(
            image, margin, margin, margin, margin, cv2.BORDER_CONSTANT, value=255
        )
        cv2.imwrite(str(args.out / f"marker_{marker_id}.png"), padded)
    print(f"wrote {len(args.ids)} markers to {args.out}")
    return 0


def run_board(args: argparse.Namespace) -> int:
    """Write the ChArUco board PNG; prints its size in squares and pixels."""
    spec = _board(args)
    if args.pixels_per_square < 20:
        raise UserError(f"--pixels-per-square must be >= 20, got {args.pixels_per_square}")
    check_output_file(args.out, parents=True)
    image = spec.image(args.pixels_per_square)
    make_output_dir(args.out.parent)
    try:
        written = cv2.imwrite(str(args.out), image)
    except cv2.error:
        written = False
    if not written:
        raise UserError(f"{args.out}: cannot write the image (use a .png name)")
    columns, rows = spec.squares
    print(
        f"wrote {args.out} ({columns}×{rows} squares, {image.shape[1]}×{image.shape[0]} px); "
        f"print it so that a square measures {spec.square_size * 1000:g} mm"
    )
    return 0


def run_intrinsics(args: argparse.Namespace) -> int:
    """Fit and save the lens model; prints the views used, RMS error and focal lengths."""
    spec = _board(args)
    if args.min_views < 3:
        raise UserError(f"--min-views must be >= 3, got {args.min_views}")
    check_output_file(args.out)
    images = read_images(args.images)
    intrinsics = calibrate_intrinsics(images, spec, min_views=args.min_views)
    intrinsics.save(args.out)
    width, height = intrinsics.image_size
    matrix = intrinsics.camera_matrix
    print(
        f"wrote {args.out} ({intrinsics.views_used} of {len(images)} views, {width}×{height} px, "
        f"RMS {intrinsics.rms_error:.3f} px, fx {matrix[0, 0]:.1f} fy {matrix[1, 1]:.1f} px)"
    )
    return 0
