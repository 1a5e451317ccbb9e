"""Animations of a trajectory on its arena: an animated GIF, drawn by MuJoCo or in 2-D.

:func:`animate` turns a trajectory of poses (one per action) into a looping GIF of at most
``max_frames`` frames (``frames_per_action`` interpolated frames per action: positions linearly,
the heading along the shorter arc; a long trajectory keeps every k-th pose first). The picture:

- ``"mujoco"``, where :func:`~skidnav.physics.backend.offscreen_rendering` says MuJoCo can render
  offscreen: the robot of :class:`~skidnav.physics.mujoco_robot.PhysicsRobot` placed at each pose
  (no physics step), seen straight down by an orthographic camera, floor tiles coloured by
  material, walls as boxes; the trail and the outlines of the start (green) and goal (red) cells
  are drawn over it (:mod:`skidnav.world.colours`). The floor tiles and
  walls are moved onto the navigation grid (cells W/(n_x − 1) wide,
  :class:`~skidnav.world.discretization.Discretization`) so the picture matches the MDP's cells.
- ``"2-d"`` otherwise (or when asked): the frames of the env's ``rgb_array`` renderer
  (:func:`skidnav.world.rendering.rgb_frame`); the same inputs give the same bytes.

Every frame is mapped onto one palette taken from the first and last frames (no dithering), so
the GIF is small and, for the 2-D renderer, deterministic.
"""

from __future__ import annotations

import io
import logging
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from PIL import Image, ImageDraw

from skidnav.physics.backend import offscreen_rendering
from skidnav.physics.materials import PATCH_MATERIAL
from skidnav.robot.kinematics import wrap_angle
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SlipField
from skidnav.world.colours import GOAL, START, TRAIL
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap
from skidnav.world.rendering import rgb_frame

logger = logging.getLogger(__name__)

RENDERERS = ("auto", "mujoco", "2-d")
ACTION_MILLISECONDS = 300
"""Playback time of one action [ms] (an action lasts 1 s: the GIF plays about 3× faster)."""
HOLD_MILLISECONDS = 1500
"""How long the last frame stays before the GIF loops [ms]."""
SWATCH_ROWS = 16
"""Rows of landmark colours added to the sample a GIF's palette is drawn from [pixels]."""


class Animation(NamedTuple):
    """An animated GIF and how it was drawn.

    Attributes:
        gif: the GIF file's bytes (loops forever).
        renderer: ``"mujoco"`` or ``"2-d"``.
        reason: why the 2-D renderer drew it (``""`` for MuJoCo or when asked for 2-D).
        frames: number of frames.
    """

    gif: bytes
    renderer: str
    reason: str
    frames: int


