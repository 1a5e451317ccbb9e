"""Pictures of the arena: an RGB frame (PIL) and an ANSI text grid.

The frame spans the whole cell grid (n_x · cell_width by n_y · cell_height metres, a little more
than the arena since the last cell starts at the arena's edge), y pointing up. It shows slip
regions tinted by their loss scale η (white: none, orange: η at the wheel speed), walls, the start
(green) and goal (red) cells, the trail (blue) and the robot with its heading, in the colours of
:mod:`skidnav.world.colours`. :func:`with_legend` adds a strip naming them below a frame (the
pictures ``skidnav world map show --png`` and ``world simulate`` write).
"""

from __future__ import annotations

import io
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from skidnav.errors import UserError
from skidnav.files.atomic import write_user_file
from skidnav.robot.kinematics import wrap_angle
from skidnav.robot.slip import SlipField
from skidnav.world.colours import GOAL, LANDMARKS, START, TRAIL
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap

PIXELS_PER_METRE = 1000.0
WALL = (60, 60, 70)
ROBOT = (20, 20, 20)
LEGEND_HEIGHT = 28
"""Height of the legend strip of :func:`with_legend` [pixels]."""
HEADING_ARROWS = "→↗↑↖←↙↓↘"


class _Canvas:
    """Maps arena metres to image pixels (y up)."""

    def __init__(self, disc: Discretization, scale: float = PIXELS_PER_METRE) -> None:
        self.disc = disc
        self.scale = scale
        self.width = round(disc.n_x * disc.cell_width * scale)
        self.height = round(disc.n_y * disc.cell_height * scale)

    def point(self, x: float, y: float) -> tuple[float, float]:
        return x * self.scale, self.height - y * self.scale

    def box(self, x0: float, y0: float, x1: float, y1: float) -> tuple[float, float, float, float]:
        left, bottom = self.point(x0, y0)
        right, top = self.point(x1, y1)
        return left, top, right, bottom

    def cell_box(self, i: int, j: int) -> tuple[float, float, float, float]:
        w, h = self.disc.cell_width, self.disc.cell_height
        return self.box(i * w, j * h, (i + 1) * w, (j + 1) * h)


def _draw_slip(draw: ImageDraw.ImageDraw, canvas: _Canvas, slip: SlipField, top: float) -> None:
    disc = canvas.disc
    region_w = disc.arena_width / (disc.regions_x - 1)
    region_h = disc.arena_height / (disc.regions_y - 1)
    eta = slip.eta_at(0.0)
    for ri in range(disc.regions_x):
        for rj in range(disc.regions_y):
            level = min(float(eta[ri, rj]) / top, 1.0) if top > 0 else 0.0
            colour = (255, round(255 - 90 * level), round(255 - 200 * level))
            draw.rectangle(
                canvas.box(ri * region_w, rj * region_h, (ri + 1) * region_w, (rj + 1) * region_h),
                fill=colour,
            )


def _draw_robot(
    draw: ImageDraw.ImageDraw, canvas: _Canvas, pose: np.ndarray, body_length: float
) -> None:
    x, y, heading = (float(v) for v in pose)
    half = body_length / 2.0
    corners = [(half, 0.0), (-half, 0.6 * half), (-half, -0.6 * half)]
    points = [
        canvas.point(
            x + cx * math.cos(heading) - cy * math.sin(heading),
            y + cx * math.sin(heading) + cy * math.cos(heading),
        )
        for cx, cy in corners
    ]
    draw.polygon(points, outline=ROBOT, width=3)


def rgb_frame(
    grid_map: GridMap,
    disc: Discretization,
    slip: SlipField,
    pose: np.ndarray,
    trail: Sequence[tuple[float, float]],
    body_length: float = 0.10,
    wheel_speed: float = 1.7,
    scale: float = PIXELS_PER_METRE,
) -> np.ndarray:
    """The arena as an RGB image, uint8 array of shape (height, width, 3), at ``scale``
    [pixels per metre]."""
    canvas = _Canvas(disc, scale)
    image = Image.new("RGB", (canvas.width, canvas.height), (255, 255, 255))
    draw = ImageDraw.Draw(image)
    _draw_slip(draw, canvas, slip, wheel_speed)
    for i, j in np.argwhere(grid_map.occupancy):
        draw.rectangle(canvas.cell_box(int(i), int(j)), fill=WALL)
    draw.rectangle(canvas.cell_box(*grid_map.start), fill=START)
    draw.rectangle(canvas.cell_box(*grid_map.goal), fill=GOAL)
    if len(trail) > 1:
        draw.line([canvas.point(x, y) for x, y in trail], fill=TRAIL, width=2)
    _draw_robot(draw, canvas, pose, body_length)
    return np.asarray(image, dtype=np.uint8).copy()


