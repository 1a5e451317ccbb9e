"""Seconds of driving: the summary columns on a hand-made episode table, the action duration of
a run's env, and the value-of-learning section of the report on synthetic summaries."""

from __future__ import annotations

import math
from pathlib import Path

import gymnasium
import numpy as np
import pandas as pd
import pytest

import skidnav  # noqa: F401  (registers the environments)
from skidnav.experiments.config import AgentSpec, ExperimentConfig, MapSpec, freeze_params
from skidnav.experiments.configfile import load_config
from skidnav.experiments.metrics import DrivingClock, run_metrics
from skidnav.experiments.report.learning_value import (
    learning_value_section,
    model_arms,
    value_of_learning,
)
from skidnav.experiments.runs import expand_runs
from skidnav.experiments.trial import action_duration


def _episodes(
    length: list[int], success: list[int], greedy_success: list[float]
) -> dict[str, np.ndarray]:
    n = len(length)
    return {
        "return": np.zeros(n), "length": np.array(length), "success": np.array(success, bool),
        "collisions": np.zeros(n, int), "planning_updates": np.zeros(n, int),
        "wall_time": np.zeros(n), "greedy_length": np.full(n, 20.0),
        "greedy_success": np.array(greedy_success, float),
    }  # fmt: skip


def _driving(episodes: dict[str, np.ndarray], duration: float, window: int) -> dict[str, float]:
    return run_metrics(episodes, np.zeros((1, 3)), False, None, DrivingClock(duration, window))


def test_seconds_are_the_actions_up_to_the_episode_times_the_action_duration() -> None:
    # Episode 2 is the first success; from episode 4 on every evaluation has >= 90 % (5/5) of
    # its rollouts at the goal (episode 3's 4/5 breaks the earlier stretch).
    episodes = _episodes([30, 12, 9, 7, 7, 6], [0, 1, 0, 1, 1, 1], [0, 1, 0.8, 1, 1, 0.9])
    metrics = _driving(episodes, 0.1, window=2)
    assert metrics["action_duration"] == 0.1
    assert metrics["driving_seconds"] == pytest.approx(7.1)  # 71 actions
    assert metrics["episodes_to_first_success"] == 2
    assert metrics["seconds_to_first_success"] == pytest.approx(4.2)  # 30 + 12 actions
    assert metrics["episodes_to_success90"] == 4
    assert metrics["seconds_to_success90"] == pytest.approx(5.8)  # 30 + 12 + 9 + 7 actions
    at_one_second = _driving(episodes, 1.0, window=2)
    assert at_one_second["seconds_to_success90"] == pytest.approx(58.0)
    # The evidence window: from episode 4 there are 3 evaluations; a window of 4 needs episode
    # 3 too, which fell short, so the run is censored.
    assert math.isnan(_driving(episodes, 1.0, window=4)["seconds_to_success90"])


def test_runs_that_never_get_there_are_censored_not_counted_at_the_end() -> None:
    # Succeeded in training never; the greedy policy reached >= 90 % but fell back at the end.
    episodes = _episodes([50, 50, 50, 50], [0, 0, 0, 0], [1.0, 1.0, 1.0, 0.6])
    metrics = _driving(episodes, 1.0, window=1)
    for column in ("episodes_to_first_success", "seconds_to_first_success"):
        assert math.isnan(metrics[column])
    assert math.isnan(metrics["episodes_to_success90"])
    assert math.isnan(metrics["seconds_to_success90"])
    assert metrics["driving_seconds"] == 200.0
    assert metrics["first_success_episode"] == 4.0  # the older column keeps its convention
    no_robot = run_metrics(episodes, np.zeros((1, 3)), False, None)
    assert math.isnan(no_robot["driving_seconds"]) and math.isnan(no_robot["action_duration"])


