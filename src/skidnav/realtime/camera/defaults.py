"""The camera's defaults, in a module that does not import OpenCV: the command line shows them
in its help whether or not the camera extra is installed (docs/camera.md)."""

from __future__ import annotations

DEFAULT_DICTIONARY = "DICT_4X4_50"
"""The OpenCV ArUco dictionary of the arena's corner and robot markers."""
# The board's markers come from another dictionary than the arena's DICT_4X4_50, so a board left
# in view can never be taken for a corner or robot marker.
DEFAULT_BOARD_DICTIONARY = "DICT_5X5_100"
"""The ArUco dictionary of the ChArUco board's markers."""
MIN_VIEWS = 4
"""Views with the board a lens calibration needs by default; each gives two constraints on K
(Zhang (2000) §3.1)."""
BOARD_SQUARES = (7, 5)
"""(columns, rows) of the default ChArUco board's chessboard squares."""
BOARD_SQUARE_SIZE = 0.03
"""Side of one square of the default board [m]."""
BOARD_MARKER_SIZE = 0.022
"""Side of one marker of the default board [m]."""
