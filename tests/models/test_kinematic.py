"""The learned Bayesian-ridge kinematic model: parameter recovery, prediction, persistence."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skidnav.models.kinematic import KinematicModel
from skidnav.models.kinematic_config import KinematicModelConfig
from skidnav.models.kinematic_files import load_model, save_model
from skidnav.models.kinematic_prediction import (
    PREDICT_COLLISION,
    PREDICT_FREE,
    PREDICT_GOAL,
    collision_wall_cell,
    predict_action,
)
from skidnav.robot.kinematics import body_velocities
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import make_slip_field
from skidnav.sim.navigation import pose_state, transition
from skidnav.sim.task import build_task
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap, border_walls

GRID = Discretization()


def _noise_free_log(
    rng: np.random.Generator, n: int, region: int, radius: float, half_track: float, x_icr: float
) -> np.ndarray:
    """Rows of a robot with the given true geometry, random wheel speeds."""
    rows = np.zeros((n, 6))
    for k in range(n):
        omega_left, omega_right = rng.uniform(-1.7, 1.7, size=2)
        v_x, v_y, yaw_rate = body_velocities(omega_left, omega_right, x_icr, radius, half_track)
        rows[k] = (region, omega_left, omega_right, v_x, v_y, yaw_rate)
    return rows


def test_recovers_geometry_from_noise_free_data_within_5_percent() -> None:
    model = KinematicModel(RobotParams(), GRID, KinematicModelConfig(refit_every=1))
    rng = np.random.default_rng(3)
    truths = {4: (0.03, 0.08, 0.02), 30: (0.015, 0.05, -0.03)}
    for region, truth in truths.items():
        model.feed(_noise_free_log(rng, 200, region, *truth))
    assert model.maybe_refit()
    for region, truth in truths.items():
        for estimate, true in zip(model.estimates(region), truth, strict=True):
            assert estimate == pytest.approx(true, rel=0.05)


@pytest.mark.parametrize("wheels", [[(1.7, 1.7)], [(1.7, 1.7), (-1.7, -1.7)]])
def test_a_region_driven_straight_learns_its_radius_and_stays_finite(
    wheels: list[tuple[float, float]],
) -> None:
    """One action, or forward and back (collinear wheel speeds: a singular XᵀX), noise-free:
    the regressions met a negative Cholesky pivot and left NaN coefficients (compiled) or divided
    by zero; now v_x gives r / 2 per wheel and the unexcited yaw and v_y keep the prior."""
    model = KinematicModel(RobotParams(), GRID, KinematicModelConfig(refit_every=1))
    rows = np.zeros((200, 6))
    for k, (omega_left, omega_right) in enumerate(wheels * (200 // len(wheels))):
        twist = body_velocities(omega_left, omega_right, 0.02, 0.03, 0.08)
        rows[k] = (4, omega_left, omega_right, *twist)
    model.feed(rows)
    model.refit()
    assert np.isfinite(model.coefficients).all() and np.isfinite(model.velocities).all()
    np.testing.assert_allclose(model.coefficients[4, :2], [0.015, 0.015], rtol=1e-6)
    np.testing.assert_allclose(model.coefficients[4, 3:], [-0.1875, 0.1875, 0.0, -0.05, 0.0])


def test_regions_without_data_use_the_pooled_fit_and_empty_model_the_prior() -> None:
    config = KinematicModelConfig(min_samples=50, refit_every=1)
    model = KinematicModel(RobotParams(), GRID, config)
    assert model.estimates(7) == pytest.approx((0.0225, 0.06, 0.05))
    model.feed(_noise_free_log(np.random.default_rng(0), 30, 4, 0.03, 0.08, 0.02))
    model.refit()  # 30 < 50 samples in total: still the prior everywhere
    assert model.estimates(4) == pytest.approx((0.0225, 0.06, 0.05))
    model.feed(_noise_free_log(np.random.default_rng(1), 100, 4, 0.03, 0.08, 0.02))
    model.refit()  # region 4 has its own fit; region 7 has none and takes the pooled one
    assert model.estimates(7) == pytest.approx(model.estimates(4), rel=0.05)
    assert model.estimates(7)[0] == pytest.approx(0.03, rel=0.05)


def test_refit_schedule_waits_for_enough_new_samples() -> None:
    model = KinematicModel(RobotParams(), GRID, KinematicModelConfig(refit_every=100))
    rng = np.random.default_rng(0)
    model.feed(_noise_free_log(rng, 60, 3, 0.0225, 0.06, 0.05))
    assert not model.maybe_refit()
    model.feed(_noise_free_log(rng, 60, 3, 0.0225, 0.06, 0.05))
    assert model.maybe_refit() and model.new_samples == 0


def test_forgetting_follows_a_change_of_slip() -> None:
    config = KinematicModelConfig(refit_every=1, forgetting=0.95, window=400)
    model = KinematicModel(RobotParams(), GRID, config)
    rng = np.random.default_rng(5)
    model.feed(_noise_free_log(rng, 300, 10, 0.0225, 0.06, 0.05))
    model.feed(_noise_free_log(rng, 100, 10, 0.0112, 0.06, 0.05))  # wheels now lose half
    model.refit()
    assert model.estimates(10)[0] == pytest.approx(0.0112, rel=0.05)


def _open_task(slip: str, seed: int) -> tuple[object, GridMap]:
    occupancy = border_walls((25, 25))
    grid_map = GridMap(occupancy=occupancy, start=(3, 3), goal=(20, 20))
    field = make_slip_field(slip, np.random.default_rng(seed))
    return build_task(grid_map, field, RobotParams(), GRID), grid_map


def test_predicts_simulator_next_cell_in_95_percent_of_free_steps() -> None:
    task, grid_map = _open_task("thesis", 0)
    rng = np.random.default_rng(11)
    model = KinematicModel(RobotParams(), GRID, KinematicModelConfig(refit_every=1))
    log = np.zeros((10, 6))
    pose = np.array([0.3, 0.25, 0.0])
    for _ in range(300):  # learn from a random walk
        transition(task, pose, int(rng.random() * 4), 0.0, rng.random(20), log)
        model.feed(log[:10])
    model.refit()
    hits = total = 0
    for _ in range(400):
        action = int(rng.random() * 4)
        start = (float(pose[0]), float(pose[1]), float(pose[2]))
        outcome = transition(task, pose, action, 0.0, rng.random(20), log)
        if outcome.collided:
            continue
        predicted, code = model.predict(start, action, grid_map.occupancy)
        assert code != PREDICT_GOAL
        total += 1
        hits += GRID.state(*predicted) == pose_state(task, pose)
    assert total > 250
    assert hits / total >= 0.95


def test_prediction_table_respects_known_walls_and_goals() -> None:
    model = KinematicModel(RobotParams(), GRID)
    walls = np.zeros((25, 25), dtype=bool)
    walls[12, :] = True
    goals = np.zeros((25, 25), dtype=bool)
    goals[5, 5] = True
    next_state, outcome = model.table(walls, goals)
    heading_east = 10  # bin centre +9°
    state = (11 * 25 + 8) * 20 + heading_east
    assert outcome[state, 0] == PREDICT_COLLISION
    assert GRID.unflatten(int(next_state[state, 0]))[0] == 11
    assert outcome[state, 1] == PREDICT_FREE
    assert GRID.unflatten(int(next_state[state, 1]))[:2] == (10, 8)  # 3.8 cm back ≈ 1.5 cells
    into_goal = (4 * 25 + 5) * 20 + heading_east
    assert outcome[into_goal, 0] == PREDICT_GOAL
    wall_state = (12 * 25 + 3) * 20
    assert next_state[wall_state, 2] == wall_state
    assert outcome[wall_state, 2] == PREDICT_COLLISION


def test_a_prediction_with_corners_does_not_squeeze_between_two_walls() -> None:
    """A sub-step through the point where walls (12, 13) and (13, 12) meet, from cell (12, 12)
    into (13, 13): the simulator's rule lets it pass, the rule against corner cutting stops it
    before the corner."""
    model = KinematicModel(RobotParams(), GRID)
    walls = np.zeros((25, 25), dtype=bool)
    walls[12, 13] = walls[13, 12] = True
    goals = np.zeros_like(walls)
    corner_x, corner_y = 13 * 0.62 / 24, 13 * 0.505 / 24
    start = (corner_x - 0.001, corner_y - 0.001, math.atan2(1.0, 1.0))
    arguments = (model.velocities, walls, goals, model.robot.kernel_constants(), GRID.grid_shape())
    x, y, _, code = predict_action(*start, 0, *arguments, False)
    assert code == PREDICT_FREE and GRID.cell(x, y) == (14, 14)  # on through (13, 13)
    x, y, _, code = predict_action(*start, 0, *arguments, True)
    assert code == PREDICT_COLLISION and (x, y) == start[:2]


def test_turn_prediction_rotates_about_36_degrees_and_slides() -> None:
    model = KinematicModel(RobotParams(), GRID)
    (x, y, heading), code = model.predict((0.3, 0.25, 0.0), 2)
    assert code == PREDICT_FREE
    assert heading == pytest.approx(0.6375, rel=1e-6)
    assert math.hypot(x - 0.3, y - 0.25) == pytest.approx(0.032, abs=0.004)


def test_collision_wall_cell_guesses_the_wall_entered() -> None:
    task, grid_map = _open_task("thesis", 0)
    model = KinematicModel(RobotParams(), GRID)
    pose = np.array([0.1, 0.25, math.pi])  # facing the x = 0 border wall
    log = np.zeros((10, 6))
    rng = np.random.default_rng(0)
    for _ in range(5):
        if transition(task, pose, 0, 0.0, rng.random(20), log).collided:
            break
    else:
        pytest.fail("expected a collision with the border")
    kc, grid = RobotParams().kernel_constants(), GRID.grid_shape()
    wall = collision_wall_cell(pose[0], pose[1], pose[2], 0, model.velocities, kc, grid)
    assert wall == (0, GRID.cell(pose[0], pose[1])[1])
    assert grid_map.occupancy[wall]


def test_save_load_round_trip(tmp_path: object) -> None:
    model = KinematicModel(RobotParams(), GRID, KinematicModelConfig(refit_every=1, window=64))
    model.feed(_noise_free_log(np.random.default_rng(0), 100, 2, 0.03, 0.07, 0.01))
    model.refit()
    path = f"{tmp_path}/kin"
    save_model(model, path)
    loaded = load_model(path)
    assert loaded.config == model.config
    np.testing.assert_array_equal(loaded.coefficients, model.coefficients)
    np.testing.assert_array_equal(loaded.velocities, model.velocities)
    np.testing.assert_array_equal(loaded.data, model.data)
    assert loaded.refits == model.refits
    np.testing.assert_array_equal(loaded.table()[0], model.table()[0])