@pytest.mark.parametrize(
    ("options", "seconds"),
    [({}, 1.0), ({"control_period": 0.1}, 0.1), ({"control_period": 2.0}, 2.0)],
)
def test_the_action_duration_is_the_env_robots(options: dict[str, float], seconds: float) -> None:
    env = gymnasium.make("skidnav/SkidSteerNav-v0", map_kind="free", **options)
    assert action_duration(env) == pytest.approx(seconds)
    assert math.isnan(action_duration(gymnasium.make("skidnav/DynaMaze-v0")))


def test_the_mujoco_robot_has_the_same_action_duration() -> None:
    pytest.importorskip("mujoco")
    env = gymnasium.make(
        "skidnav/SkidSteerNav-v0", map_kind="free", dynamics="mujoco", control_period=0.5
    )
    assert action_duration(env) == pytest.approx(0.5)


def _arm(model: str) -> AgentSpec:
    params = freeze_params({"planning_steps": 10, "kinematic_model": model})
    return AgentSpec("dyna-full", f"dyna-full[kinematic_model={model}]", params)


CONFIG = ExperimentConfig(
    "value", (AgentSpec("q-learning", "q"), _arm("learned"), _arm("prior"), _arm("true")),
    (MapSpec("m", "free"),), seeds=12, bootstrap_samples=500,
)  # fmt: skip


def _summaries() -> pd.DataFrame:
    """Learned reaches first success 30 s sooner than prior in every world; success rates
    equal up to noise; true as learned. One prior run never reaches sustained success."""
    rng = np.random.default_rng(3)
    rows = []
    for seed in range(12):
        world = rng.uniform(100, 200)
        noise = rng.normal(0, 0.02, size=3)
        for (label, shift), jitter in zip(
            (("learned", -30.0), ("prior", 0.0), ("true", -30.0)), noise, strict=True
        ):
            rows.append({
                "agent": f"dyna-full[kinematic_model={label}]", "map": "m",
                "preset": "thesis", "seed": seed,
                "seconds_to_first_success": world + shift, "episodes_to_first_success": 3.0,
                "seconds_to_success90": math.nan if (label, seed) == ("prior", 0) else world,
                "episodes_to_success90": 9.0, "success_rate": 0.9 + jitter,
                "collisions_per_episode": 1.0,
            })  # fmt: skip
    return pd.DataFrame(rows)


def test_the_arms_differ_only_in_their_kinematic_model() -> None:
    (arms,) = model_arms(CONFIG)
    assert arms.name == "dyna-full"  # the label without its kinematic_model choice
    assert set(arms.labels) == {"learned", "prior", "true"}
    lone = ExperimentConfig("x", (_arm("learned"), AgentSpec("q-learning", "q")), CONFIG.maps)
    assert model_arms(lone) == []


def test_value_of_learning_is_paired_by_world() -> None:
    table = value_of_learning(_summaries(), CONFIG)
    row = table.set_index(["comparison", "metric"])
    first = row.loc[("learned − prior", "seconds_to_first_success")]
    # Paired by world the difference is exactly −30 s, whatever the spread between worlds.
    assert first["difference"] == pytest.approx(-30.0)
    assert first["difference_high"] == pytest.approx(-30.0) and not first["no_difference"]
    assert row.loc[("true − learned", "seconds_to_first_success")]["difference"] == 0.0
    censored = row.loc[("learned − prior", "seconds_to_success90")]
    assert censored["pairs"] == 11  # the world where prior never got there is left out
    assert row.loc[("learned − prior", "success_rate")]["no_difference"]


def test_a_grid_run_in_part_is_paired_over_the_worlds_both_arms_ran() -> None:
    summaries = _summaries()
    prior = summaries["agent"] == "dyna-full[kinematic_model=prior]"
    # The prior arm ran the first 6 worlds only, and the learned arm drives its last 6 worlds
    # far longer: unpaired, the two arms' means would differ by far more than 30 s.
    summaries.loc[~prior & (summaries["seed"] >= 6), "seconds_to_first_success"] += 1000.0
    part = summaries[~prior | (summaries["seed"] < 6)]
    row = value_of_learning(part, CONFIG).set_index(["comparison", "metric"])
    first = row.loc[("learned − prior", "seconds_to_first_success")]
    assert first["difference"] == pytest.approx(-30.0) and first["pairs"] == 6
    assert row.loc[("true − learned", "seconds_to_first_success")]["pairs"] == 12
    alone = value_of_learning(summaries[~prior], CONFIG).set_index(["comparison", "metric"])
    nothing = alone.loc[("learned − prior", "seconds_to_first_success")]
    assert nothing["pairs"] == 0 and math.isnan(nothing["difference_low"])


