"""The step info: one typed record under a documented key, the same fields under their own keys."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

import skidnav  # noqa: F401  (registers the env)
from skidnav.envs.step_info import STEP_INFO_KEY, StepInfo, step_info


def test_the_documented_keys_are_the_record_fields_with_the_same_values() -> None:
    env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="obstacles", world_seed=2)
    infos = [env.reset(seed=0)[1]]
    infos += [env.step(action)[4] for action in (0, 2, 0, 0, 3, 1)]
    for info in infos:
        record = info[STEP_INFO_KEY]
        assert isinstance(record, StepInfo)
        assert list(info) == [*StepInfo._fields, STEP_INFO_KEY]
        for name in StepInfo._fields:
            assert info[name] is getattr(record, name)
        assert [type(v) for v in record.pose] == [float] * 3
        assert type(record.collision) is bool and type(record.region) is int
        assert record.kinematic_log.dtype == np.float64 and record.kinematic_log.shape[1] == 6
    assert infos[0]["kinematic_log"].shape == (0, 6)  # reset: nothing moved yet


def test_each_step_gets_its_own_log() -> None:
    env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="free", world_seed=1)
    env.reset(seed=0)
    first = env.step(0)[4]["kinematic_log"]
    kept = first.copy()
    env.step(2)
    assert np.array_equal(first, kept)


def test_step_info_converts_numbers_to_python_types() -> None:
    info = step_info(
        np.array([0.1, 0.2, 3.0]), (1, 2, 3), np.bool_(True), (np.float64(1.5), 1), np.int64(4),
        np.zeros((0, 6)),
    )  # fmt: skip
    record = info[STEP_INFO_KEY]
    assert record.pose == (0.1, 0.2, 3.0) and type(record.pose[0]) is float
    assert record.collision is True and type(record.region) is int
    assert record.wheel_speeds == (1.5, 1.0) and type(record.wheel_speeds[1]) is float


@pytest.mark.parametrize("action", [np.int64(2), np.array(1), True])
def test_integer_actions_of_any_kind_are_accepted(action: object) -> None:
    env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="free", world_seed=1).unwrapped
    env.reset(seed=0)
    reference = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="free", world_seed=1).unwrapped
    reference.reset(seed=0)
    assert env.step(action)[4]["pose"] == reference.step(int(action))[4]["pose"]  # type: ignore[call-overload]


@pytest.mark.parametrize("action", [4, -1, 1.0, "0", None])
def test_other_actions_are_refused(action: object) -> None:
    env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="free", world_seed=1).unwrapped
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"expected an action in 0\.\.3"):
        env.step(action)
