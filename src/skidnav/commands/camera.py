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

The camera needs the camera extra (OpenCV): this module builds the parsers without it, and each
subcommand refuses in one line naming ``pip install "skidnav[camera]"`` before it starts when
OpenCV is missing; the subcommands themselves are in :mod:`skidnav.commands.camera_actions`.
"""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Callable
from typing import Any

from skidnav.commands.parsing import path_argument, positive_number
from skidnav.commands.verbs import HELP
from skidnav.extras import require
from skidnav.realtime.camera.defaults import (
    BOARD_MARKER_SIZE,
    BOARD_SQUARE_SIZE,
    BOARD_SQUARES,
    DEFAULT_BOARD_DICTIONARY,
    DEFAULT_DICTIONARY,
    MIN_VIEWS,
)


def _action(verb: str) -> Callable[[argparse.Namespace], int]:
    """The handler of ``skidnav camera VERB``: it refuses without the camera extra, then runs
    ``run_VERB`` of :mod:`skidnav.commands.camera_actions` (imported only then)."""

    def run(args: argparse.Namespace) -> int:
        require("camera", f"skidnav camera {verb}")
        actions = importlib.import_module("skidnav.commands.camera_actions")
        return int(getattr(actions, f"run_{verb}")(args))

    return run


def add_parser(subparsers: Any) -> None:
    """Add ``camera`` and its sub-subcommands to the ``skidnav`` parser."""
    parser = subparsers.add_parser("camera", help=HELP["camera"])
    actions = parser.add_subparsers(dest="camera_command", required=True)

    calib = actions.add_parser("calibrate", help="fit the floor homography from corner markers")
    _add_source_arguments(calib)
    calib.add_argument("--out", required=True, type=path_argument, help="calibration JSON to write")
    calib.add_argument(
        "--frames", type=int, default=10, help="frames to combine by median (default 10)"
    )
    calib.add_argument("--intrinsics", type=path_argument, help="lens model JSON: undistort first")
    _add_layout_arguments(calib)
    calib.set_defaults(func=_action("calibrate"))

    track = actions.add_parser("track", help="print the robot pose in every frame")
    _add_source_arguments(track)
    track.add_argument("--calibration", required=True, type=path_argument, help="calibration JSON")
    track.add_argument("--max-frames", type=int, default=None, help="stop after N frames")
    track.add_argument(
        "--intrinsics",
        type=path_argument,
        help="lens model JSON (checked against the calibration's)",
    )
    track.add_argument(
        "--marker-height",
        type=float,
        default=0.0,
        help="robot marker height above the corner markers [m] (needs intrinsics; default 0)",
    )
    track.set_defaults(func=_action("track"))
    _add_lens_parsers(actions)

    markers = actions.add_parser("markers", help="write printable marker images (PNG)")
    markers.add_argument("--out", required=True, type=path_argument, help="folder to write into")
    markers.add_argument("--ids", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    markers.add_argument("--pixels", type=int, default=600, help="side of each image [px]")
    markers.add_argument("--dictionary", default=DEFAULT_DICTIONARY)
    markers.set_defaults(func=_action("markers"))


def _add_lens_parsers(actions: Any) -> None:
    """The ``board`` and ``intrinsics`` sub-subcommands (the lens model)."""
    board = actions.add_parser("board", help="write a printable ChArUco board (PNG)")
    board.add_argument("--out", required=True, type=path_argument, help="PNG file to write")
    board.add_argument(
        "--pixels-per-square", type=int, default=120, help="[px] per square (default 120)"
    )
    _add_board_arguments(board)
    board.set_defaults(func=_action("board"))

    lens = actions.add_parser("intrinsics", help="calibrate the lens from ChArUco board images")
    lens.add_argument(
        "--images", required=True, nargs="+", help="image files and/or folders of images"
    )
    lens.add_argument("--out", required=True, type=path_argument, help="intrinsics JSON to write")
    lens.add_argument(
        "--min-views", type=int, default=MIN_VIEWS, help=f"views needed (default {MIN_VIEWS})"
    )
    _add_board_arguments(lens)
    lens.set_defaults(func=_action("intrinsics"))


def _add_board_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--squares",
        type=int,
        nargs=2,
        metavar=("COLUMNS", "ROWS"),
        default=list(BOARD_SQUARES),
        help="chessboard squares (default {} {})".format(*BOARD_SQUARES),
    )
    parser.add_argument(
        "--square-size", type=float, default=BOARD_SQUARE_SIZE, help="[m] (default %(default)s)"
    )
    parser.add_argument(
        "--marker-size", type=float, default=BOARD_MARKER_SIZE, help="[m] (default %(default)s)"
    )
    parser.add_argument(
        "--dictionary",
        default=DEFAULT_BOARD_DICTIONARY,
        help=f"board markers' ArUco dictionary (default {DEFAULT_BOARD_DICTIONARY})",
    )


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
