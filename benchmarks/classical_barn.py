"""The classical navigator on BARN worlds: success, time to goal, time per control step.

    python benchmarks/classical_barn.py --worlds 1,76,151,226,299
    python benchmarks/classical_barn.py --every 10 --profile
    python benchmarks/classical_barn.py --worlds 0 --set horizon=2.0 --set speed_weight=0.1

Each world is one episode of the Jackal (``robot="jackal"``, 0.1-s actions, wheel speeds, the
features with ``--rays`` lidar rays of 10 m, the ``nominal`` floor), at most 1000 actions
(100 s, the benchmark's limit), from an empty map. Per world: whether it reached the goal, the
actions taken (× 0.1 s: the time), the env's collisions, the steps whose footprint touched a
cylinder of the true map (the Jackal's 0.458 × 0.416 m rectangle against the cells' discs at
every action's end pose: the benchmark's collision, measured here whether or not the env
stops the robot for it), the wall time and the navigator's own time per action. ``--profile``
splits the navigator's time between mapping, planning and control.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import gymnasium
import numpy as np

import skidnav
from skidnav.agents.classical import navigator
from skidnav.agents.classical.agent import ClassicalAgent
from skidnav.agents.classical.config import ClassicalConfig
from skidnav.sim.footprint import footprint_collides
from skidnav.world.barn import load_barn_world

JACKAL_FOOTPRINT = (0.458, 0.416)
"""The Jackal's footprint [m], along × across (docs/barn.md)."""
LIMIT = 1000
"""Actions per episode: 100 s of 0.1-s actions."""


def barn_env(world: int, rays: int) -> gymnasium.Env[Any, Any]:
    """The Jackal on BARN world ``world`` with ``rays`` lidar rays of 10 m."""
    barn = load_barn_world(world)
    return gymnasium.make(
        "skidnav/SkidSteerNav-v0", grid_map=barn.map.grid, discretization=barn.discretization,
        robot="jackal", control_period=0.1, action="continuous", observation="features",
        lidar_rays=rays, lidar_range=10.0, slip="nominal", max_episode_steps=LIMIT,
    )  # fmt: skip


class Timed:
    """Wall time [s] spent in a few module-level functions, by name."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}

    def wrap(self, module: Any, name: str) -> None:
        function = getattr(module, name)

        def timed(*args: Any) -> Any:
            start = time.perf_counter()
            try:
                return function(*args)
            finally:
                self.seconds[name] = self.seconds.get(name, 0.0) + time.perf_counter() - start

        setattr(module, name, timed)


def episode(world: int, rays: int, params: dict[str, Any]) -> dict[str, Any]:
    """One episode of the navigator on ``world`` (module doc)."""
    env = barn_env(world, rays)
    agent = skidnav.make_agent("classical", env, **params)
    assert isinstance(agent, ClassicalAgent)
    truth = env.unwrapped.grid_map.as_uint8()
    grid = env.unwrapped.discretization.grid_shape()
    observation, _ = env.reset(seed=0)
    started = time.perf_counter()
    acting = 0.0
    collisions = touching = steps = 0
    terminated = truncated = False
    while not (terminated or truncated):
        steps += 1
        before = time.perf_counter()
        action = agent.act(observation)
        acting += time.perf_counter() - before
        observation, _, terminated, truncated, info = env.step(action)
        collisions += bool(info.get("collision"))
        x, y, heading = observation[0], observation[1], np.arctan2(observation[3], observation[2])
        touching += footprint_collides(truth, grid, x, y, heading, *JACKAL_FOOTPRINT)
    return {
        "world": world, "success": bool(terminated), "steps": steps,
        "collisions": collisions, "touching": touching,
        "wall": time.perf_counter() - started, "per_step_ms": 1000 * acting / steps,
        "replans": agent.navigator.replans, "recoveries": agent.navigator.recoveries,
    }  # fmt: skip


def parse_setting(text: str) -> tuple[str, Any]:
    """``key=value`` with the value a number if it reads as one."""
    key, _, value = text.partition("=")
    try:
        return key, int(value)
    except ValueError:
        try:
            return key, float(value)
        except ValueError:
            return key, value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worlds", default="1,76,151,226,299", help="comma-separated indices")
    parser.add_argument("--every", type=int, help="every N-th world from 0 instead")
    parser.add_argument("--rays", type=int, default=720)
    parser.add_argument("--set", action="append", default=[], help="a setting key=value")
    parser.add_argument("--footprint", action="store_true", help="plan for the Jackal's footprint")
    parser.add_argument("--profile", action="store_true")
    args = parser.parse_args()
    worlds = (
        list(range(0, 300, args.every)) if args.every else [int(w) for w in args.worlds.split(",")]
    )
    params = dict(parse_setting(text) for text in args.set)
    if args.footprint:
        params.setdefault("footprint_length", JACKAL_FOOTPRINT[0])
        params.setdefault("footprint_width", JACKAL_FOOTPRINT[1])
    ClassicalConfig.from_mapping(params)
    timed = Timed()
    if args.profile:
        for name in ("record_scan", "update_occupancy", "replan", "choose_command"):
            timed.wrap(navigator, name)
    episode(worlds[0], args.rays, params)  # compile (or load the compiled kernels) first
    timed.seconds.clear()
    rows = [episode(world, args.rays, params) for world in worlds]
    for row in rows:
        print(" ".join(f"{key}={value:.3g}" if isinstance(value, float) else f"{key}={value}"
                       for key, value in row.items()))  # fmt: skip
    success = [row["success"] and row["touching"] == 0 for row in rows]
    steps = sum(row["steps"] for row in rows)
    times = [0.1 * row["steps"] for row, ok in zip(rows, success, strict=True) if ok]
    print(
        f"worlds {len(rows)}: reached {sum(row['success'] for row in rows)}, reached without "
        f"touching {sum(success)} ({100 * np.mean(success):.0f} %), mean time of those "
        f"{np.mean(times) if times else np.nan:.2f} s, "
        f"wall {sum(row['wall'] for row in rows):.1f} s, navigator "
        f"{np.mean([row['per_step_ms'] for row in rows]):.2f} ms/action"
    )
    if args.profile:
        for name, seconds in timed.seconds.items():
            print(f"  {name}: {1000 * seconds / steps:.3f} ms/action")


if __name__ == "__main__":
    main()
