"""``skidnav.train``'s callback, progress bar and compile notice: a callback hears of every
episode (the compiled tabular trainer's, the plain loop's, Stable-Baselines3's), stops training
when it returns False or raises StopTraining, and changes no number when it does not."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numba
import numpy as np
import pytest

import skidnav
from skidnav import _jit
from skidnav.agents.training import TrainingLog
from skidnav.errors import UserError


def _same(first: TrainingLog, second: TrainingLog) -> None:
    """Every field equal but the wall time."""
    for name in TrainingLog._fields:
        if name != "wall_time":
            np.testing.assert_array_equal(getattr(first, name), getattr(second, name), name)


@pytest.mark.parametrize(
    ("name", "observation"), [("dyna-q", "discrete"), ("linear-q", "features")]
)
def test_a_callback_that_never_stops_changes_nothing_and_hears_every_episode(
    name: str, observation: str, capsys: pytest.CaptureFixture[str]
) -> None:
    env = skidnav.make_env("free", seed=1, observation=observation, max_episode_steps=60)

    def run(**listen: Any) -> TrainingLog:
        agent = skidnav.make_agent(name, env, seed=3)
        return skidnav.train(agent, env, 6, seed=3, rollouts=2, **listen)

    heard: list[skidnav.EpisodeInfo] = []
    quiet, listened = run(), run(callback=heard.append, progress=True)
    _same(quiet, listened)
    assert [info.episode for info in heard] == [1, 2, 3, 4, 5, 6]
    assert [info.length for info in heard] == listened.lengths.tolist()
    assert [info.success for info in heard] == listened.successes.tolist()
    np.testing.assert_array_equal([info.total for info in heard], listened.returns)
    assert [info.wall_time for info in heard] == listened.wall_time.tolist()
    elapsed = [info.elapsed for info in heard]
    assert elapsed == sorted(elapsed) and elapsed[0] > 0
    seconds = env.unwrapped.robot.action_duration
    assert [info.driving for info in heard] == [n * seconds for n in listened.lengths]
    assert "6/6" in capsys.readouterr().err  # the progress bar, on stderr


def test_returning_false_or_raising_stop_training_ends_training_after_that_episode() -> None:
    env = skidnav.make_env("free", seed=1, max_episode_steps=60)
    full = skidnav.train(skidnav.make_agent("q-learning", env), env, 5, rollouts=1)

    def stop_after(n: int, how: str) -> Any:
        def callback(info: skidnav.EpisodeInfo) -> bool:
            if info.episode == n and how == "raise":
                raise skidnav.StopTraining
            return info.episode < n

        return callback

    for n, how in [(2, "return"), (3, "raise"), (1, "return")]:
        agent = skidnav.make_agent("q-learning", env)
        log = skidnav.train(agent, env, 5, rollouts=1, callback=stop_after(n, how))
        assert len(log.returns) == n and log.greedy_lengths.shape == (n, 1)
        _same(log, TrainingLog(*(np.asarray(column)[:n] for column in full)))


def test_a_deep_agent_stops_where_its_callback_says() -> None:
    pytest.importorskip("stable_baselines3")
    env = skidnav.make_env("free", seed=1, observation="pose", max_episode_steps=5)
    agent = skidnav.make_agent("dqn", env, seed=0, learning_starts=1, batch_size=4)
    log = skidnav.train(agent, env, 6, rollouts=1, callback=lambda info: info.episode < 2)
    assert len(log.lengths) == 2 and agent.episodes == 2
    assert len(skidnav.train(agent, env, 3, rollouts=1).lengths) == 3  # it goes on after


def test_callback_and_progress_are_checked_in_one_line() -> None:
    env = skidnav.make_env("free", seed=1, max_episode_steps=5)
    agent = skidnav.make_agent("q-learning", env)
    for argument, value, message in [
        ("callback", 3, "train: expected callback to be a function of an episode's info or None"),
        ("progress", "yes", "train: expected progress to be true or false, got 'yes'"),
    ]:
        with pytest.raises(UserError) as refused:
            skidnav.train(agent, env, 1, **{argument: value})
        assert message in str(refused.value) and "\n" not in str(refused.value)


def test_the_compile_notice_is_for_kernels_neither_compiled_nor_cached(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    def double(x: float) -> float:
        return 2 * x

    double.__module__ = "probe.kernels"
    # an empty cache of its own: the user's cache may hold this probe from an earlier run
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    kernel = numba.njit(cache=True)(double)
    if not hasattr(kernel, "signatures"):
        pytest.skip("NUMBA_DISABLE_JIT: nothing compiles")
    assert Path(kernel._cache._cache_file._index_path).is_relative_to(tmp_path)
    monkeypatch.setattr(_jit, "KERNELS", [kernel])
    assert _jit.first_compile(("probe",)) and not _jit.first_compile(("elsewhere",))
    assert kernel(1.5) == 3.0
    assert not _jit.first_compile(("probe",))  # compiled now


def test_train_says_when_it_will_compile(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import skidnav.api

    env = skidnav.make_env("free", seed=1, max_episode_steps=5)
    agent = skidnav.make_agent("q-learning", env)
    for cold in (True, False):
        monkeypatch.setattr(skidnav.api, "first_compile", lambda packages, cold=cold: cold)
        skidnav.train(agent, env, 1, rollouts=1)
        said = capsys.readouterr().err
        assert ("compiling (first run only)…" in said) == cold
    assert not math.isnan(env.unwrapped.robot.action_duration)
