"""One run: the warm-up changes no number and leaves nothing to compile inside the timed run;
the greedy-policy map; config errors that name the file."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from skidnav import cli
from skidnav._jit import jit_disabled
from skidnav.agents.tabular.registry import available_agents
from skidnav.agents.training import TrainingLog
from skidnav.errors import UserError
from skidnav.experiments import trial
from skidnav.experiments.configfile import parse_config
from skidnav.experiments.reference.world import WorldReference
from skidnav.experiments.runner import run_experiment
from skidnav.experiments.runs import expand_runs
from skidnav.experiments.store import TrialResult
from skidnav.experiments.value_maps import policy_map
from skidnav.world.grid import GridMap
from tests.experiments.exp_support import TINY_TOML, cli_env


def _numbers(result: TrialResult) -> dict[str, object]:
    """Everything a run measured except wall times, as comparable lists (NaN as −9)."""
    episodes = {
        k: np.nan_to_num(v, nan=-9.0).tolist()
        for k, v in result.episodes.items()
        if k != "wall_time"
    }
    summary = {k: -9.0 if v != v else v for k, v in result.summary.items() if k != "wall_time"}
    arrays = {k: np.nan_to_num(v, nan=-9.0).tolist() for k, v in result.arrays.items()}
    return {"episodes": episodes, "summary": summary, "arrays": arrays}


def test_warm_up_changes_no_number(monkeypatch: pytest.MonkeyPatch) -> None:
    runs = expand_runs(parse_config(TINY_TOML))
    spec = runs[-1]  # dyna-q: plans from a learned model
    without = _numbers(trial.measure_trial(spec))
    monkeypatch.setattr(trial, "_warmed_up", set())
    trial.warm_up(runs[0])  # another agent's warm-up in between must not matter either
    assert _numbers(trial.run_trial(spec)) == without
    assert ("skidnav/SkidSteerNav-v0", "dyna-q", repr(spec.agent.params)) in trial._warmed_up


# Run in a fresh interpreter: the run after the warm-up must not add a compiled signature to any
# numba dispatcher of skidnav, i.e. nothing is compiled (or loaded from the cache) on its clock.
FRESH_PROCESS = """
import json, sys
import numba.core.dispatcher
from skidnav.experiments import trial
from skidnav.experiments.configfile import parse_config
from skidnav.experiments.runs import expand_runs

def signatures():
    found = {}
    for name, module in list(sys.modules.items()):
        if name.startswith("skidnav."):
            for attr, value in vars(module).items():
                if isinstance(value, numba.core.dispatcher.Dispatcher):
                    found[f"{name}.{attr}"] = len(value.signatures)
    return found

report = []
for spec in expand_runs(parse_config(sys.argv[1])):
    trial.warm_up(spec)
    before = signatures()
    trial.measure_trial(spec)
    after = signatures()
    compiled = sorted(k for k in after if after[k] != before.get(k, 0))
    report.append({"agent": spec.agent.label, "compiled": sum(before.values()), "new": compiled})
print(json.dumps(report))
"""


@pytest.mark.skipif(jit_disabled(), reason="nothing is compiled with NUMBA_DISABLE_JIT=1")
def test_warm_up_compiles_everything_before_the_clock_starts() -> None:
    others = [name for name in available_agents() if name not in ("q-learning", "dyna-q")]
    text = TINY_TOML.replace("seeds = 2", "seeds = 1") + "".join(
        f'\n[[agents]]\nname = "{name}"\nparams = {{ planning_steps = 3 }}\n' for name in others
    )
    result = subprocess.run(
        [sys.executable, "-c", FRESH_PROCESS, text],
        capture_output=True,
        text=True,
        env=cli_env(),
        timeout=600,
    )
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout.strip().splitlines()[-1])
    assert [entry["agent"] for entry in report[::2]] == ["q-learning", "dyna-q-5", *others]
    for entry in report:
        assert entry["compiled"] > 0, entry
        assert entry["new"] == [], entry


# The refit kernels of a learned kinematic model run only when its schedule asks for a refit
# (500 new samples by default), which the warm-up's few actions never reach on their own.
REFIT_KERNELS = """
import sys
from skidnav.agents import planner_learning
from skidnav.experiments import trial
from skidnav.experiments.configfile import parse_config
from skidnav.experiments.runs import expand_runs
from skidnav.models import bayesian_ridge, kinematic_moments

