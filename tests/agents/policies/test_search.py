"""CMA-ES policy search: it improves the policy, the same seed gives the same numbers, common
random numbers, batch rollouts equal single-env episodes, and checkpoints resume exactly."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import shutil
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import pytest
from cmaes import CMA

import skidnav  # noqa: F401  (registers the env)
from skidnav.agents.policies.search import rollouts
from skidnav.agents.policies.search.cmaes import (
    GenerationRecord,
    SearchResult,
    generation_seeds,
    run_search,
)
from skidnav.agents.policies.search.config import MAX_SIGMA0, SearchConfig
from skidnav.agents.policies.search.rollouts import PopulationRollouts
from skidnav.agents.policies.search.tanh_policy import TanhPolicy
from skidnav.errors import CorruptFileError, UserError
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


SMALL = SearchConfig(
    map_kind="free", world_seed=3, max_episode_steps=10, hidden=0, population=4,
    episodes_per_candidate=1, eval_episodes=1, eval_every=2, generations=3, seed=0,
)  # fmt: skip
"""A search of 3 generations in about 0.05 s."""


class Killed(BaseException):
    """The process killed in the middle of a checkpoint."""


@pytest.mark.parametrize("kill_at", [3, 4])
def test_a_search_killed_while_checkpointing_resumes_as_never_stopped(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, kill_at: int
) -> None:
    """Killed as generation 2's archive (3rd write), or its readable copy (4th), is moved into
    place: the resumed search is the one never stopped (before one-file checkpoints, a kill at
    the 4th write left generation 2's arrays with generation 1's σ and curve)."""
    whole = run_search(SMALL)
    checkpoint, replace, targets = tmp_path / "checkpoint", os.replace, []

    def dying(source: str | Path, target: str | Path) -> None:
        targets.append(Path(target).name)
        if len(targets) == kill_at:
            raise Killed
        replace(source, target)

    monkeypatch.setattr(os, "replace", dying)
    with pytest.raises(Killed):
        run_search(SMALL, checkpoint=checkpoint)
    monkeypatch.setattr(os, "replace", replace)
    assert targets == (["checkpoint.npz", "checkpoint.json"] * 2)[:kill_at]
    resumed = run_search(SMALL, checkpoint=checkpoint, resume=True)
    assert without_clock(resumed.records) == without_clock(whole.records)
    np.testing.assert_array_equal(resumed.policy.parameters, whole.policy.parameters)


def test_a_search_extended_with_resume_records_what_one_run_does(tmp_path: Path) -> None:
    """Evaluated every 5 generations: a 3-generation search evaluates its last one too (in its
    result), but the 6 generations resumed from it are the 6 of one run, evaluated at 0, 5, 6."""
    config = dataclasses.replace(SMALL, eval_every=5, generations=6)
    whole = run_search(config)
    assert [record.evaluation_episodes for record in whole.records] == [1, 1, 1, 1, 1, 2, 3]
    checkpoint, short = tmp_path / "checkpoint", dataclasses.replace(config, generations=3)
    first = run_search(short, checkpoint=checkpoint)
    assert first.records[-1].evaluation_episodes == 2 and not math.isnan(
        first.records[-1].mean_return
    )
    again = run_search(short, checkpoint=checkpoint, resume=True)  # nothing left but the evaluation
    assert without_clock(again.records) == without_clock(first.records)
    extended = run_search(config, checkpoint=checkpoint, resume=True)
    assert without_clock(extended.records) == without_clock(whole.records)
    np.testing.assert_array_equal(extended.policy.parameters, whole.policy.parameters)


def test_every_record_is_reported_once_the_last_after_its_evaluation() -> None:
    reported: list[GenerationRecord] = []
    result = run_search(dataclasses.replace(SMALL, eval_every=5), on_generation=reported.append)
    assert reported == list(result.records) and result.records[-1].evaluation_episodes == 2


@pytest.fixture(scope="module")
def saved_checkpoint(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The checkpoint of :data:`SMALL` after 2 generations (copy it before damaging it)."""
    checkpoint = tmp_path_factory.mktemp("saved") / "checkpoint"
    run_search(dataclasses.replace(SMALL, generations=2), checkpoint=checkpoint)
    return checkpoint


