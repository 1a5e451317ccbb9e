"""``mppi-kinematic`` learning online on the sim robot: its model refits and cost-map recomputes
run off the control path (a refit made slower than three control periods leaves the period
held), the learned model and map survive a SIGKILL and continue with ``--resume``, and the
safety guarantees of the tabular loop hold for it (a lost pose trips, stops and the run goes on;
a robot frozen mid-action never resumes the old command; SIGINT stops the wheels and ends the
run)."""

from __future__ import annotations

import json
import signal
import time
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import pytest

from skidnav.agents.mpc.agent import MPPIKinematicAgent, make_mppi_agent
from skidnav.agents.mpc.loading import load_mppi_agent
from skidnav.agents.mpc.training import train_mppi
from skidnav.cli import main
from skidnav.models.kinematic import KinematicModel
from skidnav.realtime.control.checkpoint import Checkpoints
from tests.realtime.realtime_helpers import (
    ServerThread,
    read_events,
    start_run,
    wait_for,
    write_config,
)
from tests.realtime.test_policy_run import inject_after_transitions
from tests.realtime.test_stall import check_stall

PERIOD = 0.1
RUN = {
    "episodes": 1, "max_actions": 150, "time_scale": 1.0, "period": PERIOD, "substeps": 1,
    "settle_periods": 0, "map": '"free"', "seed": 0, "reconnect_timeout": 8.0,
    "homing_timeout": 60.0,
}  # fmt: skip
"""One action per 0.1-s control period, in real time, on the free map of seed 0."""
SLOW_REFIT = 0.3
"""Seconds added to every refit in the first test: three control periods."""


def config(tmp_path: Path, sim: str = "", **run: object) -> Path:
    text = "[run]\n" + "".join(f"{k} = {v}\n" for k, v in {**RUN, **run}.items())
    return write_config(tmp_path, text + "[sim]\n" + sim)


def agent_at(directory: Path) -> MPPIKinematicAgent:
    return load_mppi_agent(directory / "agent.json")


