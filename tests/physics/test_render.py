"""Animated trajectories: frame counts and sizes, determinism, MuJoCo's frames, the fallback."""

from __future__ import annotations

import io
import math
import sys
from collections.abc import Iterator

import numpy as np
import pytest
from PIL import Image

from skidnav.physics import backend
from skidnav.physics.render import Arena, TopCamera, animate, frame_poses
from skidnav.robot.params import RobotParams

ROBOT = RobotParams()


def _arena() -> Arena:
    """A walled 25 × 25 arena with one inner wall column (right) and one slippery region."""
    occupancy = np.zeros((25, 25), dtype=np.uint8)
    occupancy[[0, -1], :] = 1
    occupancy[:, [0, -1]] = 1
    occupancy[21, 3:9] = 1  # where cells W/24 and W/25 wide differ by 4/10 of a cell
    eta = np.zeros((7, 7))
    eta[3, 1] = ROBOT.wheel_speed
    return Arena(occupancy, (2, 2), (20, 20), slip_eta=eta, robot=ROBOT)


def _poses(n: int = 12) -> np.ndarray:
    """A drive from (0.1, 0.1) to (0.45, 0.35) m, turning a quarter turn on the way."""
    fractions = np.linspace(0.0, 1.0, n)
    return np.column_stack(
        [0.1 + 0.35 * fractions, 0.1 + 0.25 * fractions, fractions * math.pi / 2]
    )


def _frames(gif: bytes) -> list[np.ndarray]:
    """Every frame of a GIF as RGB (H, W, 3) uint8."""
    movie = Image.open(io.BytesIO(gif))
    frames = []
    for k in range(movie.n_frames):
        movie.seek(k)
        frames.append(np.asarray(movie.convert("RGB")))
    return frames


def test_frame_poses_interpolate_and_respect_the_budget() -> None:
    poses = np.array([[0.0, 0.0, 3.0], [0.3, 0.0, -3.0]])  # heading crosses ±π
    frames = frame_poses(poses, 3, 150)
    assert frames.shape == (4, 3)
    np.testing.assert_allclose(frames[:, 0], [0.0, 0.1, 0.2, 0.3])
    turn = 2 * math.pi - 6.0  # the short way round, through π
    np.testing.assert_allclose(frames[1, 2], 3.0 + turn / 3)
    long = frame_poses(_poses(400), 3, 150)
    assert len(long) <= 150
    np.testing.assert_array_equal(long[0], _poses(400)[0])
    np.testing.assert_array_equal(long[-1], _poses(400)[-1])
    with pytest.raises(ValueError, match="expected poses of shape"):
        frame_poses(np.zeros((3, 2)), 3, 150)


def test_two_d_gif_has_the_frames_size_and_same_bytes() -> None:
    arena, poses = _arena(), _poses()
    movie = animate(arena, poses, renderer="2-d", frames_per_action=3, max_frames=150)
    assert (movie.renderer, movie.reason) == ("2-d", "")
    frames = _frames(movie.gif)
    assert len(frames) == movie.frames == 3 * (len(poses) - 1) + 1
    disc = arena.discretization()
    scale = min(320 / (disc.n_x * disc.cell_width), 240 / (disc.n_y * disc.cell_height))
    expected = (
        round(disc.n_y * disc.cell_height * scale),
        round(disc.n_x * disc.cell_width * scale),
    )
    assert frames[0].shape[:2] == expected
    assert max(frames[0].shape[:2][::-1]) <= 320 and frames[0].shape[0] <= 240
    assert not np.array_equal(frames[0], frames[-1])  # the robot moved
    assert Image.open(io.BytesIO(movie.gif)).info.get("loop") == 0
    again = animate(arena, poses, renderer="2-d", frames_per_action=3, max_frames=150)
    assert again.gif == movie.gif


def _robot_coloured(frame: np.ndarray, pixel: tuple[float, float], radius: int = 4) -> bool:
    """True when the chassis colour (orange: red well above green and blue) is near ``pixel``."""
    column, row = round(pixel[0]), round(pixel[1])
    patch = frame[row - radius : row + radius + 1, column - radius : column + radius + 1]
    red, green, blue = (patch[..., k].astype(int) for k in range(3))
    return bool(np.any((red - green > 90) & (red - blue > 90)))


def test_mujoco_frames_show_the_robot_where_the_pose_is() -> None:
    reason = backend.offscreen_rendering()
    if reason:
        pytest.skip(reason)
    arena, poses = _arena(), _poses()
    movie = animate(arena, poses, renderer="mujoco", frames_per_action=2, max_frames=150)
    assert (movie.renderer, movie.reason) == ("mujoco", "")
    frames = _frames(movie.gif)
    assert len(frames) == 2 * (len(poses) - 1) + 1
    assert frames[0].shape == (240, 320, 3)
    disc = arena.discretization()
    camera = TopCamera((disc.n_x * disc.cell_width, disc.n_y * disc.cell_height), (320, 240))
    first, last = camera.pixel(*poses[0, :2]), camera.pixel(*poses[-1, :2])
    assert _robot_coloured(frames[0], first) and not _robot_coloured(frames[0], last)
    assert _robot_coloured(frames[-1], last) and not _robot_coloured(frames[-1], first)
    # The inner wall is drawn on its navigation cells (the MDP's, W/(n_x − 1) wide).
    column, row = camera.pixel(21.5 * disc.cell_width, 5.5 * disc.cell_height)
    wall = frames[0][round(row), round(column)].astype(int)
    column, row = camera.pixel(18.5 * disc.cell_width, 5.5 * disc.cell_height)
    floor = frames[0][round(row), round(column)].astype(int)
    assert abs(wall[0] - wall[2]) < 40 and floor[0] - floor[2] > 40  # grey wall, warm laminate


@pytest.fixture
def no_mujoco(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """MuJoCo made unimportable, with the backend's cached answers forgotten before and after."""
    monkeypatch.setitem(sys.modules, "mujoco", None)
    backend.load_mujoco.cache_clear()
    backend.offscreen_rendering.cache_clear()
    yield
    monkeypatch.undo()
    backend.load_mujoco.cache_clear()
    backend.offscreen_rendering.cache_clear()


@pytest.mark.usefixtures("no_mujoco")
def test_without_mujoco_the_animation_falls_back_to_two_d() -> None:
    arena, poses = _arena(), _poses(5)
    movie = animate(arena, poses)
    assert movie.renderer == "2-d"
    assert "needs the physics extra" in movie.reason
    assert movie.gif == animate(arena, poses, renderer="2-d").gif