trial.warm_up(expand_runs(parse_config(sys.argv[1]))[-1])
kernels = {  # the refit's entry points, and the episode end without a refit
    "sync_moments": kinematic_moments.sync_moments,
    "newest_moments": kinematic_moments.newest_moments,
    "evidence_loop": bayesian_ridge._evidence_loop,
    "refresh_stale": planner_learning.refresh_stale,
}
print(" ".join(name for name, kernel in kernels.items() if not kernel.signatures))
"""


@pytest.mark.skipif(jit_disabled(), reason="nothing is compiled with NUMBA_DISABLE_JIT=1")
def test_warm_up_compiles_the_kinematic_refit_and_the_episode_end_without_one() -> None:
    text = TINY_TOML + '\n[[agents]]\nname = "dyna-full"\n'
    result = subprocess.run(
        [sys.executable, "-c", REFIT_KERNELS, text],
        capture_output=True, text=True, env=cli_env(), timeout=600,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    # Compiled, or loaded from numba's cache, by the warm-up: a signature each (their helpers
    # are compiled into them, so a cache hit leaves theirs empty).
    assert result.stdout.split() == [], result.stdout


def test_policy_map_is_the_greedy_action_at_the_heading() -> None:
    rng = np.random.default_rng(5)
    walls = np.zeros((4, 3), dtype=bool)
    walls[2, 1] = True
    grid_map = GridMap(walls, (0, 0), (1, 1))
    n_headings = 5
    q = rng.normal(size=(4 * 3 * n_headings, 4))
    q[(3 * 3 + 0) * n_headings + 2] = 0.0  # cell (3, 0) at heading 2: never updated
    actions = policy_map(q, grid_map, 2)
    assert actions.shape == (4, 3) and actions.dtype == np.int64
    for i in range(4):
        for j in range(3):
            state = (i * 3 + j) * n_headings + 2
            expected = -1 if walls[i, j] or (i, j) == (3, 0) else int(np.argmax(q[state]))
            assert actions[i, j] == expected, (i, j)


def test_run_arrays_hold_the_policy_map(serial_results: Path) -> None:
    from skidnav.experiments.store import ResultStore

    run = ResultStore(serial_results).read_run("run-000004")
    policy, occupancy = run.arrays["policy_map"], run.arrays["occupancy"]
    assert policy.shape == occupancy.shape
    assert set(np.unique(policy)) <= {-1, 0, 1, 2, 3}
    assert (policy[occupancy] == -1).all()
    assert (policy >= 0).any()
    assert float(run.arrays["start_heading"]) == 0.0


def test_invalid_agent_params_name_the_config_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "bad-params.toml"
    path.write_text(TINY_TOML.replace("planning_steps = 5", "planning_steps = -1"))
    config = parse_config(path.read_text(), path)
    with pytest.raises(
        UserError, match=rf"^expected .*planning_steps.* in {path}: agent 'dyna-q'$"
    ):
        run_experiment(config, tmp_path / "out", backend="serial", config_path=path)
    assert not (tmp_path / "out").exists()
    code = cli.main(["run", str(path), "--out", str(tmp_path / "out"), "--no-progress"])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1
    assert lines[0].startswith("skidnav: error: expected an integer planning_steps ")
    assert lines[0].endswith(f" in {path}: agent 'dyna-q'")


def test_an_evaluation_costs_the_mean_of_its_rollouts_that_reached_the_goal() -> None:
    nan = float("nan")
    log = TrainingLog(
        np.zeros(3), np.ones(3, np.int64), np.ones(3, bool), np.zeros(3, np.int64),
        np.zeros(3, np.int64), np.zeros(3),
        np.array([[10, -1, 12], [-1, -1, -1], [7, 7, 7]]),
        np.array([[11.5, nan, 13.5], [nan, nan, nan], [9.0, 8.0, 7.0]]),
    )  # fmt: skip
    arrays = trial._episode_arrays(log)
    assert arrays["greedy_length"].tolist()[::2] == [11.0, 7.0]
    assert arrays["greedy_cost"].tolist()[::2] == [12.5, 8.0]
    assert np.isnan(arrays["greedy_cost"][1]) and np.isnan(arrays["greedy_length"][1])
    assert arrays["greedy_success"].tolist() == [2 / 3, 0.0, 1.0]


def test_without_an_oracle_the_reference_cost_is_the_length() -> None:
    maze = WorldReference(14.0, None, None, {})  # a grid maze: every move costs one
    columns = maze.summary_columns(None)
    assert columns["oracle_cost"] == columns["oracle_length"] == 14.0 == maze.optimum("cost")
    assert np.isnan(columns["oracle_rollout_cost"]) and np.isnan(columns["oracle_rollout_length"])
    assert np.isnan(columns["start_plan_length"])
    other = WorldReference(float("nan"), None, None, {}).summary_columns(None)
    assert np.isnan(other["oracle_cost"])


COSTS_TOML = """
[experiment]
name = "costs"
episodes = 12
max_steps = 60
seeds = 1
root_seed = 5
presets = ["slippery"]
oracle_samples = 4
eval_rollouts = 3
convergence_window = 2

