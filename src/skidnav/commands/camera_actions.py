"""The ``skidnav camera`` subcommands (their parsers: :mod:`skidnav.commands.camera`, which
imports this module only once the camera extra is known to be installed)."""

from __future__ import annotations

import argparse
import itertools
import math

from skidnav.errors import UserError
from skidnav.files.outputs import check_output_file, make_output_dir
from skidnav.realtime.camera.calibration import check_intrinsics
from skidnav.realtime.camera.markers import aruco_dictionary
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