@dataclass(frozen=True)
class Arena:
    """The world a trajectory is drawn on.

    Attributes:
        occupancy: wall map, shape (n_x, n_y), nonzero = wall.
        start, goal: start and goal cells (i, j); None: the cells of the first and last pose.
        slip_eta: wheel-speed loss scale η per slip region, shape (regions_x, regions_y)
            [rad/s]; None: from ``materials`` (wet tile: the wheel speed, else 0).
        materials: floor material name per region (object array of the same shape); None:
            from ``slip_eta`` (wet tile where η reaches the wheel speed, as the ``slippery``
            preset; laminate elsewhere).
        robot: geometry and arena size.
    """

    occupancy: np.ndarray
    start: tuple[int, int] | None = None
    goal: tuple[int, int] | None = None
    slip_eta: np.ndarray | None = None
    materials: np.ndarray | None = None
    robot: RobotParams = field(default_factory=RobotParams)

    def __post_init__(self) -> None:
        if self.slip_eta is None and self.materials is None:
            raise ValueError("expected slip_eta or materials, got neither")
        occupancy = np.asarray(self.occupancy)
        if occupancy.ndim != 2:
            raise ValueError(f"expected occupancy of shape (n_x, n_y), got {occupancy.shape}")
        object.__setattr__(self, "occupancy", (occupancy != 0).astype(np.uint8))

    def eta(self) -> np.ndarray:
        """η per region [rad/s], float64 (regions_x, regions_y)."""
        if self.slip_eta is not None:
            return np.asarray(self.slip_eta, dtype=np.float64)
        patches = np.asarray(self.materials, dtype=object) == PATCH_MATERIAL
        return np.where(patches, self.robot.wheel_speed, 0.0)

    def floor(self) -> np.ndarray:
        """Material name per region, object array (regions_x, regions_y)."""
        if self.materials is not None:
            return np.asarray(self.materials, dtype=object)
        names = np.full(self.eta().shape, "laminate", dtype=object)
        names[self.eta() >= self.robot.wheel_speed] = PATCH_MATERIAL
        return names

    def discretization(self) -> Discretization:
        """The navigation grid of this arena (cells and slip regions)."""
        n_x, n_y = self.occupancy.shape
        regions_x, regions_y = self.eta().shape
        return Discretization(
            n_x, n_y, 20, regions_x, regions_y, self.robot.arena_width, self.robot.arena_height
        )

    def grid_map(self, poses: np.ndarray) -> GridMap:
        """Walls, start and goal (the first and last pose's cells where not given)."""
        disc = self.discretization()
        start = self.start or disc.cell(poses[0, 0], poses[0, 1])
        goal = self.goal or disc.cell(poses[-1, 0], poses[-1, 1])
        return GridMap(
            self.occupancy.astype(bool),
            (int(start[0]), int(start[1])),
            (int(goal[0]), int(goal[1])),
        )