def damaged_copy(saved: Path, folder: Path) -> Path:
    """A copy of the checkpoint ``saved`` in ``folder`` (``NAME`` of it)."""
    for suffix in (".npz", ".json"):
        shutil.copy(saved.with_suffix(suffix), folder / f"checkpoint{suffix}")
    return folder / "checkpoint"


def edit_archive(checkpoint: Path, meta: dict[str, Any] | None = None, **arrays: Any) -> None:
    """Rewrite the checkpoint's archive with ``meta`` changed in its JSON and ``arrays``
    replaced (a function: applied to the saved array)."""
    members = arrays_of(checkpoint.with_suffix(".npz"))
    saved = json.loads(members["meta"].tobytes())
    text = json.dumps({**saved, **(meta or {})}).encode()
    members["meta"] = np.frombuffer(text, dtype=np.uint8)
    for name, change in arrays.items():
        members[name] = change(members[name].copy())
    write_npz(checkpoint.with_suffix(".npz"), members)


def edit_copy(checkpoint: Path, change: Any) -> None:
    """Rewrite the checkpoint's readable copy: ``change(copy) -> JSON text``."""
    path = checkpoint.with_suffix(".json")
    path.write_text(change(json.loads(path.read_text())))


def last_row(column: str, value: float) -> Any:
    """A change of the records table: ``column`` of the last row set to ``value``."""

    def change(table: np.ndarray) -> np.ndarray:
        table[-1, GenerationRecord._fields.index(column)] = value
        return table

    return change


BIG = "1" + "0" * 400
"""An integer JSON reads whole and float() cannot convert."""


def copy_text(old: str, new: str) -> Any:
    """A damage: the first ``old`` of the readable copy's text replaced by ``new``."""
    return lambda c: edit_copy(c, lambda meta: json.dumps(meta).replace(old, new, 1))


def archive(meta: dict[str, Any] | None = None, **arrays: Any) -> Any:
    """A damage: :func:`edit_archive` with these changes."""
    return lambda c: edit_archive(c, meta, **arrays)


DAMAGES = {
    "sigma huge integer": (archive({"sigma": 10**400}), "expected sigma to be a finite number"),
    "sigma 1e300": (archive({"sigma": 1e300}), r"sigma .* in \(0, 1e\+32\], got 1e\+300"),
    "sigma negative": (archive({"sigma": -1.0}), "expected sigma to be a finite number"),
    "sigma string": (archive({"sigma": "0.3"}), "expected sigma to be a finite number"),
    "generation huge": (archive({"generation": 10**400}), "expected generation"),
    "config list": (archive({"config": [1, 2]}), "expected the config to be an object"),
    "config string": (archive({"config": {"population": "4"}}), "population"),
    "version 1": (archive({"version": 1}), "not a skidnav CMA-ES checkpoint of version 2"),
    "mean 1e33": (archive(mean=lambda m: m + 1e33), "array 'mean' holds a value"),
    "covariance inf": (archive(covariance=lambda m: m * np.inf), "array 'covariance'"),
    "wall time NaN": (archive(records=last_row("wall_time", np.nan)), "wall_time"),
    "wall time < 0": (archive(records=last_row("wall_time", -1.0)), "wall times >= 0"),
    "episodes": (archive(records=last_row("episodes", 9.0)), "episodes"),
    "evaluation": (archive(records=last_row("mean_return", np.nan)), "mean_return"),
    "records cut": (archive(records=lambda t: t[:2]), "array 'records' is float64 of"),
    "copy sigma 1e300": (copy_text('"sigma": 0', '"sigma": 1e300, "s": 0'), "does not match"),
    "copy sigma huge": (copy_text('"sigma": 0', f'"sigma": {BIG}, "s": 0'), "does not match"),
    "copy wall time huge": (copy_text('"wall_time": ', f'"wall_time": {BIG}, "w": '), "not match"),
    "copy wall time null": (copy_text('"wall_time": ', '"wall_time": null, "w": '), "not match"),
    "copy cut": (lambda c: edit_copy(c, lambda meta: json.dumps(meta)[:100]), "invalid JSON"),
    "version 1 archive": (
        lambda c: write_npz(c.with_suffix(".npz"), {"mean": np.zeros(10)}),
        "not a skidnav CMA-ES checkpoint of version 2",
    ),
}
"""Damaged checkpoints of :func:`saved_checkpoint` and what refuses them (the hand edits of the
review: each ended in an OverflowError, an AssertionError of cmaes, or NaN wall times)."""