def with_legend(frame: np.ndarray) -> np.ndarray:
    """``frame`` (H, W, 3) uint8 with a white strip of :data:`LEGEND_HEIGHT` pixels below it
    naming the start, the goal, the walls, the trail and the robot by their colours; shape
    (H + LEGEND_HEIGHT, W, 3)."""
    height, width = frame.shape[:2]
    image = Image.new("RGB", (width, height + LEGEND_HEIGHT), (255, 255, 255))
    image.paste(Image.fromarray(np.asarray(frame, dtype=np.uint8)), (0, 0))
    draw = ImageDraw.Draw(image)
    font = _legend_font()
    top, x = height + 7, 8
    for label, colour in (*LANDMARKS, ("wall", WALL)):
        draw.rectangle((x, top, x + 14, top + 14), fill=colour)
        draw.text((x + 19, top), label, fill=ROBOT, font=font)
        x += 26 + round(draw.textlength(label, font=font)) + 12
    draw.line((x, top + 7, x + 18, top + 7), fill=TRAIL, width=3)
    draw.text((x + 23, top), "trail", fill=ROBOT, font=font)
    x += 30 + round(draw.textlength("trail", font=font)) + 12
    draw.polygon([(x + 16, top + 7), (x, top), (x, top + 14)], outline=ROBOT, width=2)
    draw.text((x + 21, top), "robot (pointing along its heading)", fill=ROBOT, font=font)
    return np.asarray(image, dtype=np.uint8).copy()


def _legend_font() -> ImageFont.ImageFont | ImageFont.FreeTypeFont:
    """Pillow's own font at 13 pixels (its small bitmap font where FreeType is missing)."""
    try:
        return ImageFont.load_default(size=13)
    except (TypeError, ImportError, OSError):  # Pillow < 10.1, or no FreeType
        return ImageFont.load_default()


def save_frame(frame: np.ndarray, path: Path | str) -> None:
    """Write an RGB frame (H, W, 3) uint8 as a picture, its format chosen by the file suffix
    (e.g. ``.png``), all-or-nothing: the picture is encoded in memory, then written with
    :func:`~skidnav.files.atomic.write_user_file`, so a failed write leaves the old file, if any.

    Raises:
        UserError: the path cannot be written (missing directory, no permission, disk full) or
            its suffix names no picture format.
    """
    picture_format = Image.registered_extensions().get(Path(path).suffix.lower())
    if picture_format is None:
        raise UserError(f"{path}: unknown picture format (use e.g. .png)")
    buffer = io.BytesIO()
    try:
        Image.fromarray(np.asarray(frame, dtype=np.uint8)).save(buffer, format=picture_format)
    except (ValueError, KeyError, OSError):  # a format PIL reads but cannot write (e.g. .eps)
        raise UserError(f"{path}: cannot write {picture_format} pictures (use e.g. .png)") from None
    write_user_file(path, buffer.getvalue(), "picture")


def ansi_frame(grid_map: GridMap, disc: Discretization, pose: np.ndarray) -> str:
    """The map as text, top row first: ``#`` wall, ``S`` start, ``G`` goal, an arrow for the
    robot pointing along its heading (8 directions)."""
    robot_i, robot_j = disc.cell(float(pose[0]), float(pose[1]))
    sector = round(wrap_angle(pose[2]) / (math.pi / 4)) % 8
    rows = []
    for j in range(disc.n_y - 1, -1, -1):
        chars = []
        for i in range(disc.n_x):
            if (i, j) == (robot_i, robot_j):
                chars.append(HEADING_ARROWS[sector])
            elif grid_map.occupancy[i, j]:
                chars.append("#")
            elif (i, j) == grid_map.goal:
                chars.append("G")
            elif (i, j) == grid_map.start:
                chars.append("S")
            else:
                chars.append(".")
        rows.append("".join(chars))
    return "\n".join(rows) + "\n"
