"""The tanh policy: shapes, bounds, one forward for batches and single observations, saved files."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium
import numpy as np
import pytest

import skidnav  # noqa: F401  (registers the env)
from skidnav.agents.policies.search.policy_file import load_policy, save_policy
from skidnav.agents.policies.search.tanh_policy import PolicyLayout, TanhPolicy, parameter_count
from skidnav.agents.saved import load_policy as load_any_policy
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.errors import CorruptFileError, UserError
from tests.saved_file_support import arrays_of, write_npz

RAYS = 8


@pytest.fixture(scope="module")
def layout() -> PolicyLayout:
    env = gymnasium.make(
        "skidnav/SkidSteerNav-v0", action="continuous", observation="features", lidar_rays=RAYS
    )
    space = env.observation_space
    assert isinstance(space, gymnasium.spaces.Box)
    return PolicyLayout(space.low, space.high, hidden=5, wheel_speed=1.7, lidar_rays=RAYS)


def random_policy(layout: PolicyLayout, seed: int = 0, scale: float = 1.0) -> TanhPolicy:
    rng = np.random.default_rng(seed)
    return TanhPolicy(layout, scale * rng.standard_normal(layout.n_parameters))


def observations(layout: PolicyLayout, shape: tuple[int, ...], seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    low, high = layout.observation_low, layout.observation_high
    return np.asarray(low + (high - low) * rng.random((*shape, layout.n_inputs)))


def test_the_parameter_count_is_that_of_the_layers(layout: PolicyLayout) -> None:
    d = 7 + RAYS
    assert layout.n_parameters == 5 * d + 5 + 2 * 5 + 2 == parameter_count(d, 5)
    linear = PolicyLayout(layout.observation_low, layout.observation_high, 0, 1.7, RAYS)
    assert linear.n_parameters == 2 * d + 2


def test_forward_shapes_and_wheel_speed_bounds(layout: PolicyLayout) -> None:
    rng = np.random.default_rng(2)
    parameters = 50.0 * rng.standard_normal((3, layout.n_parameters))  # saturating weights
    speeds = layout.forward(parameters, observations(layout, (3, 4)))
    assert speeds.shape == (3, 4, 2) and speeds.dtype == np.float64
    assert np.all(np.abs(speeds) <= 1.7) and np.abs(speeds).max() > 1.6
    still = TanhPolicy(layout, np.zeros(layout.n_parameters))
    assert still.wheel_speeds(observations(layout, ())) == (0.0, 0.0)
    with pytest.raises(ValueError, match="expected observations of shape"):
        layout.forward(parameters, observations(layout, (2, 4)))


def test_population_rows_single_calls_and_the_protocol_agree(layout: PolicyLayout) -> None:
    policies = [random_policy(layout, seed) for seed in range(3)]
    batch = observations(layout, (3, 6))
    together = layout.forward(np.array([p.parameters for p in policies]), batch)
    for k, policy in enumerate(policies):
        assert isinstance(policy, WheelSpeedPolicy)
        np.testing.assert_array_equal(policy.batch_wheel_speeds(batch[k]), together[k])
        single = np.array([policy.wheel_speeds(row) for row in batch[k]])
        np.testing.assert_array_equal(single, together[k])


def test_inputs_are_scaled_to_the_unit_box(layout: PolicyLayout) -> None:
    corners = np.stack(
        [layout.observation_low, layout.observation_high, 2 * layout.observation_high]
    )
    np.testing.assert_allclose(layout.scaled(corners), [[-1.0] * 15, [1.0] * 15, [1.0] * 15])


def test_bad_layouts_and_parameters_are_refused(layout: PolicyLayout) -> None:
    low, high = layout.observation_low, layout.observation_high
    with pytest.raises(ValueError, match="observation bounds of shape"):
        PolicyLayout(low[:-1], high[:-1], 5, 1.7, RAYS)
    with pytest.raises(ValueError, match="high > low"):
        PolicyLayout(high, low, 5, 1.7, RAYS)
    with pytest.raises(ValueError, match="hidden"):
        PolicyLayout(low, high, -1, 1.7, RAYS)
    with pytest.raises(ValueError, match="wheel_speed"):
        PolicyLayout(low, high, 5, float("nan"), RAYS)
    with pytest.raises(ValueError, match="finite parameters"):
        TanhPolicy(layout, np.full(layout.n_parameters, np.inf))
    with pytest.raises(ValueError, match="finite parameters"):
        TanhPolicy(layout, np.zeros(3))


def test_a_saved_policy_loads_back_the_same(layout: PolicyLayout, tmp_path: Path) -> None:
    policy = random_policy(layout, 4)
    npz_path, json_path = save_policy(policy, tmp_path / "policy.npz", {"generation": 3})
    assert (npz_path.name, json_path.name) == ("policy.npz", "policy.json")
    loaded = load_policy(tmp_path / "policy")
    assert loaded.layout.same_as(layout)
    np.testing.assert_array_equal(loaded.parameters, policy.parameters)
    batch = observations(layout, (7,))
    np.testing.assert_array_equal(
        loaded.batch_wheel_speeds(batch), policy.batch_wheel_speeds(batch)
    )
    assert json.loads(json_path.read_text())["provenance"] == {"generation": 3}


def _edit_json(path: Path, **changes: object) -> None:
    meta = json.loads(path.read_text())
    meta.update(changes)
    path.write_text(json.dumps(meta))


@pytest.mark.parametrize(
    ("damage", "message"),
    [
        (lambda base: _edit_json(base / "p.json", format="skidnav-agent"), "not a skidnav tanh"),
        (lambda base: _edit_json(base / "p.json", hidden=10**9), "expected hidden"),
        (lambda base: _edit_json(base / "p.json", hidden=4), "n_parameters 92 does not fit"),
        (lambda base: _edit_json(base / "p.json", wheel_speed=-1.0), "wheel_speed"),
        (lambda base: _edit_json(base / "p.json", wheel_speed="fast"), "wheel_speed"),
        (lambda base: _edit_json(base / "p.json", wheel_speed=10**400), "wheel_speed to be a"),
        (lambda base: _edit_json(base / "p.json", lidar_range=10**400), "lidar_range to be a"),
        (lambda base: (base / "p.json").write_text("{"), "invalid JSON"),
        (lambda base: (base / "p.npz").unlink(), "no such file"),
        (lambda base: (base / "p.npz").write_bytes(b"PK\x03\x04 cut"), "not a readable .npz"),
    ],
)
def test_damaged_policy_files_are_refused_in_one_line(
    layout: PolicyLayout, tmp_path: Path, damage: object, message: str
) -> None:
    save_policy(random_policy(layout), tmp_path / "p")
    damage(tmp_path)  # type: ignore[operator]
    with pytest.raises(CorruptFileError, match=message) as caught:
        load_policy(tmp_path / "p")
    assert "\n" not in str(caught.value) and str(tmp_path) in str(caught.value)


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("parameters", np.zeros(92, dtype=np.float32), "array 'parameters' is float32"),
        ("parameters", np.zeros(91), r"array 'parameters' is float64 of shape \(91,\)"),
        ("parameters", np.full(92, np.nan), "NaN or not below 1e\\+32"),
        ("observation_high", np.zeros(15), "high > low"),
        ("extra", np.zeros(2), "unexpected array 'extra'"),
    ],
)
def test_policy_archives_that_do_not_fit_are_refused(
    layout: PolicyLayout, tmp_path: Path, name: str, value: np.ndarray, message: str
) -> None:
    save_policy(random_policy(layout), tmp_path / "p")
    members = arrays_of(tmp_path / "p.npz")
    members[name] = value
    write_npz(tmp_path / "p.npz", members)
    with pytest.raises(CorruptFileError, match=message):
        load_policy(tmp_path / "p")


def test_a_huge_integer_in_a_policy_file_is_one_line_for_robot_run(
    layout: PolicyLayout, tmp_path: Path
) -> None:
    """``skidnav robot run --policy-file`` loads through the registry of policy formats: a
    400-digit wheel speed is one line there too (it was an OverflowError)."""
    save_policy(random_policy(layout), tmp_path / "p")
    _edit_json(tmp_path / "p.json", wheel_speed=10**400)
    with pytest.raises(UserError, match="expected wheel_speed to be a finite number > 0"):
        load_any_policy(tmp_path / "p.json")