def frame_poses(poses: np.ndarray, frames_per_action: int, max_frames: int) -> np.ndarray:
    """The pose of every frame, float64 (m, 3) with m ≤ ``max_frames``: up to
    ``frames_per_action`` per action, interpolated (x, y linearly, heading along the shorter
    arc), the last pose last. Over ``max_frames − 1`` actions, evenly spaced poses are kept.

    >>> frame_poses(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), 4, 150)[:, 0].tolist()
    [0.0, 0.25, 0.5, 0.75, 1.0]
    """
    poses = np.asarray(poses, dtype=np.float64)
    if poses.ndim != 2 or poses.shape[1] != 3 or len(poses) == 0:
        raise ValueError(f"expected poses of shape (n, 3) with n >= 1, got {poses.shape}")
    if max_frames < 2 or frames_per_action < 1:
        raise ValueError(
            f"expected max_frames >= 2 and frames_per_action >= 1, got {max_frames}, "
            f"{frames_per_action}"
        )
    actions = len(poses) - 1
    if actions == 0:
        return poses.copy()
    if actions > max_frames - 1:
        keep = np.unique(np.linspace(0, actions, max_frames).round().astype(int))
        poses, actions = poses[keep], len(keep) - 1
    per_action = max(1, min(frames_per_action, (max_frames - 1) // actions))
    fractions = np.arange(per_action) / per_action
    starts, ends = poses[:-1], poses[1:]
    turn = np.array([wrap_angle(float(h)) for h in ends[:, 2] - starts[:, 2]])
    delta = np.column_stack([ends[:, :2] - starts[:, :2], turn])
    frames = starts[:, None, :] + fractions[None, :, None] * delta[:, None, :]
    return np.vstack([frames.reshape(-1, 3), poses[-1:]])


def _frames_2d(arena: Arena, poses: np.ndarray, size: tuple[int, int]) -> list[Image.Image]:
    """The env's 2-D frames, scaled to fit ``size`` (width, height) [px]."""
    disc = arena.discretization()
    grid_map = arena.grid_map(poses)
    eta = arena.eta()
    slip = SlipField(eta, np.zeros_like(eta), drift_phase=np.zeros_like(eta))
    scale = min(size[0] / (disc.n_x * disc.cell_width), size[1] / (disc.n_y * disc.cell_height))
    robot = arena.robot
    return [
        Image.fromarray(
            rgb_frame(
                grid_map, disc, slip, pose, [(float(x), float(y)) for x, y, _ in poses[: k + 1]],
                robot.body_length, robot.wheel_speed, scale,
            )
        )
        for k, pose in enumerate(poses)
    ]  # fmt: skip


@dataclass(frozen=True)
class TopCamera:
    """The orthographic camera looking straight down on the whole cell grid.

    Attributes:
        extent: grid width and height [m] (n_x · cell width, n_y · cell height).
        size: image width and height [px].
    """

    extent: tuple[float, float]
    size: tuple[int, int]

    @property
    def view_height(self) -> float:
        """Floor height seen by the image [m] (the grid with a 4 % margin)."""
        width, height = self.extent
        return 1.04 * max(height, width * self.size[1] / self.size[0])

    def pixel(self, x: float, y: float) -> tuple[float, float]:
        """Image (column, row) [px] of floor point (x, y) [m]; y points up."""
        per_metre = self.size[1] / self.view_height
        column = self.size[0] / 2 + (x - self.extent[0] / 2) * per_metre
        row = self.size[1] / 2 - (y - self.extent[1] / 2) * per_metre
        return column, row

    def mjv_camera(self, mujoco: Any) -> Any:
        """The ``MjvCamera`` (free, orthographic, elevation −90°, x to the right)."""
        camera = mujoco.MjvCamera()
        camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        camera.lookat[:] = (self.extent[0] / 2, self.extent[1] / 2, 0.0)
        camera.distance, camera.elevation, camera.azimuth = 1.0, -90.0, 90.0
        camera.orthographic = 1
        return camera


Box = tuple[float, float, float, float]
"""A cell's corners (x0, y0, x1, y1) [m]."""


def _overlay(
    image: Image.Image, camera: TopCamera, landmarks: tuple[Box, Box], trail: np.ndarray
) -> None:
    """Draw the outlines of the start and goal cells (``landmarks``, in the colours of
    :mod:`skidnav.world.colours`) and the trail (the poses so far, (k, 3)) over a MuJoCo
    frame."""
    draw = ImageDraw.Draw(image)
    for box, colour in zip(landmarks, (START, GOAL), strict=True):
        left, top = camera.pixel(box[0], box[3])
        right, bottom = camera.pixel(box[2], box[1])
        draw.rectangle((left, top, right, bottom), outline=colour, width=2)
    if len(trail) > 1:
        draw.line([camera.pixel(float(x), float(y)) for x, y, _ in trail], fill=TRAIL, width=2)


def _cell_box(disc: Discretization, cell: tuple[int, int]) -> Box:
    """The corners of ``cell`` (i, j) on the navigation grid [m]."""
    i, j = cell
    w, h = disc.cell_width, disc.cell_height
    return (i * w, j * h, (i + 1) * w, (j + 1) * h)


def _frames_mujoco(arena: Arena, poses: np.ndarray, size: tuple[int, int]) -> list[Image.Image]:
    """MuJoCo's offscreen frames of the robot placed at each pose."""
    from skidnav.physics.mujoco_robot import PhysicsRobot  # imports MuJoCo

    robot = PhysicsRobot(arena.robot, arena.floor(), occupancy=arena.occupancy)
    mujoco, model = robot.mujoco, robot.model
    disc = arena.discretization()
    camera = TopCamera((disc.n_x * disc.cell_width, disc.n_y * disc.cell_height), size)
    model.vis.global_.fovy = camera.view_height  # an orthographic camera's fovy is in metres
    model.vis.headlight.diffuse[:] = 0.45
    model.light_specular[:] = 0.05
    view = camera.mjv_camera(mujoco)
    grid_map = arena.grid_map(poses)
    landmarks = (_cell_box(disc, grid_map.start), _cell_box(disc, grid_map.goal))
    frames = []
    with mujoco.Renderer(model, size[1], size[0]) as renderer:
        for flag in ("mjRND_SHADOW", "mjRND_REFLECTION", "mjRND_SKYBOX"):  # slow on CPU GL
            renderer.scene.flags[getattr(mujoco.mjtRndFlag, flag)] = False
        for k, (x, y, heading) in enumerate(poses):
            robot.place(float(x), float(y), float(heading))
            renderer.update_scene(robot.data, camera=view)
            image = Image.fromarray(renderer.render())
            _overlay(image, camera, landmarks, poses[: k + 1])
            frames.append(image)
    return frames


def encode_gif(frames: list[Image.Image], durations: list[int]) -> bytes:
    """A looping GIF of RGB ``frames`` shown ``durations`` [ms] each, on one 64-colour palette
    from the first and last frames and the start, goal and trail colours (so their thin
    outlines keep their colour), without dithering (same frames, same bytes)."""
    first, last = frames[0], frames[-1]
    sample = Image.new("RGB", (first.width * 2, first.height + SWATCH_ROWS))
    sample.paste(first, (0, 0))
    sample.paste(last, (first.width, 0))
    draw = ImageDraw.Draw(sample)
    step = sample.width // 3
    for k, colour in enumerate((START, GOAL, TRAIL)):
        draw.rectangle((k * step, first.height, (k + 1) * step, sample.height), fill=colour)
    palette = sample.quantize(colors=64, dither=Image.Dither.NONE)
    indexed = [frame.quantize(palette=palette, dither=Image.Dither.NONE) for frame in frames]
    buffer = io.BytesIO()
    indexed[0].save(
        buffer, format="GIF", save_all=True, append_images=indexed[1:], duration=durations,
        loop=0,
    )  # fmt: skip
    return buffer.getvalue()


def animate(
    arena: Arena,
    poses: np.ndarray,
    *,
    renderer: str = "auto",
    frames_per_action: int = 3,
    max_frames: int = 150,
    size: tuple[int, int] = (320, 240),
) -> Animation:
    """An animated GIF of ``poses`` (float64 (n, 3): x [m], y [m], heading [rad], one per
    action) on ``arena``.

    Args:
        renderer: ``"auto"`` (MuJoCo where it renders offscreen, else 2-D), ``"mujoco"``
            (2-D, with the reason, where it cannot) or ``"2-d"``.
        frames_per_action, max_frames: see :func:`frame_poses`.
        size: image (width, height) [px]; the 2-D frames keep the grid's aspect within it.
    """
    if renderer not in RENDERERS:
        raise ValueError(f"expected renderer in {', '.join(RENDERERS)}, got {renderer!r}")
    frames_at = frame_poses(poses, frames_per_action, max_frames)
    per_action = (len(frames_at) - 1) / max(1, len(np.asarray(poses)) - 1)
    step = max(10, round(ACTION_MILLISECONDS / max(per_action, 1.0) / 10) * 10)
    durations = [step] * (len(frames_at) - 1) + [HOLD_MILLISECONDS]
    reason = offscreen_rendering() if renderer != "2-d" else ""
    if renderer != "2-d" and not reason:
        try:
            frames = _frames_mujoco(arena, frames_at, size)
            return Animation(encode_gif(frames, durations), "mujoco", "", len(frames))
        except Exception as error:  # a GL context can still fail here (e.g. out of memory)
            reason = f"MuJoCo rendering failed: {error}".splitlines()[0]
            logger.warning("render: %s; drawing in 2-D", reason)
    frames = _frames_2d(arena, frames_at, size)
    return Animation(encode_gif(frames, durations), "2-d", reason, len(frames))


def describe(animation: Animation) -> str:
    """One line naming the renderer (and why 2-D, if it was not asked for).

    >>> describe(Animation(b"", "2-d", "no GL backend", 10))
    '2-D renderer (MuJoCo offscreen rendering unavailable: no GL backend), 10 frames'
    """
    if animation.renderer == "mujoco":
        return f"MuJoCo offscreen renderer, {animation.frames} frames"
    why = (
        f" (MuJoCo offscreen rendering unavailable: {animation.reason})" if animation.reason else ""
    )
    return f"2-D renderer{why}, {animation.frames} frames"


__all__ = ["Animation", "Arena", "TopCamera", "animate", "describe", "encode_gif", "frame_poses"]
