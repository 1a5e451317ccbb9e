"""The MuJoCo robot: what its physics shows, measured with tolerances (docs/physics.md)."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

pytest.importorskip("mujoco")

from skidnav.physics import backend
from skidnav.physics.materials import MATERIALS, material, region_materials
from skidnav.physics.mjcf import PhysicsParams, arena_mjcf, uniform_floor
from skidnav.physics.mujoco_robot import PhysicsRobot
from skidnav.robot.kinematics import body_velocities
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import make_slip_field

ROBOT = RobotParams()


def one_second(floor: str, commands: tuple[float, float], timestep: float = 0.002):
    """Body-frame displacement (forward [m], left [m], heading change [rad]) of a robot at rest
    driven by ``commands`` for 1 s in ten 0.1-s drives."""
    robot = PhysicsRobot(ROBOT, uniform_floor(floor), PhysicsParams(timestep=timestep))
    robot.reset(0.3, 0.25, 0.4)
    start = robot.pose
    for _ in range(10):
        robot.drive(commands[0], commands[1], 0.1)
    return robot.displacement(start)


def test_straight_run_on_a_grippy_floor_is_r_omega_t() -> None:
    forward, left, turned = one_second("rubber-mat", (1.7, 1.7))
    expected = ROBOT.wheel_radius * 1.7 * 1.0  # r·ω·t, 3.825 cm
    assert forward == pytest.approx(expected, rel=0.03)
    assert abs(left) < 1e-4 and abs(turned) < 1e-3


def test_turning_in_place_is_slower_than_the_icr_model_and_slower_on_grippier_floors() -> None:
    icr_turn = body_velocities(-1.7, 1.7, ROBOT.x_icr, ROBOT.wheel_radius, ROBOT.half_track)[2]
    turns = {
        name: one_second(name, (-1.7, 1.7))[2] for name in ("wet-tile", "laminate", "rubber-mat")
    }
    for name, turned in turns.items():
        assert 0.2 * icr_turn < turned < 0.7 * icr_turn, name  # measured: 0.34–0.36 rad vs 0.64
    assert turns["rubber-mat"] < turns["laminate"] < turns["wet-tile"]


def test_the_timestep_passes_the_halving_test_and_twice_it_does_not() -> None:
    """docs/physics.md: the default timestep is the largest of 8, 4, 2 ms at which halving it
    changes a 1-s action's displacement by < 1 mm and its heading by < 0.5° (forward, turn in
    place, arc; every floor of the thesis's presets). Ice, added for the Jackal, is left out:
    the 0.35 kg robot's arc on it moves 8 mm between 2 and 1 ms (docs/physics.md)."""

    def passes(timestep: float) -> bool:
        for floor in sorted(set(MATERIALS) - {"ice"}):
            for commands in ((1.7, 1.7), (-1.7, 1.7), (0.5, 1.7)):
                coarse = np.array(one_second(floor, commands, timestep))
                fine = np.array(one_second(floor, commands, timestep / 2))
                if math.hypot(*(coarse[:2] - fine[:2])) >= 1e-3:
                    return False
                if abs(math.degrees(coarse[2] - fine[2])) >= 0.5:
                    return False
        return True

    default = PhysicsParams().timestep
    assert passes(default)
    assert not passes(2 * default)


def test_same_inputs_same_trajectory_bit_for_bit() -> None:
    poses = []
    for _ in range(2):
        robot = PhysicsRobot(ROBOT, uniform_floor("laminate"))
        robot.reset(0.2, 0.2, 1.0)
        trajectory = []
        for k in range(15):
            robot.drive(1.7 if k % 3 else -1.7, 1.7, 0.1)
            trajectory.append(robot.pose)
        poses.append(trajectory)
    assert poses[0] == poses[1]


def test_each_wheel_takes_the_friction_of_the_region_under_it() -> None:
    floor = uniform_floor("laminate")
    floor[:, 3:] = "wet-tile"  # regions j >= 3: y >= 3/7 of the arena
    robot = PhysicsRobot(ROBOT, floor)
    robot.reset(0.31, ROBOT.arena_height * 3 / 7, math.pi / 2)  # left wheels beyond the border
    robot.drive(0.0, 0.0, 0.002)
    frictions = {
        name: float(robot.model.geom_friction[robot.model.geom(name).id][0])
        for name in ("front_left", "front_right")
    }
    # Heading +y: the left wheels lie at smaller x, the front ones at larger y (wet tile).
    assert frictions["front_left"] == material("wet-tile").sliding
    rear = float(robot.model.geom_friction[robot.model.geom("rear_right").id][0])
    assert rear == material("laminate").sliding


