"""Finer state grids for tabular agents, the oracle on them, the continuous optimum."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

import skidnav  # noqa: F401  (registers the env)
from skidnav.agents.tabular.fast_training import train_agent_fast
from skidnav.agents.tabular.registry import make_agent
from skidnav.agents.training import Evaluation, train_agent
from skidnav.commands.report import write_results_report
from skidnav.envs.wrappers import FineStates
from skidnav.errors import UserError
from skidnav.experiments.config import config_from_dict, config_to_dict
from skidnav.experiments.config_checks import check_config
from skidnav.experiments.configfile import parse_config
from skidnav.experiments.reference.finegrid import state_grid
from skidnav.experiments.reference.optimum import Optimum, compute_optimum, optimum_columns
from skidnav.experiments.reference.oracle import compute_oracle, solve
from skidnav.experiments.report.html import build_report
from skidnav.experiments.runner import run_experiment
from skidnav.experiments.store import ResultStore
from skidnav.studies.gap import gap_rows, gap_section, optimum_rows
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap, border_walls, generate_map

FORWARD = 0.0225 * 1.7  # metres of one forward action without slip (docs/simulator.md)


def _corridor(observation: str) -> gymnasium.Env:
    """A free 7 × 7 map (cells 10.3 cm × 8.4 cm): start (1, 3), goal (2, 3) right ahead. From the
    start cell's centre (x = 15.5 cm) the goal cell begins 5.2 cm ahead: at least two forward
    actions (3.8 cm each), and two suffice; the robot ends at 23.2 cm, inside the goal cell
    [20.7, 31.0) cm."""
    grid_map = GridMap(border_walls((7, 7)), start=(1, 3), goal=(2, 3))
    return gymnasium.make(
        "skidnav/SkidSteerNav-v0", grid_map=grid_map, slip="thesis", observation=observation,
        max_episode_steps=50,
    )  # fmt: skip


def test_fine_oracle_finds_the_hand_known_optimum_the_coarse_one_misses():
    env = _corridor("pose")
    nav = env.unwrapped
    coarse = solve(_corridor("discrete").unwrapped, 16, np.random.default_rng(0))
    fine = solve(nav, 16, np.random.default_rng(0), state_grid(nav, (25, 25, 40)))
    # coarse: the poses of the start cell after one action are spread over 10 cm, and those
    # short of 20.7 cm need a third action; fine: every pose of the state reached after one
    # action is one forward action from the goal
    assert coarse.start_value > 2.2
    assert fine.start_value == pytest.approx(2.0, abs=1e-9)
    optimum = compute_optimum(env, (25, 25, 40), 16, 0, [1, 2, 3], 50)
    assert optimum.actions == pytest.approx(2.0, abs=1e-9)
    assert optimum.success == 1.0 and optimum.rollout_actions == 2.0
    assert 0.97 * 2 * FORWARD < optimum.length_m <= 2 * FORWARD  # slip only slows the wheels
    assert compute_optimum(env, (25, 25, 40), 16, 0, [1, 2, 3], 50) == optimum  # same seeds


def test_oracle_on_a_finer_grid_of_a_fine_states_env():
    env = FineStates(_corridor("pose").unwrapped, Discretization(n_x=25, n_y=25, n_headings=40))
    oracle = compute_oracle(env, 16, 0, [1, 2], 50)
    assert oracle.start_value == pytest.approx(2.0, abs=1e-9)
    assert oracle.q.shape == (25 * 25 * 40, 4)
    assert oracle.rollout_lengths.tolist() == [2, 2]


def test_fine_states_on_the_maps_own_grid_train_as_the_compiled_trainer():
    grid_map = generate_map("obstacles", np.random.default_rng(0))

    def make(observation: str) -> gymnasium.Env:
        return gymnasium.make(
            "skidnav/SkidSteerNav-v0", grid_map=grid_map, world_seed=1, observation=observation
        ).unwrapped

    logs = []
    for env, eval_env, trainer in (
        (FineStates(make("pose"), Discretization()), FineStates(make("pose"), Discretization()),
         train_agent),
        (make("discrete"), make("discrete"), train_agent_fast),
    ):  # fmt: skip
        agent = make_agent("q-learning", 12_500, 4, {}, np.random.default_rng(0))
        env.reset(seed=0)
        logs.append(trainer(agent, env, 8, max_steps=100, evaluation=Evaluation(eval_env, [1, 2])))
    assert np.array_equal(logs[0].returns, logs[1].returns)
    assert np.array_equal(logs[0].greedy_lengths, logs[1].greedy_lengths)


GAP_TOML = """
[experiment]
name = "gap"
episodes = 4
max_steps = 40
seeds = 1
root_seed = 3
oracle_samples = 2
bootstrap_samples = 100
convergence_window = 2
eval_rollouts = 1
optimum_grids = [[13, 13, 20], [25, 25, 20]]
optimum_samples = 2
optimum_rollouts = 3