[[maps]]
kind = "free"
options = { shape = [7, 7], min_distance = 3 }

[[agents]]
name = "dyna-q"
params = { planning_steps = 10 }

[[agents]]
name = "dyna-q"
label = "finer cells"
discretization = [13, 13, 20]
params = { planning_steps = 10 }
"""


def test_a_run_records_what_its_evaluations_cost() -> None:
    """On a slippery floor every action costs more than one; the compiled evaluation (the map's
    own cells) and the plain one (finer cells) record the costs, the oracle its C*."""
    coarse, fine = (trial.run_trial(spec) for spec in expand_runs(parse_config(COSTS_TOML)))
    lengths, costs = coarse.episodes["greedy_length"], coarse.episodes["greedy_cost"]
    reached = coarse.episodes["greedy_success"] > 0
    assert 0 < reached.sum() < len(reached)
    assert (costs[reached] > lengths[reached]).all()
    assert np.isnan(costs[~reached]).all()
    for result in (coarse, fine):
        summary = result.summary
        assert summary["oracle_cost"] > summary["oracle_length"] > 1.0
        assert summary["oracle_rollout_cost"] > 1.0  # every oracle rollout reached the goal


def test_the_cost_objective_measures_evaluations_against_c_star() -> None:
    toml = TINY_TOML.replace(
        "eval_rollouts = 2", 'eval_rollouts = 2\nconvergence_objective = "cost"'
    )
    spec = next(s for s in expand_runs(parse_config(toml)) if s.coordinates["preset"] == "slippery")
    result = trial.run_trial(spec)
    summary, costs = result.summary, result.episodes["greedy_cost"]
    assert summary["oracle_cost"] > summary["oracle_length"]  # slippery: C* is not L*
    last = costs[-2:][np.isfinite(costs[-2:])]  # the last W = 2 evaluations that reached it
    expected = last.mean() / summary["oracle_cost"] - 1 if last.size else np.nan
    np.testing.assert_allclose(summary["optimality_gap"], expected)
    assert np.isnan(summary["start_plan_passes"])  # the plan's replays record no cost
    with pytest.raises(UserError, match="convergence_objective"):
        parse_config(toml.replace('"cost"', '"return"'))
