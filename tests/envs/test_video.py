"""Episodes of ``render_mode="rgb_array"`` to a video file through Gymnasium's ``RecordVideo``
(the ``video`` extra: moviepy), as docs/simulator.md shows: one frame per action plus the start,
at the env's ``render_fps``, the size of the env's frames."""

from __future__ import annotations

from pathlib import Path

import gymnasium
import numpy as np
from gymnasium.wrappers import RecordVideo
from moviepy import VideoFileClip

import skidnav  # noqa: F401  (registers the env)


def test_an_episode_is_recorded_frame_by_frame(tmp_path: Path) -> None:
    env = gymnasium.make(
        "skidnav/SkidSteerNav-v0",
        map_kind="free",
        world_seed=3,
        render_mode="rgb_array",
        max_episode_steps=12,
    )
    folder = tmp_path / "videos"
    env = RecordVideo(env, str(folder), episode_trigger=lambda episode: True, name_prefix="nav")
    env.reset(seed=0)
    first = env.render()
    actions = 0
    truncated = terminated = False
    while not (terminated or truncated):
        _, _, terminated, truncated, _ = env.step(actions % 2)  # forward, backward, …
        actions += 1
    last = env.render()
    env.close()

    video = folder / "nav-episode-0.mp4"
    assert [path.name for path in folder.iterdir()] == [video.name]
    clip = VideoFileClip(str(video))
    try:
        frames = list(clip.iter_frames())
        assert clip.fps == env.metadata["render_fps"] == 10
        assert tuple(clip.size) == (first.shape[1], first.shape[0])
    finally:
        clip.close()
    assert actions == 12 and len(frames) == actions + 1  # the start, then one per action
    assert all(frame.shape == first.shape for frame in frames)
    # Lossy compression: the first and last frames look like the env's (the robot moved).
    assert np.abs(frames[0].astype(int) - first).mean() < 3
    assert np.abs(frames[-1].astype(int) - last).mean() < 3
    assert np.abs(frames[0].astype(int) - frames[-1]).max() > 100