[[maps]]
kind = "free"
options = { shape = [7, 7], min_distance = 2 }

[[agents]]
name = "q-learning"

[[agents]]
name = "q-learning"
label = "finer headings"
discretization = [7, 7, 40]

[[agents]]
name = "dyna-q"
label = "finer cells"
discretization = [13, 13, 20]
params = { planning_steps = 2 }
"""


def test_a_gap_study_runs_and_tabulates(tmp_path):
    config = parse_config(GAP_TOML)
    check_config(config)
    run_experiment(config, tmp_path, backend="serial")
    _, summaries = ResultStore(tmp_path).load_tables()
    assert summaries["oracle_length"].nunique() >= 2  # each grid its own L*
    assert summaries["optimum_length_m"].nunique() == 1  # one optimum per world
    rows = gap_rows(summaries, config)
    assert rows["grid"].tolist() == ["7 × 7 × 20", "7 × 7 × 40", "13 × 13 × 20"]
    lstar = {row["agent"]: row["oracle_length"] for _, row in summaries.iterrows()}
    assert rows["L* of its grid [actions]"].tolist() == [f"{lstar[a]:.2f}" for a in lstar]
    optimum = optimum_rows(summaries, config)
    assert optimum["best grid (worlds)"].iloc[0] in ("13 × 13 × 20 (1)", "25 × 25 × 20 (1)")
    gap = summaries["final_length_m"] / summaries["optimum_length_m"] - 1  # NaN if not reached
    shown = [f"{100 * g:.1f}" if g == g else "n/a" for g in gap]
    assert rows["gap to optimum [%]"].tolist() == shown
    assert "<h2>Discretization gap</h2>" in gap_section(summaries, config)
    # the report draws it as a section the commands pass (the report imports no study)
    page = write_results_report(tmp_path).path.read_text()
    assert page.count("<h2>Discretization gap</h2>") == 1
    assert "<h2>Discretization gap</h2>" not in build_report(tmp_path)


def test_the_optimum_is_the_best_policy_over_the_grids_and_its_check_leaves_the_finest_out():
    nan = float("nan")  # a grid whose policy never reached the goal
    optima = [
        Optimum(15.0, 0.55, 15.0, 1.0),
        Optimum(14.0, 0.48, 13.0, 1.0),  # best: every rollout reached the goal, fewest actions
        Optimum(13.5, 0.40, 11.0, 0.9),  # fewer actions, but 10 % of its rollouts got stuck
        Optimum(nan, nan, nan, 0.0),
    ]
    columns = optimum_columns(optima)
    assert columns["optimum_grid"] == 1 and columns["optimum_length_m"] == 0.48
    assert columns["optimum_rollout_actions"] == 13.0 and columns["optimum_actions"] == 14.0
    assert columns["optimum_check_length_m"] == 0.48  # the finest grid did not improve it
    finer = optimum_columns([*optima[:3], Optimum(13.0, 0.45, 12.5, 1.0)])
    assert finer["optimum_grid"] == 3 and finer["optimum_check_rollout_actions"] == 13.0
    alone = optimum_columns(optima[:1])
    assert alone["optimum_grid"] == 0 and np.isnan(alone["optimum_check_length_m"])


def test_config_without_the_new_keys_keeps_its_dict():
    config = parse_config(GAP_TOML.replace("optimum_grids", "# optimum_grids"))
    data = config_to_dict(config)
    assert "optimum_grids" not in data and "discretization" not in data["agents"][0]
    assert data["agents"][2]["discretization"] == [13, 13, 20]
    assert config_from_dict(data) == config


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ("discretization = [13, 13, 20]", None),
        (
            "discretization = [13, 13]",
            r"^expected agent 'finer cells' discretization to be \[n_x, n_y, n_headings\] .*, "
            r"got \(13, 13\) in a\.toml: \[\[agents\]\] #3$",
        ),
        (
            'discretization = "fine"',
            r"^expected discretization to be \[n_x, n_y, n_headings\], got 'fine' "
            r"in a\.toml: \[\[agents\]\] #3$",
        ),
        (
            "discretization = [14, 13, 20]",
            r"^expected n_x − 1 to be a multiple of 6 .*, got 14 "
            r"in a\.toml: agent 'finer cells' discretization on map 'free'$",
        ),
        (
            "discretization = [1000, 1000, 1000]",
            r"^expected agent 'finer cells' discretization of at most 5,000,000 states, "
            r"got 1,000,000,000 in a\.toml: \[\[agents\]\] #3$",
        ),
    ],
)
def test_the_discretization_key_is_checked_in_one_line(change, message):
    text = GAP_TOML.replace("discretization = [13, 13, 20]", change)
    if message is None:
        check_config(parse_config(text))
        return
    with pytest.raises(UserError, match=message) as error:
        check_config(parse_config(text, "a.toml"), "a.toml")
    assert "\n" not in str(error.value)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            "optimum_grids = 5",
            r"^expected optimum_grids to be a list of \[n_x, n_y, n_headings\], got 5 "
            r"in a\.toml: \[experiment\]$",
        ),
        (
            "optimum_grids = [[13, 13]]",
            r"^expected each of optimum_grids to be \[n_x, n_y, n_headings\] .*, got \(13, 13\) "
            r"in a\.toml: \[experiment\]$",
        ),
        (
            'optimum_grids = [["13", 13, 20]]',
            r"^expected each of optimum_grids to be .* in a\.toml: \[experiment\]$",
        ),
        (
            "optimum_grids = [[13, 14, 20]]",
            r"^expected n_y − 1 to be a multiple of 6 .*, got 14 "
            r"in a\.toml: optimum_grids on map 'free'$",
        ),
        (
            "optimum_samples = 0",
            r"^expected optimum_samples to be an integer in \[1, 1000\], got 0 "
            r"in a\.toml: \[experiment\]$",
        ),
        (
            "optimum_rollouts = 1.5",
            r"^expected optimum_rollouts to be an integer .*, got 1\.5 in a\.toml: \[experiment\]$",
        ),
    ],
)
def test_a_bad_optimum_setting_is_one_line_naming_it(change, message):
    key = change.split(" = ")[0]
    old = next(line for line in GAP_TOML.splitlines() if line.startswith(f"{key} = "))
    text = GAP_TOML.replace(old, change)
    with pytest.raises(UserError, match=message) as error:
        check_config(parse_config(text, "a.toml"), "a.toml")
    assert "\n" not in str(error.value)


@pytest.mark.parametrize(
    ("agent", "message"),
    [
        ('name = "dyna-kinematic"', "plans on the environment's own cells"),
        ('name = "linear-q"', "only tabular agents take a discretization"),
    ],
)
def test_agents_that_cannot_use_finer_cells_are_refused(agent, message):
    text = GAP_TOML.replace('name = "dyna-q"', agent).replace("params = { planning_steps = 2 }", "")
    with pytest.raises(UserError, match=message):
        check_config(parse_config(text, "a.toml"), "a.toml")


def test_the_table_printer_refuses_a_directory_without_results(tmp_path, capsys):
    from skidnav.studies.gap import main

    assert main([str(tmp_path / "none")]) == 2
    error = capsys.readouterr().err
    assert error.startswith("skidnav: error: ") and error.count("\n") == 1
