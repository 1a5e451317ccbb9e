"""CMA-ES policy search: it improves the policy, the same seed gives the same numbers, common
random numbers, batch rollouts equal single-env episodes, and checkpoints resume exactly."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import pytest
from cmaes import CMA

import skidnav  # noqa: F401  (registers the env)
from skidnav.errors import CorruptFileError, UserError
from skidnav.policysearch.config import SearchConfig
from skidnav.policysearch.policy import TanhPolicy
from skidnav.policysearch.rollouts import PopulationRollouts
from skidnav.policysearch.search import (
    GenerationRecord,
    SearchResult,
    generation_seeds,
    run_search,
)
from tests.saved_file_support import arrays_of, write_npz

TINY = SearchConfig(
    map_kind="free", world_seed=3, max_episode_steps=30, hidden=0, population=16, sigma0=0.5,
    progress_weight=30.0, episodes_per_candidate=2, eval_episodes=4, eval_every=5,
    generations=15, seed=0,
)  # fmt: skip
"""A goal about 7 actions from the start, 30 actions per episode, a linear policy."""


def without_clock(records: tuple[GenerationRecord, ...]) -> list[tuple[Any, ...]]:
    """The records without their wall time, NaN as None (NaN ≠ NaN)."""
    return [
        tuple(
            None if isinstance(v, float) and math.isnan(v) else v for v in record[:3] + record[4:]
        )
        for record in records
    ]


@pytest.fixture(scope="module")
def tiny_result() -> SearchResult:
    return run_search(TINY)


def test_cma_es_finds_a_policy_that_reaches_the_goal(tiny_result: SearchResult) -> None:
    first, last = tiny_result.records[0], tiny_result.records[-1]
    assert first.mean_success == 0.0 and first.mean_return == pytest.approx(-30.0, abs=0.1)
    assert last.mean_success >= 0.75
    assert last.mean_return >= first.mean_return + 20.0
    assert last.episodes == 15 * 16 * 2 and last.evaluation_episodes == 4 * 4
    assert len(tiny_result.records) == 16


def test_the_same_budget_with_the_ranking_inverted_does_not(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The control of the test above: an optimiser told the scores with the wrong sign (a broken
    search) spends the same budget and never reaches the goal."""
    tell = CMA.tell

    def inverted(self: CMA, solutions: list[tuple[np.ndarray, float]]) -> None:
        tell(self, [(x, -value) for x, value in solutions])

    monkeypatch.setattr(CMA, "tell", inverted)
    last = run_search(TINY).records[-1]
    assert last.mean_success == 0.0 and last.mean_return < -29.0


def test_the_same_seed_gives_the_same_search(tiny_result: SearchResult) -> None:
    short = dataclasses.replace(TINY, generations=6)
    again = run_search(short)  # the same but for the evaluation after the last generation
    assert without_clock(again.records[:6]) == without_clock(tiny_result.records[:6])
    other = run_search(dataclasses.replace(short, seed=1))
    assert without_clock(other.records) != without_clock(again.records)


def test_every_candidate_meets_the_same_episodes() -> None:
    config = dataclasses.replace(TINY, slip="slippery", population=3)
    rollouts = PopulationRollouts(3, 2, config.env_options())
    layout = rollouts.layout(0)
    forward = np.zeros(layout.n_parameters)
    forward[-2:] = 1.0  # biases only: both wheels at 1.7·tanh(1) whatever the observation
    batch = rollouts.run(layout, np.array([forward, forward, np.zeros_like(forward)]), [7, 8])
    np.testing.assert_array_equal(batch.returns[0], batch.returns[1])
    np.testing.assert_array_equal(batch.progress[0], batch.progress[1])
    assert batch.progress[0, 0] != batch.progress[0, 1]  # two seeds, two slip noises
    assert generation_seeds(config, 1) != generation_seeds(config, 2)
    rollouts.close()


def single_episode(
    policy: TanhPolicy, config: SearchConfig, seed: int
) -> tuple[float, int, bool, float]:
    """(return, length, goal reached, goal distance gained [m]) of one episode in one env, the
    policy asked one observation at a time through the WheelSpeedPolicy contract."""
    env = gymnasium.make("skidnav/SkidSteerNav-v0", **config.env_options())
    observation, _ = env.reset(seed=seed)
    start_distance = observation[4]
    total, length = 0.0, 0
    while True:
        action = np.array(policy.wheel_speeds(observation), dtype=np.float32)
        observation, reward, terminated, truncated, _ = env.step(action)
        total, length = total + float(reward), length + 1
        if terminated or truncated:
            return total, length, bool(terminated), start_distance - observation[4]


