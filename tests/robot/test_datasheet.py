"""The datasheet is every kinematic learner's prior, and the floors move the truth away from it by
what the calibration measured: turns at about half the datasheet's rate on the physical floors."""

from __future__ import annotations

import numpy as np
import pytest

import skidnav
from skidnav.commands.floors import prior_gap_rows
from skidnav.models.kinematic_regression import nominal_coefficients
from skidnav.robot.datasheet import Datasheet, floor_gap, material_gap
from skidnav.robot.floors import CALIBRATED_PRESETS, PRESET_FLOORS
from skidnav.robot.params import RobotParams


def test_the_hand_set_floors_are_near_the_datasheet() -> None:
    for preset, loss in [("thesis", 0.01), ("rough", 0.03)]:
        gap = floor_gap(preset)
        assert 1 - loss <= gap.forward <= 1 and gap.turn == pytest.approx(gap.forward)
        assert gap.x_icr == pytest.approx(RobotParams().x_icr)
    slippery = floor_gap("slippery")
    assert 0.8 < slippery.forward < 0.95 and 0 < slippery.x_icr < RobotParams().x_icr


@pytest.mark.parametrize("preset", [p for p in sorted(CALIBRATED_PRESETS) if p != "ice-physics"])
def test_the_physical_floors_turn_at_half_the_datasheet_rate(preset: str) -> None:
    gap = floor_gap(preset)
    assert 0.95 < gap.forward < 1.0 and 0.45 < gap.turn < 0.6 and abs(gap.x_icr) < 1e-3
    floor_material = PRESET_FLOORS[preset][0]  # the preset's floor, away from its patches
    mujoco = material_gap(floor_material)
    if PRESET_FLOORS[preset][1] is None:  # one material everywhere: the preset is its fit
        assert gap == pytest.approx(mujoco, rel=1e-9, abs=1e-12)
    assert mujoco.turn == pytest.approx(gap.turn, rel=0.05)


def test_the_table_has_every_floor_of_both_robots() -> None:
    rows = prior_gap_rows()
    presets = list(skidnav.robot.SLIP_PRESETS)
    assert [row[0] for row in rows][: len(presets)] == presets
    assert {row[1] for row in rows} == {"kinematic simulator", "MuJoCo robot"}


@pytest.mark.parametrize("slip", ["rough-physics", "slippery"])
def test_every_kinematic_learner_starts_from_the_datasheet_not_the_floor(slip: str) -> None:
    """Made on a floor whose truth differs, each learner's model is the datasheet's robot without
    slip until it has driven: nothing of the floor reaches it."""
    prior = nominal_coefficients(RobotParams(**vars(Datasheet.of(RobotParams()))))
    discrete = skidnav.make_env("obstacles", seed=3, slip=slip)
    wheels = skidnav.make_env(
        "obstacles", seed=3, slip=slip, observation="pose", action="continuous"
    )
    features = skidnav.make_env("obstacles", seed=3, slip=slip, observation="features")
    models = [
        skidnav.make_agent("dyna-full", discrete).kinematic,
        skidnav.make_agent("linear-dyna-kinematic", features).kinematic,
        skidnav.make_agent("mppi-kinematic", wheels).model,
    ]
    truth = discrete.unwrapped.true_kinematics
    for model in models:
        np.testing.assert_array_equal(
            model.coefficients, np.tile(prior, (len(model.coefficients), 1))
        )
        assert not np.allclose(model.velocities[:, :, :], truth, rtol=0.02)
