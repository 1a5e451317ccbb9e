"""Hostile calls of the Python API (:mod:`skidnav.api`): each ends within a second in one
:class:`~skidnav.errors.UserError` line naming the function and the argument — never a hang,
a MemoryError, a silent default or another exception. The limits are the experiment config's
(:mod:`skidnav.experiments.limits`), so a value the config refuses the API refuses too."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import skidnav
from skidnav.errors import UserError
from skidnav.experiments.limits import SETTINGS
from tests.saved_file_support import within

SECONDS = 1.0
"""Longest a refused call may take."""
NAN, INF = math.nan, math.inf


@pytest.fixture(scope="module")
def world() -> dict[str, Any]:
    """A small env, a q-learning agent for it and a two-episode training log."""
    env = skidnav.make_env("free", seed=1, max_episode_steps=5)
    agent = skidnav.make_agent("q-learning", env, seed=0)
    log = skidnav.train(agent, env, 2, rollouts=1)
    return {"env": env, "agent": agent, "log": log}


def _calls(world: dict[str, Any]) -> dict[str, tuple[Callable[..., Any], dict[str, Any]]]:
    """Each public function with valid arguments (a hostile case replaces one of them)."""
    env, agent = world["env"], world["agent"]
    return {
        "make_env": (skidnav.make_env, {"map": "free", "slip": "thesis", "seed": 0}),
        "make_agent": (skidnav.make_agent, {"name": "q-learning", "env": env, "seed": 0}),
        "train": (
            skidnav.train,
            {"agent": agent, "env": env, "episodes": 1, "seed": 0, "max_steps": 3, "rollouts": 1},
        ),
        "evaluate": (
            skidnav.evaluate,
            {"agent": agent, "env": env, "rollouts": 1, "seed": 0, "max_steps": 3},
        ),
        "save_agent": (skidnav.save_agent, {"agent": agent, "path": "unused"}),
        "load_agent": (skidnav.load_agent, {"path": "unused", "env": None}),
        "convergence_episode": (
            skidnav.convergence_episode,
            {"log": world["log"], "env": env, "tolerance": 0.1, "window": 1, "level": 0.9},
        ),
        "reference_length": (skidnav.reference_length, {"env": env}),
        "run_config": (skidnav.run_config, {"config": "unused.toml", "out": None}),
    }


def _refused(world: dict[str, Any], function: str, argument: str, value: object) -> str:
    """Call ``function`` with ``argument`` replaced by ``value``; its one-line message."""
    call, arguments = _calls(world)[function]
    with pytest.raises(UserError) as refused, within(SECONDS):
        call(**{**arguments, argument: value})
    message = str(refused.value)
    assert "\n" not in message, message
    assert message.startswith((f"{function}: ", "unknown agent")), message
    return message


CATALOG: list[tuple[str, str, object, str]] = [
    # function, argument, value, what the message says
    ("train", "episodes", 10**12, "expected episodes to be an integer in [1, 10000000]"),
    ("train", "episodes", 2**63, "expected episodes to be an integer in [1, 10000000]"),
    ("train", "episodes", 0, "expected episodes to be an integer in [1, 10000000], got 0"),
    ("train", "episodes", 2.0, "expected episodes to be an integer"),
    ("train", "max_steps", NAN, "expected max_steps to be an integer in [1, 1000000], got nan"),
    ("train", "max_steps", 2.5, "expected max_steps to be an integer in [1, 1000000], got 2.5"),
    ("train", "max_steps", 10**12, "expected max_steps to be an integer in [1, 1000000]"),
    ("train", "max_steps", 0, "expected max_steps to be an integer in [1, 1000000], got 0"),
    ("train", "rollouts", 10**9, "expected rollouts to be an integer in [1, 100]"),
    ("train", "seed", -1, "expected seed to be an integer in [0, 9223372036854775807], got -1"),
    ("train", "agent", "q-learning", "expected agent to be an agent (skidnav.make_agent)"),
    ("train", "env", None, "expected env to be a Gymnasium env (skidnav.make_env), got None"),
    ("train", "eval_env", "free", "expected eval_env to be a Gymnasium env or None"),
    ("train", "callback", 3, "expected callback to be a function of an episode's info or None"),
    ("train", "progress", 1, "expected progress to be true or false, got 1"),
    ("evaluate", "rollouts", 10**9, "expected rollouts to be an integer in [1, 100]"),
    ("evaluate", "max_steps", 0, "expected max_steps to be an integer in [1, 1000000], got 0"),
    ("evaluate", "seed", None, "expected seed to be an integer in [0, 9223372036854775807]"),
    ("evaluate", "agent", None, "expected agent to be an agent"),
    ("evaluate", "env", "free", "expected env to be a Gymnasium env"),
    ("convergence_episode", "tolerance", NAN, "expected tolerance to be a number in"),
    ("convergence_episode", "tolerance", -0.1, "expected tolerance to be a number in"),
    ("convergence_episode", "level", NAN, "expected level to be a number in [1e-06, 1.0]"),
    ("convergence_episode", "level", -1.0, "expected level to be a number in [1e-06, 1.0]"),
    ("convergence_episode", "window", 0, "expected window to be an integer in [1, 10000]"),
    ("convergence_episode", "log", [1, 2], "expected log to be a training log (skidnav.train)"),
    ("convergence_episode", "env", None, "expected a skidnav/SkidSteerNav-v0 env on kinematic"),
    ("reference_length", "env", "free", "expected a skidnav/SkidSteerNav-v0 env on kinematic"),
    ("make_env", "map", None, "expected map to be a map kind or a map file's path, got None"),
    ("make_env", "map", 3, "expected map to be a map kind or a map file's path, got 3"),
    ("make_env", "seed", None, "expected seed to be an integer in [0, 9223372036854775807]"),
    ("make_env", "seed", True, "expected seed to be an integer in [0, 9223372036854775807]"),
    ("make_env", "seed", 2**64, "expected seed to be an integer in [0, 9223372036854775807]"),
    ("make_env", "slip", 3, "expected slip to be a slip preset's name, got 3"),
    ("make_env", "observation", None, "expected observation to be an observation's name"),
    ("make_agent", "name", None, "expected name to be an agent's name"),
    ("make_agent", "env", "free", "expected env to be a Gymnasium env"),
    ("make_agent", "seed", None, "expected seed to be an integer in [0, 9223372036854775807]"),
    ("save_agent", "agent", "q-learning", "expected agent to be an agent"),
    ("save_agent", "path", None, "expected path to be a path, got None"),
    ("save_agent", "path", 3, "expected path to be a path, got 3"),
    ("load_agent", "path", None, "expected path to be a path or a pair of paths, got None"),
    ("load_agent", "path", [1, 2], "expected path to be a path or a pair of paths"),
    ("load_agent", "env", "free", "expected env to be a Gymnasium env or None"),
    ("run_config", "config", None, "expected config to be a config file's path, got None"),
    ("run_config", "out", 3, "expected out to be a folder's path or None, got 3"),
]


@pytest.mark.parametrize(("function", "argument", "value", "message"), CATALOG)
def test_each_hostile_call_is_one_line_naming_the_argument(
    world: dict[str, Any], function: str, argument: str, value: object, message: str
) -> None:
    assert message in _refused(world, function, argument, value)


@pytest.mark.parametrize(
    ("param", "value", "message"),
    [
        ("alpha", True, "expected alpha to be a number, got True"),
        ("alpha", "0.5", "expected alpha to be a number, got '0.5'"),
        ("alpha", NAN, "expected alpha in (0, 1], got nan"),
        ("epsilon", None, "expected epsilon to be a number, got None"),
        ("planning_steps", 2.5, "expected an integer planning_steps in [0, 10,000,000], got 2.5"),
    ],
)
def test_agent_hyperparameters_take_their_own_type(
    world: dict[str, Any], param: str, value: object, message: str
) -> None:
    name = "dyna-q" if param == "planning_steps" else "q-learning"
    with pytest.raises(UserError) as refused, within(SECONDS):
        skidnav.make_agent(name, world["env"], **{param: value})
    text = str(refused.value)
    assert text == f"{message} in agent {name!r}"


def test_an_unknown_env_option_is_named_without_the_envs_arguments() -> None:
    with pytest.raises(UserError) as refused, within(SECONDS):
        skidnav.make_env("free", bogus=1)
    assert str(refused.value) == (
        "make_env: SkidSteerNavEnv.__init__() got an unexpected keyword argument 'bogus'"
    )


def test_train_no_longer_ignores_a_zero_action_limit(world: dict[str, Any]) -> None:
    """``max_steps=0`` was taken as "the env's limit"; now it is refused (and None is the
    env's limit, as documented)."""
    log = skidnav.train(world["agent"], world["env"], 1, rollouts=1, max_steps=None)
    assert len(log.lengths) == 1
    assert "max_steps" in _refused(world, "train", "max_steps", 0)


def _outside(name: str) -> st.SearchStrategy[object]:
    """Values the setting ``name`` (:data:`SETTINGS`) refuses: out of range, of another type,
    NaN or infinite, a bool, None, text."""
    limit = SETTINGS[name]
    numbers = st.one_of(
        st.integers(max_value=math.ceil(limit.low) - 1),
        st.integers(min_value=int(limit.high) + 1),
        st.floats().filter(lambda x: not limit.low <= x <= limit.high),
    )
    if limit.integer:
        numbers = st.one_of(numbers, st.floats().filter(lambda x: not x.is_integer()))
        numbers = st.one_of(numbers, st.floats(allow_nan=False, allow_infinity=False))
    return st.one_of(numbers, st.booleans(), st.none(), st.text(max_size=5), st.lists(st.none()))


HOSTILE = {
    ("train", "episodes"): "episodes",
    ("train", "max_steps"): "max_steps",
    ("train", "rollouts"): "eval_rollouts",
    ("train", "seed"): "root_seed",
    ("evaluate", "rollouts"): "eval_rollouts",
    ("evaluate", "max_steps"): "max_steps",
    ("evaluate", "seed"): "root_seed",
    ("make_env", "seed"): "root_seed",
    ("make_agent", "seed"): "root_seed",
    ("convergence_episode", "tolerance"): "convergence_tolerance",
    ("convergence_episode", "window"): "convergence_window",
    ("convergence_episode", "level"): "convergence_level",
}
"""Every numeric argument of the API and the setting whose limit it shares."""
ALLOWED_NONE = {("train", "seed"), ("train", "max_steps"), ("evaluate", "max_steps")}
"""Arguments whose None means a default (the env's generator, the env's limit)."""
PROPERTY = settings(
    max_examples=40,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


@pytest.mark.parametrize(("function", "argument"), sorted(HOSTILE))
def test_property_any_value_outside_a_limit_is_refused_in_time(
    world: dict[str, Any], function: str, argument: str
) -> None:
    name = HOSTILE[(function, argument)]
    wanted = f"expected {argument} to be"

    @PROPERTY
    @given(_outside(name))
    def refused(value: object) -> None:
        if value is None and (function, argument) in ALLOWED_NONE:
            return
        limit = SETTINGS[name]
        number = isinstance(value, int | float) and not isinstance(value, bool)
        integral = isinstance(value, int) or not limit.integer
        if number and integral and limit.low <= value <= limit.high:  # type: ignore[operator]
            return  # a float within the range of a number setting: valid
        assert wanted in _refused(world, function, argument, value)

    refused()


def test_a_path_argument_refused_writes_nothing(world: dict[str, Any], tmp_path: Path) -> None:
    before = sorted(tmp_path.iterdir())
    _refused(world, "save_agent", "path", [tmp_path / "a"])
    assert sorted(tmp_path.iterdir()) == before


NOT_AN_OBJECT_OF_THE_API = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(),
    st.floats(),
    st.binary(max_size=5),
    st.lists(st.integers(), max_size=3),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
)
"""Values that are no env, agent, training log, name or path."""
TYPED = [
    ("make_env", "map"),
    ("make_agent", "name"),
    ("make_agent", "env"),
    ("train", "agent"),
    ("train", "env"),
    ("evaluate", "agent"),
    ("evaluate", "env"),
    ("save_agent", "agent"),
    ("save_agent", "path"),
    ("load_agent", "path"),
    ("convergence_episode", "log"),
    ("convergence_episode", "env"),
    ("reference_length", "env"),
    ("run_config", "config"),
]
"""Every argument of the API that takes an object, a name or a path."""


@pytest.mark.parametrize(("function", "argument"), TYPED)
def test_property_any_value_of_another_type_is_refused_in_time(
    world: dict[str, Any], function: str, argument: str
) -> None:
    @PROPERTY
    @given(NOT_AN_OBJECT_OF_THE_API)
    def refused(value: object) -> None:
        _refused(world, function, argument, value)

    refused()