@pytest.mark.parametrize(("damage", "message"), DAMAGES.values(), ids=DAMAGES)
def test_bad_checkpoints_are_refused_in_one_line(
    saved_checkpoint: Path, tmp_path: Path, damage: Any, message: str
) -> None:
    checkpoint = damaged_copy(saved_checkpoint, tmp_path)
    damage(checkpoint)
    with pytest.raises(CorruptFileError, match=message) as caught:
        run_search(SMALL, checkpoint=checkpoint, resume=True)
    assert "\n" not in str(caught.value) and str(tmp_path) in str(caught.value)


def test_checkpoints_of_other_searches_are_refused(saved_checkpoint: Path) -> None:
    with pytest.raises(UserError, match="saved for another search"):
        run_search(dataclasses.replace(SMALL, seed=9), checkpoint=saved_checkpoint, resume=True)
    with pytest.raises(UserError, match="already 2 generations"):
        run_search(
            dataclasses.replace(SMALL, generations=1), checkpoint=saved_checkpoint, resume=True
        )
    with pytest.raises(
        CorruptFileError, match=r"'covariance' is float64 of shape \(32, 32\), expected .*\(16, 16"
    ):
        run_search(
            dataclasses.replace(SMALL, lidar_rays=0), checkpoint=saved_checkpoint, resume=True
        )


def test_a_stale_copy_is_the_mark_of_a_cut_write_and_accepted(
    saved_checkpoint: Path, tmp_path: Path
) -> None:
    """The readable copy of an older generation (the archive of a newer one moved into place,
    its copy not yet): the archive is the checkpoint."""
    checkpoint = damaged_copy(saved_checkpoint, tmp_path)
    edit_copy(checkpoint, lambda m: json.dumps({**m, "generation": 1, "sigma": 9.0}))
    assert run_search(SMALL, checkpoint=checkpoint, resume=True).records[-1].generation == 3


def test_a_diverging_search_stops_in_one_line(saved_checkpoint: Path, tmp_path: Path) -> None:
    """σ = 10³² is a step size cmaes keeps (its cap), but its candidates pass the bound cmaes
    asserts of them: one line, not cmaes' AssertionError."""
    checkpoint = damaged_copy(saved_checkpoint, tmp_path)
    edit_archive(checkpoint, {"sigma": 1e32})
    (tmp_path / "checkpoint.json").unlink()
    with pytest.raises(UserError, match="generation 3: a candidate's parameter is not below 1e"):
        run_search(SMALL, checkpoint=checkpoint, resume=True)


def test_the_largest_initial_step_size_is_one_cmaes_accepts() -> None:
    result = run_search(dataclasses.replace(SMALL, sigma0=MAX_SIGMA0, generations=1))
    assert result.records[-1].generation == 1
    with pytest.raises(ValueError, match=r"expected sigma0 to be a finite number in \(0, 1e\+30\]"):
        dataclasses.replace(SMALL, sigma0=1e40)


def test_an_env_that_refuses_its_settings_is_one_user_error(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    def refuse(num_envs: int, env_options: Any) -> Any:
        raise ValueError("Maximum allowed dimension exceeded\nsecond line")

    monkeypatch.setattr(rollouts, "make_batch_env", refuse)
    with pytest.raises(
        UserError, match=r"^cannot build the search's env: Maximum allowed"
    ) as caught:
        run_search(SMALL)
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"population": 1}, "population"),
        ({"control_period": 0.15}, "control_period"),
        ({"map_kind": "cave"}, "map_kind"),
        ({"sigma0": float("inf")}, "sigma0"),
        ({"progress_weight": -1.0}, "progress_weight"),
        ({"hidden": True}, "hidden"),
        ({"control_period": 1e300}, r"control_period to be a finite number in \(0, 3600\]"),
        ({"sigma0": 1e40}, "sigma0"),
        ({"lidar_range": 10**400}, "lidar_range"),
        ({"progress_weight": 10**400}, "progress_weight"),
        (
            {"population": 10_000, "episodes_per_candidate": 10_000},
            "at most 4 GiB, got about 812 GiB",
        ),
        ({"hidden": 1024, "lidar_rays": 1024}, "CMA-ES update of 1,058,818 parameters"),
        ({"hidden": 256}, "at most 4 GiB"),
    ],
)
def test_bad_configs_are_refused(change: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        dataclasses.replace(TINY, **change)
