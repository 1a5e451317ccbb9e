"""The one episode loop (:func:`skidnav.agents.training.train_episodes`): the reset seeds, the
evaluation limit, the evaluation env's first reset, the recording and the log, written once for
every family trainer, which all share one signature."""

from __future__ import annotations

import inspect
from typing import Any

import numpy as np
import pytest

from skidnav.agents.catalog import families
from skidnav.agents.greedy import NOT_REACHED, Rollout
from skidnav.agents.mpc.training import train_mppi
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.training import (
    NO_EVALUATION,
    Episode,
    Evaluation,
    TrainingLog,
    train_agent,
    train_episodes,
)


class EvaluationEnv:
    """Records its resets in ``events``."""

    def __init__(self, events: list[tuple[str, Any]]) -> None:
        self.events = events

    def reset(self, *, seed: int | None = None) -> None:
        self.events.append(("evaluation reset", seed))


def _loop(
    events: list[tuple[str, Any]], episodes: int, evaluation: Evaluation, **options: Any
) -> TrainingLog:
    """The loop over functions that record their calls in ``events``: episode ``k`` (from 0)
    returns (k, k + 1, k odd, 2k, 3k); each evaluation gives rollouts of length = the limit."""

    def run(seed: int | None) -> Episode:
        index = sum(event[0] == "episode" for event in events)
        events.append(("episode", seed))
        return Episode(float(index), index + 1, index % 2 == 1, 2 * index, 3 * index)

    def evaluate(limit: int) -> list[Rollout]:
        events.append(("evaluate", limit))
        return [Rollout(limit, 0.5)] * evaluation.n_rollouts

    return train_episodes(run, evaluate, episodes, evaluation=evaluation, **options)


def test_the_first_episode_resets_with_the_seed_and_the_evaluation_env_with_the_next() -> None:
    events: list[tuple[str, Any]] = []
    _loop(events, 3, Evaluation(EvaluationEnv(events)), max_steps=20, seed=7)
    assert events == [
        ("episode", 7), ("evaluation reset", 8), ("evaluate", 20),
        ("episode", None), ("evaluate", 20),
        ("episode", None), ("evaluate", 20),
    ]  # fmt: skip


@pytest.mark.parametrize("seed", [7, None])
def test_evaluation_seeds_or_no_seed_leave_the_evaluation_env_unseeded(seed: int | None) -> None:
    events: list[tuple[str, Any]] = []
    seeds = [1, 2] if seed is not None else None
    log = _loop(events, 2, Evaluation(EvaluationEnv(events), seeds), seed=seed)
    assert [event for event in events if event[0] != "evaluate"] == [
        ("episode", seed), ("episode", None),
    ]  # fmt: skip
    assert log.greedy_lengths.shape == (2, 1 if seeds is None else 2)


@pytest.mark.parametrize(
    ("rollout_steps", "max_steps", "limit"), [(5, 20, 5), (None, 20, 20), (None, None, 10_000)]
)
def test_the_rollout_limit_is_the_evaluations_else_the_trainings_else_ten_thousand(
    rollout_steps: int | None, max_steps: int | None, limit: int
) -> None:
    events: list[tuple[str, Any]] = []
    evaluation = Evaluation(EvaluationEnv(events), [0], rollout_steps)
    assert evaluation.limit(max_steps) == limit
    log = _loop(events, 2, evaluation, max_steps=max_steps)
    assert ("evaluate", limit) in events and log.greedy_lengths.tolist() == [[limit], [limit]]


def test_the_log_holds_each_episode_and_its_evaluation() -> None:
    log = _loop([], 4, Evaluation(EvaluationEnv([]), [3, 4, 5], 9))
    assert log.returns.tolist() == [0.0, 1.0, 2.0, 3.0] and log.lengths.tolist() == [1, 2, 3, 4]
    assert log.successes.tolist() == [False, True, False, True]
    assert log.collisions.tolist() == [0, 2, 4, 6]
    assert log.planning_updates.tolist() == [0, 3, 6, 9]
    assert (log.wall_time >= 0).all() and log.wall_time.dtype == np.float64
    assert log.greedy_lengths.tolist() == [[9] * 3] * 4 and (log.greedy_costs == 0.5).all()
    dtypes = [column.dtype for column in log]
    assert dtypes == [np.float64, np.int64, np.bool_, np.int64, np.int64, np.float64, np.int64,
                      np.float64]  # fmt: skip


def test_without_an_evaluation_env_nothing_is_evaluated() -> None:
    events: list[tuple[str, Any]] = []
    log = _loop(events, 2, Evaluation(seeds=[1, 2, 3]), seed=4)
    assert all(event[0] == "episode" for event in events)
    assert log.greedy_lengths.tolist() == [[NOT_REACHED.length] * 3] * 2
    assert np.isnan(log.greedy_costs).all()
    assert _loop([], 2, NO_EVALUATION).greedy_lengths.shape == (2, 1)


@pytest.mark.parametrize(("episodes", "max_steps"), [(-1, None), (3, 0)])
def test_bad_arguments_are_refused_in_one_line(episodes: int, max_steps: int | None) -> None:
    with pytest.raises(ValueError, match=r"^expected episodes >= 0 and max_steps >= 1, got"):
        _loop([], episodes, NO_EVALUATION, max_steps=max_steps)


def test_every_family_trainer_has_the_one_signature() -> None:
    def shape(trainer: Any) -> list[tuple[str, Any, Any]]:
        parameters = inspect.signature(trainer).parameters.values()
        return [(p.kind, p.default) for p in parameters][1:]  # the agent's type differs

    trainers = (train_agent, train_agent_fast, train_mppi, *(f.train for f in families()))
    expected = [
        (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.empty),
        (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.empty),
        (inspect.Parameter.KEYWORD_ONLY, None),
        (inspect.Parameter.KEYWORD_ONLY, NO_EVALUATION),
        (inspect.Parameter.KEYWORD_ONLY, None),
    ]
    for trainer in trainers:
        names = list(inspect.signature(trainer).parameters)[3:]
        assert names == ["max_steps", "evaluation", "seed"], trainer.__name__
        assert shape(trainer) == expected, trainer.__name__
