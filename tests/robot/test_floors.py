"""The calibrated floors and the presets built from them (no MuJoCo needed)."""

import json

import numpy as np
import pytest

from skidnav.robot.floors import calibrated_floor, parse_floors
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import make_slip_field
from skidnav.sim.task import build_task, drive_substep
from skidnav.world.discretization import Discretization
from skidnav.world.grid import generate_map

ROBOT = RobotParams()


def test_rough_physics_is_the_rubber_mat_everywhere() -> None:
    field = make_slip_field("rough-physics", np.random.default_rng(0))
    rubber = calibrated_floor("rubber-mat")
    assert field.materials is not None and set(field.materials.flat) == {"rubber-mat"}
    assert np.all(field.eta == rubber.eta) and np.all(field.x_icr == rubber.x_icr)
    radius, track = rubber.scales()
    assert np.all(field.wheel_radius_scale == radius) and np.all(field.half_track_scale == track)
    assert 1.8 < track < 2.0  # the fit's c is ~1.9 times the geometric one


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_slippery_physics_has_wet_tile_on_the_patches_of_slippery(seed: int) -> None:
    hand_set = make_slip_field("slippery", np.random.default_rng(seed))
    calibrated = make_slip_field("slippery-physics", np.random.default_rng(seed))
    patches = hand_set.eta >= ROBOT.wheel_speed
    assert 3 <= patches.sum() <= 5
    assert calibrated.materials is not None
    assert np.array_equal(calibrated.materials == "wet-tile", patches)
    assert np.all(calibrated.eta[patches] == calibrated_floor("wet-tile").eta)
    assert np.all(calibrated.eta[~patches] == calibrated_floor("laminate").eta)


@pytest.mark.parametrize("commands", [(1.7, 1.7), (-1.7, 1.7)])
def test_a_calibrated_floor_moves_an_action_by_the_fits_mean_twist(
    commands: tuple[float, float],
) -> None:
    """At the mean wheel-speed loss (uniforms 0.5: η/2), one sub-step moves the robot by the
    fitted r·ω and turns it by r·ω/c, not by the geometric ICR model's."""
    task = build_task(
        generate_map("free", np.random.default_rng(0)),
        make_slip_field("rough-physics", np.random.default_rng(0)),
        ROBOT,
        Discretization(),
    )
    x, _, heading = drive_substep(task, (0.3, 0.25, 0.0), commands, 0.0, 0.5, 0.5)
    rubber = calibrated_floor("rubber-mat")
    forward = rubber.wheel_radius * (commands[0] + commands[1]) / 2
    yaw = rubber.wheel_radius * (commands[1] - commands[0]) / (2 * rubber.half_track)
    assert x - 0.3 == pytest.approx(forward * ROBOT.dt, abs=1e-12)
    assert heading == pytest.approx(yaw * ROBOT.dt, rel=1e-9)
    if yaw:
        geometric = ROBOT.wheel_radius * 1.7 / ROBOT.half_track
        assert yaw < 0.55 * geometric  # the calibrated floor turns at about half the ICR rate


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("not json", "Expecting value"),
        ('{"fits": [{"material": "x"}]}', "missing 'wheel_radius'"),
        (
            '{"fits": [{"material": "x", "wheel_radius": 0.02, "half_track": -1,'
            ' "x_icr": 0, "eta": 0.1}]}',
            "x: expected finite r, c > 0 and eta >= 0",
        ),
        ('{"seed": 0}', "missing 'fits'"),
    ],
)
def test_a_broken_floors_document_is_one_line(text: str, message: str) -> None:
    with pytest.raises(ValueError, match=message) as error:
        parse_floors(text)
    assert "\n" not in str(error.value)


def test_a_material_calibrated_twice_is_refused() -> None:
    fit = {"material": "x", "wheel_radius": 0.02, "half_track": 0.1, "x_icr": 0.0, "eta": 0.1}
    with pytest.raises(ValueError, match="x: calibrated twice"):
        parse_floors(json.dumps({"fits": [fit, fit]}))