def test_on_a_grid_run_in_part_the_arms_cells_cover_the_worlds_every_arm_ran() -> None:
    summaries = _summaries()
    prior = summaries["agent"] == "dyna-full[kinematic_model=prior]"
    summaries.loc[~prior & (summaries["seed"] >= 6), "seconds_to_first_success"] += 1000.0
    part = summaries[~prior | (summaries["seed"] < 6)]
    text = learning_value_section(part, CONFIG)
    assert "dyna-full · m · thesis (6 of 12 worlds, those every arm ran)" in text
    row = text[text.index("driving to the first success [s]") :]
    learned, prior_cell, true = (float(cell.split()[0]) for cell in row.split("<td>")[1:4])
    # Over the six shared worlds each arm's mean is about 150 s; over all twelve the learned
    # and true arms' would be about 620 s (the +1000 s of their last six worlds).
    assert learned < 300.0 and true < 300.0 and learned == pytest.approx(prior_cell - 30.0)
    assert "(12 of 12" not in learning_value_section(summaries, CONFIG)


def test_the_section_says_plainly_where_no_difference_was_measured() -> None:
    text = learning_value_section(_summaries(), CONFIG)
    assert "Value of learning the kinematic model" in text
    said = text[text.index("Learned − prior: no difference measured in") :]
    assert "success rate (all episodes)" in said.split("</p>")[0]
    clear = text[text.index("intervals clear of 0") :].split("</p>")[0]
    assert "driving to the first success [s] -30" in clear
    assert "11/12 reached" in text  # the prior arm's censored run
    nothing = ExperimentConfig("x", (AgentSpec("q-learning", "q"),), CONFIG.maps)
    assert learning_value_section(_summaries(), nothing) == ""


def test_the_kaplan_meier_medians_count_the_runs_that_never_got_there() -> None:
    summaries = _summaries()
    summaries["driving_seconds"] = 1000.0
    prior = summaries["agent"] == "dyna-full[kinematic_model=prior]"
    summaries.loc[prior & (summaries["seed"] < 7), "seconds_to_success90"] = math.nan
    text = learning_value_section(summaries, CONFIG)
    row = text[text.index("driving to ≥ 90 % greedy success, Kaplan–Meier median [s]") :]
    cells = [cell.split("<")[0] for cell in row.split("<td>")[1:6]]
    learned, prior_cell = cells[0], cells[1]
    assert prior_cell.startswith("∞")  # 7 of 12 never got there: more than half
    assert not learned.startswith("∞") and cells[3:] == ["–", "–"]
    assert "5/12 reached" in text  # the mean over the runs that got there hides the seven
    del summaries["driving_seconds"]
    assert "Kaplan–Meier" not in learning_value_section(summaries, CONFIG).split("</p>", 1)[1]


def test_the_reduced_value_configs_run_the_first_worlds_of_the_full_ones() -> None:
    configs = Path(__file__).resolve().parents[2] / "configs"
    for name in ("kinematic-value-seconds", "kinematic-value-seconds-mppi"):
        full = expand_runs(load_config(configs / f"{name}.toml"))
        reduced = expand_runs(load_config(configs / f"{name}-reduced.toml"))
        worlds = {(r.agent, r.map, r.preset, r.seed): r.world_seed for r in full}
        assert reduced and all(
            worlds[(r.agent, r.map, r.preset, r.seed)] == r.world_seed for r in reduced
        )