def test_refits_run_off_the_control_path_and_the_period_holds(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The sim server with 50 ms of latency, pose noise and 5 % of poses dropped; every refit
    takes 0.3 s more than it does: were it on the control path, each would stretch a period
    fourfold."""
    refit = KinematicModel.refit

    def slow_refit(model: KinematicModel) -> None:
        time.sleep(SLOW_REFIT)
        refit(model)

    monkeypatch.setattr(KinematicModel, "refit", slow_refit)
    out = tmp_path / "out"
    sim = "latency = 0.05\npose_noise = 0.001\ndrop = 0.05\n"
    argv = ["robot", "run", "--quiet", "--config", str(config(tmp_path, sim)), "--out", str(out)]
    assert main([*argv, "--agent", "mppi-kinematic"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    learning, period = summary["learning"], summary["control_period"]
    events = read_events(out / "run.jsonl")
    transitions = [e for e in events if e["event"] == "transition"]
    refits = [e for e in events if e["event"] == "learned" and e["refit"]]
    assert learning["refits"] == len(refits) >= 2  # at 50 and 100 logged periods
    assert all(e["seconds"] >= SLOW_REFIT for e in refits)
    assert learning["steps"] == len(transitions)  # every action learned, none twice
    assert period["count"] == len(transitions) - 1
    assert period["median"] == pytest.approx(PERIOD, rel=0.05)
    assert period["p95"] <= 1.2 * PERIOD
    # the period around each refit that ran while the robot drove (a learner that lags on a
    # loaded machine may run one after the last action, while the loop waits for it): the
    # decisions while it ran came on time
    decisions = np.array([e["mono"] for e in transitions])
    while_driving = [e for e in refits if e["mono"] - e["seconds"] < decisions[-1] - 2.5 * PERIOD]
    assert while_driving
    for event in while_driving:
        started = event["mono"] - event["seconds"]
        during = decisions[(decisions > started) & (decisions < event["mono"])]
        assert len(during) >= 2
        assert np.diff(during).max() <= 1.5 * PERIOD
    # the checkpoint holds what was learned: every logged period in the model
    learned = agent_at(out / "checkpoints" / "ep-00000")
    assert learned.model.refits == len(refits)
    assert int(learned.model.counts.sum()) == sum(t["log_rows"] for t in transitions)
    assert learned.episodes == 1 and learned.steps == len(transitions)


def test_the_learned_model_and_map_survive_a_sigkill(tmp_path: Path) -> None:
    out = tmp_path / "out"
    path = config(tmp_path, episodes=3, max_actions=40, time_scale=5.0)
    run = start_run(tmp_path, "--agent", "mppi-kinematic", "--config", str(path))
    try:
        wait_for(lambda: (out / "checkpoints" / "latest.json").exists(), 120.0, "a checkpoint")
        run.send_signal(signal.SIGKILL)
        run.wait(timeout=10)
    finally:
        if run.poll() is None:
            run.kill()
        run.communicate()
    latest = Checkpoints(out / "checkpoints").latest()
    assert latest is not None
    episode, directory, _ = latest
    before = agent_at(directory)
    saved = {name: array.copy() for name, array in before.state_arrays().items()}
    assert int(before.model.counts.sum()) > 0 and before.evidence.passes.sum() > 0
    argv = ["robot", "run", "--quiet", "--config", str(path), "--out", str(out), "--resume"]
    assert main([*argv, "--agent", "mppi-kinematic", "--episodes", str(episode + 2)]) == 0
    after = agent_at(out / "checkpoints" / f"ep-{episode + 1:05d}")
    assert after.episodes == before.episodes + 1 and after.steps > before.steps
    # the resumed run went on from the saved arrays: the model's samples of every region start
    # with those saved, and the map's counts only grew
    counts = saved["kinematic_counts"]
    for region in np.flatnonzero(counts):
        kept = saved["kinematic_data"][region, : counts[region]]
        np.testing.assert_array_equal(after.model.data[region, : counts[region]], kept)
    for name in ("hits", "passes", "ray_ends", "ray_crossings"):
        assert (getattr(after.evidence, name) >= saved[name]).all(), name
    assert int(after.model.counts.sum()) > int(counts.sum())
    results = json.loads((out / "summary.json").read_text())
    assert results["episodes"] == episode + 2


def test_a_lost_pose_trips_stops_and_the_learner_keeps_what_it_learned(tmp_path: Path) -> None:
    """The ``silence`` fault mid-episode: the watchdog trips on the stale pose, the stop is
    confirmed, the episode is aborted (its unfinished action not learned), the run reconnects
    and completes its episodes."""
    out = tmp_path / "out"
    with ServerThread(5.0, log=tmp_path / "server.jsonl", faults=("silence",)) as server:
        path = config(tmp_path, episodes=2, max_actions=40, time_scale=5.0)
        path.write_text(path.read_text() + f"[tcp]\nport = {server.port}\n")
        injector = inject_after_transitions(server, out, 5)
        argv = ["robot", "run", "--quiet", "--driver", "tcp", "--config", str(path)]
        assert main([*argv, "--agent", "mppi-kinematic", "--out", str(out)]) == 0
        injector.join(timeout=5)
    events = read_events(out / "run.jsonl")
    trip = next(e for e in events if e["event"] == "trip")
    assert "pose stale" in trip["reason"]
    stops = [e["confirmed"] for e in events if e["event"] == "stopped"]
    assert stops and all(stops)  # one per trip (a loaded machine may add a late-pose trip)
    assert any(e["event"] == "reconnected" for e in events)
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["episodes"], summary["exit_code"]) == (2, 0)
    assert summary["aborted"] >= 1
    transitions = [e for e in events if e["event"] == "transition"]
    assert summary["learning"]["steps"] == len(transitions)
    learned = agent_at(out / "checkpoints" / "ep-00001")
    assert learned.steps == len(transitions) and learned.episodes == 2


def test_sigint_stops_the_wheels_and_ends_the_run_with_a_checkpoint(tmp_path: Path) -> None:
    out = tmp_path / "out"
    path = config(tmp_path, episodes=5, max_actions=200, time_scale=5.0)
    run = start_run(tmp_path, "--agent", "mppi-kinematic", "--config", str(path))
    try:
        wait_for(
            lambda: sum(e["event"] == "transition" for e in read_events(out / "run.jsonl")) > 10,
            120.0,
            "ten actions",
        )
        run.send_signal(signal.SIGINT)
        assert run.wait(timeout=30) == 130
    finally:
        if run.poll() is None:
            run.kill()
        run.communicate()
    events = read_events(out / "run.jsonl")
    trip = next(e for e in events if e["event"] == "trip")
    assert "SIGINT" in trip["reason"]
    stopped = next(e for e in events if e["event"] == "stopped")
    assert stopped["confirmed"] and stopped["delay"] < 0.5
    assert events[-1]["event"] != "cmd" or events[-1]["omega_left"] == 0.0
    latest = Checkpoints(out / "checkpoints").latest()
    assert latest is not None and latest[2]["results"][-1]["aborted"]
    assert agent_at(latest[1]).steps > 0


@pytest.fixture(scope="module")
def saved_mppi(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An agent trained one episode of 0.1-s actions in the simulator on the run's world, saved
    by itself (no world.json beside it)."""
    env = gymnasium.make(
        "skidnav/SkidSteerNav-v0", map_kind="free", world_seed=0, slip="rough",
        action="continuous", observation="features", control_period=PERIOD, max_episode_steps=400,
    )  # fmt: skip
    agent = make_mppi_agent(env, {}, np.random.default_rng(0))
    train_mppi(agent, env, 1, seed=0)
    return agent.save(tmp_path_factory.mktemp("mppi") / "agent")[1]


def test_a_saved_mppi_agent_keeps_learning_from_its_model_and_map(
    saved_mppi: Path, tmp_path: Path
) -> None:
    out = tmp_path / "out"
    path = config(tmp_path, max_actions=40, time_scale=5.0)
    argv = ["robot", "run", "--quiet", "--config", str(path), "--out", str(out)]
    assert main([*argv, "--agent-file", str(saved_mppi)]) == 0
    saved, learned = load_mppi_agent(saved_mppi), agent_at(out / "checkpoints" / "ep-00000")
    transitions = [e for e in read_events(out / "run.jsonl") if e["event"] == "transition"]
    assert learned.steps == saved.steps + len(transitions)
    assert learned.episodes == saved.episodes + 1
    counts = saved.model.counts
    for region in np.flatnonzero(counts):
        np.testing.assert_array_equal(
            learned.model.data[region, : counts[region]], saved.model.data[region, : counts[region]]
        )
    assert int(learned.model.counts.sum()) == int(counts.sum()) + sum(
        t["log_rows"] for t in transitions
    )


@pytest.mark.parametrize(
    ("run", "message"),
    [
        ({"substeps": 10}, "it was trained with actions of 0.1 s, the run's last 1 s"),
        ({"map": '"obstacles"'}, "it was trained for the goal cell (6, 16), the run's map has"),
    ],
)
def test_a_saved_mppi_agent_of_another_world_is_refused(
    saved_mppi: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    run: dict[str, object],
    message: str,
) -> None:
    path = config(tmp_path, **{"settle_periods": 1, **run} if "substeps" in run else run)
    argv = ["robot", "run", "--config", str(path), "--out", str(tmp_path / "o")]
    assert main([*argv, "--agent-file", str(saved_mppi)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], lines
    assert not (tmp_path / "o").exists()


def test_a_robot_frozen_mid_action_never_resumes_the_old_command(
    tmp_path: Path, server_process: Any
) -> None:
    """The tabular loop's stall test (tests/realtime/test_stall.py) with mppi-kinematic: the
    server frozen (SIGSTOP) while its wheels turn; the host trips on the stale pose, its stop is
    confirmed once the robot lives again, no command from before the trip runs, the run
    reconnects."""
    server = server_process("--time-scale", "5.0")
    path = config(tmp_path, episodes=4, max_actions=100, time_scale=5.0)
    path.write_text(path.read_text() + f"[tcp]\nport = {server.port}\n")
    run = start_run(tmp_path, "--driver", "tcp", "--agent", "mppi-kinematic", "--config", str(path))
    try:
        check_stall(tmp_path / "out", run, server)
    finally:
        run.send_signal(signal.SIGINT)
        run.communicate(timeout=30)