def test_substep_applies_the_slip_loss_to_the_set_points_and_measures_the_twist() -> None:
    robot = PhysicsRobot(ROBOT, uniform_floor("rubber-mat"))
    robot.reset(0.3, 0.25, 0.0)
    set_points, twist = robot.substep((1.7, 1.7), 0.4, (0.5, 0.25), 0.1)
    assert set_points == pytest.approx((1.5, 1.6))
    assert twist[0] > 0 and abs(twist[1]) < 1e-3
    assert robot.time == pytest.approx(0.1)


def test_mjcf_has_four_servoed_wheels_and_one_box_per_wall_cell() -> None:
    occupancy = np.zeros((25, 25), dtype=np.uint8)
    occupancy[0, :] = 1
    occupancy[5, 7] = 1
    robot = PhysicsRobot(ROBOT, uniform_floor("laminate"), occupancy=occupancy)
    model = robot.model
    assert model.nu == 4
    assert np.allclose(model.actuator_forcerange, [[-0.02, 0.02]] * 4)
    wall_boxes = [
        k for k in range(model.ngeom)
        if model.geom_type[k] == 6 and model.geom_size[k][2] == pytest.approx(0.02)
    ]  # fmt: skip
    assert len(wall_boxes) == int(occupancy.sum())


def test_a_drawn_model_moves_exactly_as_the_simulated_one() -> None:
    """The drawn-only geoms (wall boxes, floor tiles) change nothing in the motion."""
    occupancy = np.zeros((25, 25), dtype=np.uint8)
    occupancy[0, :] = 1
    floor = region_materials("slippery", make_slip_field("slippery", np.random.default_rng(0)))
    drawn = PhysicsRobot(ROBOT, floor, occupancy=occupancy)
    simulated = PhysicsRobot(ROBOT, floor)
    assert drawn.model.ngeom == simulated.model.ngeom + 49 + 25  # 7 × 7 tiles, 25 wall cells
    poses = []
    for robot in (drawn, simulated):
        robot.reset(0.2, 0.25, 0.4)
        for k in range(30):  # turns and runs across the wet patches
            robot.substep((1.7, -1.7) if k % 4 else (1.7, 1.5), 0.3, (0.5, 0.2), 0.1)
        poses.append((robot.pose, robot.body_twist()))
    assert poses[0] == poses[1]


def test_bad_inputs_are_refused_in_one_line() -> None:
    with pytest.raises(ValueError, match="expected floor materials"):
        arena_mjcf(ROBOT, PhysicsParams(), np.full((7, 7), "lava", dtype=object))
    with pytest.raises(ValueError, match="expected a floor material"):
        material("lava")
    with pytest.raises(ValueError, match="timestep"):
        PhysicsParams(timestep=0.5)
    with pytest.raises(ValueError, match="motor_torque"):
        PhysicsParams(motor_torque=-1.0)


def test_slippery_preset_puts_wet_tile_on_its_patches() -> None:
    field = make_slip_field("slippery", np.random.default_rng(4))
    names = region_materials("slippery", field)
    assert set(names[field.eta >= ROBOT.wheel_speed]) == {"wet-tile"}
    assert set(names[field.eta < ROBOT.wheel_speed]) == {"laminate"}
    assert set(region_materials("rough", field).ravel()) == {"rubber-mat"}


def test_missing_mujoco_is_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    backend.load_mujoco.cache_clear()
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import then raises ImportError
    try:
        with pytest.raises(backend.PhysicsUnavailable) as caught:
            backend.load_mujoco()
        assert "\n" not in str(caught.value) and "skidnav[physics]" in str(caught.value)
        assert not backend.mujoco_available()
    finally:
        monkeypatch.undo()
        backend.load_mujoco.cache_clear()
    assert backend.mujoco_available()


def test_gl_backend_keeps_the_users_choice(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MUJOCO_GL", "osmesa")
    assert backend.gl_backend() == "osmesa"


def test_mujoco_imported_first_without_a_backend_degrades_instead_of_crashing() -> None:
    import os
    import subprocess

    script = (
        "import mujoco\n"
        "from skidnav.physics.backend import offscreen_rendering\n"
        "print(offscreen_rendering())\n"
    )
    environment = {key: value for key, value in os.environ.items() if key != "MUJOCO_GL"}
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, env=environment, timeout=60
    )
    assert done.returncode == 0, done.stderr
    assert "imported before" in done.stdout
