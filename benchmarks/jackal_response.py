"""How the MuJoCo Jackal responds to wheel-speed commands: its accelerations and its effective
half track, the numbers the classical navigator's dynamic window is given on it.

    python benchmarks/jackal_response.py [--material rubber-mat]

The robot (``skidnav.physics``, the Jackal's build) drives on one material (the ``nominal``
floor's is the rubber mat) and is measured as the navigator measures it: from its poses every
control period T = 0.1 s, the forward speed along the mean heading and the yaw rate
(:class:`skidnav.agents.classical.window.Odometry`).

* **acceleration**, **braking**: full speed ahead from rest for 1 s, then both wheels
  commanded to 0; the largest change of the forward speed from one period to the next, over T
  [m/s²];
* **yaw acceleration**, **yaw braking**: the same for a turn in place at full wheel speed
  [rad/s²];
* **effective half track** c: the yaw rate held after 1 s of each of 9 × 9 wheel-speed pairs
  over ± Ω, fitted by least squares to ψ̇ = r (ω_R − ω_L) / (2 c) (Mandow et al. 2007: a
  skid-steer robot turns as a wider one), over every pair and over the gentle ones
  (|r (ω_R − ω_L) / 2| ≤ 0.5 m/s: the arcs a navigator drives at speed).

docs/barn.md ("The MuJoCo Jackal's response") states the figures this prints.
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from skidnav.agents.classical.window import Odometry
from skidnav.physics.mujoco_robot import PhysicsRobot
from skidnav.robot.presets import JACKAL

PERIOD = 0.1
"""The control period T [s] (the BARN benchmark's 10 Hz)."""
GENTLE = 0.5
"""The largest |r (ω_R − ω_L) / 2| [m/s] of the gentle arcs' fit."""


def drive(commands: list[tuple[float, float, int]], material: str) -> np.ndarray:
    """(v [m/s], ψ̇ [rad/s]) per period, float64 (n, 2), of the Jackal from rest on
    ``material`` under ``commands``: (ω_L [rad/s], ω_R [rad/s], periods) each."""
    robot = replace(JACKAL, arena_width=100.0, arena_height=100.0)  # far from any edge
    physics = PhysicsRobot(robot, np.array([[material]], dtype=object))
    physics.reset(50.0, 50.0, 0.0)
    odometry = Odometry(PERIOD)
    odometry.update(*physics.pose)
    velocities = []
    for left, right, periods in commands:
        for _ in range(periods):
            physics.drive(left, right, PERIOD)
            velocities.append(odometry.update(*physics.pose))
    return np.array(velocities)


def rates(values: np.ndarray) -> tuple[float, float]:
    """(largest rise, largest fall) per second of a per-period series starting from rest."""
    change = np.diff(np.concatenate([[0.0], values])) / PERIOD
    return float(change.max()), float(-change.min())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--material", default="rubber-mat", help="floor material")
    material = parser.parse_args().material
    top, radius = JACKAL.wheel_speed, JACKAL.wheel_radius
    ahead = drive([(top, top, 10), (0.0, 0.0, 10)], material)
    turn = drive([(-top, top, 10), (0.0, 0.0, 10)], material)
    pairs = np.linspace(-top, top, 9)
    differences, yaw_rates = [], []
    for left in pairs:
        for right in pairs:
            held = drive([(left, right, 15)], material)
            differences.append(radius * (right - left) / 2)
            yaw_rates.append(held[-5:, 1].mean())
    d, yaw = np.array(differences), np.array(yaw_rates)
    gentle = np.abs(d) <= GENTLE
    print(f"MuJoCo Jackal on {material}, measured every {PERIOD} s from its poses")
    print(f"top speed             {ahead[9, 0]:.3f} m/s")
    print("acceleration, braking {:.2f}, {:.2f} m/s²".format(*rates(ahead[:, 0])))
    datasheet = radius * top / JACKAL.half_track
    print(f"turn in place         {turn[9, 1]:.3f} rad/s (datasheet {datasheet:.2f})")
    print("yaw acceleration, braking {:.2f}, {:.2f} rad/s²".format(*rates(turn[:, 1])))
    print(f"effective half track  {(d @ d) / (d @ yaw):.3f} m over all {d.size} pairs, "
          f"{(d[gentle] @ d[gentle]) / (d[gentle] @ yaw[gentle]):.3f} m over the "
          f"{int(gentle.sum())} gentle ones (datasheet {JACKAL.half_track:.3f} m)")  # fmt: skip


if __name__ == "__main__":
    main()