def test_batch_episodes_are_those_of_one_env_each(tiny_result: SearchResult) -> None:
    """Masking and autoreset: each sub-env's episode equals the same policy's episode alone."""
    config = dataclasses.replace(TINY, slip="slippery")
    trained = tiny_result.policy
    rng = np.random.default_rng(5)
    noisy = TanhPolicy(trained.layout, trained.parameters + 0.3 * rng.standard_normal(32))
    rollouts = PopulationRollouts(2, 2, config.env_options())
    batch = rollouts.run(trained.layout, np.array([trained.parameters, noisy.parameters]), [11, 12])
    rollouts.close()
    assert batch.lengths.min() < batch.lengths.max()  # episodes of different lengths
    for p, policy in enumerate((trained, noisy)):
        for e, seed in enumerate((11, 12)):
            total, length, reached, progress = single_episode(policy, config, seed)
            assert (batch.lengths[p, e], batch.successes[p, e]) == (length, reached)
            assert batch.returns[p, e] == total
            assert batch.progress[p, e] == progress


def test_a_resumed_search_is_the_search_never_stopped(tmp_path: Path) -> None:
    config = dataclasses.replace(TINY, generations=4, eval_every=1)
    whole = run_search(config)
    checkpoint = tmp_path / "checkpoint"
    run_search(dataclasses.replace(config, generations=2), checkpoint=checkpoint)
    assert json.loads(checkpoint.with_suffix(".json").read_text())["generation"] == 2
    resumed = run_search(config, checkpoint=checkpoint, resume=True)
    assert without_clock(resumed.records) == without_clock(whole.records)
    np.testing.assert_array_equal(resumed.policy.parameters, whole.policy.parameters)


def test_bad_checkpoints_are_refused_in_one_line(tmp_path: Path) -> None:
    config = dataclasses.replace(TINY, generations=1)
    checkpoint = tmp_path / "checkpoint"
    run_search(config, checkpoint=checkpoint)
    with pytest.raises(UserError, match="saved for another search"):
        run_search(dataclasses.replace(config, seed=9), checkpoint=checkpoint, resume=True)
    with pytest.raises(UserError, match="already 1 generations"):
        run_search(dataclasses.replace(config, generations=0), checkpoint=checkpoint, resume=True)
    meta_path = checkpoint.with_suffix(".json")
    meta = json.loads(meta_path.read_text())
    meta_path.write_text(json.dumps({**meta, "sigma": -1.0}))
    with pytest.raises(CorruptFileError, match="expected sigma > 0"):
        run_search(config, checkpoint=checkpoint, resume=True)
    meta_path.write_text(json.dumps({**meta, "records": meta["records"][:1]}))
    with pytest.raises(CorruptFileError, match="expected 2 records"):
        run_search(config, checkpoint=checkpoint, resume=True)
    meta_path.write_text(json.dumps({**meta, "records": [{"generation": "0"}] * 2}))
    with pytest.raises(CorruptFileError, match="expected a record object of numbers"):
        run_search(config, checkpoint=checkpoint, resume=True)
    meta_path.write_text(json.dumps(meta))
    arrays = arrays_of(checkpoint.with_suffix(".npz"))
    write_npz(checkpoint.with_suffix(".npz"), {**arrays, "covariance": np.eye(31)})
    with pytest.raises(
        CorruptFileError, match=r"array 'covariance' is float64 of shape \(31, 31\)"
    ):
        run_search(config, checkpoint=checkpoint, resume=True)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"population": 1}, "population"),
        ({"control_period": 0.15}, "control_period"),
        ({"map_kind": "cave"}, "map_kind"),
        ({"sigma0": float("inf")}, "sigma0"),
        ({"progress_weight": -1.0}, "progress_weight"),
        ({"hidden": True}, "hidden"),
    ],
)
def test_bad_configs_are_refused(change: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        dataclasses.replace(TINY, **change)
