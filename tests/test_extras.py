"""The light core and its extras: with an extra's modules absent, every command, agent or backend
that needs it refuses in one line naming ``pip install "skidnav[EXTRA]"``, with exit code 2,
before any work starts (nothing written); the rest of the command line works without them."""

from __future__ import annotations

import json
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from skidnav import extras
from skidnav.errors import UserError

ROOT = Path(__file__).resolve().parents[1]
EVERY_EXTRA = sorted({module for modules in extras.EXTRAS.values() for module in modules})
RUNNER = """
import contextlib, io, json, sys
for name in json.loads(sys.argv[1]):
    sys.modules[name] = None  # import name: ModuleNotFoundError, as when it is not installed
from skidnav.cli import main
for argv in json.loads(sys.argv[2]):
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        try:
            code = main(argv)
        except SystemExit as leave:
            code = leave.code
    print(json.dumps({"argv": argv, "code": code, "err": err.getvalue(), "out": out.getvalue()}))
"""
MUJOCO_CONFIG = """[experiment]
name = "mj"
episodes = 2
seeds = 1
[env]
dynamics = "mujoco"
[[maps]]
kind = "free"
[[agents]]
name = "q-learning"
"""
DQN_CONFIG = MUJOCO_CONFIG.replace('dynamics = "mujoco"', 'observation = "pose"').replace(
    '"q-learning"', '"dqn"'
)


def run_blocked(
    blocked: list[str], commands: list[list[str]], cwd: Path
) -> list[dict[str, object]]:
    """Each of ``commands`` run by ``skidnav.cli.main`` in one new interpreter in which the
    modules ``blocked`` cannot be imported; their exit codes and output."""
    result = subprocess.run(
        [sys.executable, "-c", RUNNER, json.dumps(blocked), json.dumps(commands)],
        capture_output=True, text=True, cwd=cwd, timeout=600, check=True,
    )  # fmt: skip
    return [json.loads(line) for line in result.stdout.splitlines()]


def refusals(tmp_path: Path) -> dict[str, tuple[list[str], str]]:
    """Command → (its arguments, the extra it needs); each writes into ``tmp_path/out-N``."""
    (tmp_path / "mujoco.toml").write_text(MUJOCO_CONFIG)
    (tmp_path / "dqn.toml").write_text(DQN_CONFIG)
    (tmp_path / "small.toml").write_text(MUJOCO_CONFIG.replace('dynamics = "mujoco"', ""))
    robot_run = ["robot", "run", "--agent", "q-learning", "--driver"]
    cases = {
        "dqn in a config": (["run", "dqn.toml"], "deep"),
        "study generalise (dqn by default)": (["study", "generalise"], "deep"),
        "study continuity (cmaes by default)": (["study", "continuity"], "search"),
        "study search": (["study", "search"], "search"),
        "study kinematic compare (gp by default)": (["study", "kinematic", "compare"], "gp"),
        "tune": (["tune", str(ROOT / "configs" / "tune-thesis.toml")], "tuning"),
        "--backend dask": (["run", "small.toml", "--backend", "dask"], "distributed"),
        "dynamics mujoco": (["run", "mujoco.toml"], "physics"),
        "study transfer": (["study", "transfer"], "physics"),
        "camera markers": (["camera", "markers"], "camera"),
        "camera board": (["camera", "board"], "camera"),
        "robot run --driver ros2": ([*robot_run, "ros2"], "ros2"),
        "robot run --driver serial": ([*robot_run, "serial"], "serial"),
    }  # fmt: skip
    return {
        name: ([*argv, "--out", str(tmp_path / f"out-{number}")], extra)
        for number, (name, (argv, extra)) in enumerate(cases.items())
    }


def check_refused(outcome: dict[str, object], extra: str) -> None:
    """One line naming the extra's install, exit code 2, nothing written."""
    lines = str(outcome["err"]).splitlines()
    assert outcome["code"] == 2, outcome
    assert len(lines) == 1 and lines[0].startswith("skidnav: error: "), outcome
    assert f"needs the {extra} extra (no module " in lines[0]
    assert lines[0].endswith(f'pip install "skidnav[{extra}]"')
    argv = list(outcome["argv"])  # type: ignore[call-overload]
    assert not Path(argv[argv.index("--out") + 1]).exists(), outcome


def test_every_command_needing_a_missing_extra_refuses_before_any_work(tmp_path: Path) -> None:
    cases = refusals(tmp_path)
    commands = [argv for argv, _ in cases.values()]
    physics = ["robot", "sim-server", "--port", "0", "--physics", "mujoco"]
    outcomes = run_blocked(EVERY_EXTRA, [*commands, physics, ["--help"]], tmp_path)
    for (name, (_, extra)), outcome in zip(cases.items(), outcomes, strict=False):
        assert outcome["argv"] == cases[name][0]
        check_refused(outcome, extra)
    server, helped = outcomes[-2:]
    assert server["code"] == 2 and 'pip install "skidnav[physics]"' in str(server["err"])
    assert helped["code"] == 0 and "study" in str(helped["out"])  # every command still lists


def test_a_default_deep_learner_is_refused_up_front(tmp_path: Path) -> None:
    """The continuity study's default learners include PPO and SAC: without the deep extra (the
    search extra present) it refuses naming the first of them, before any learner trains."""
    out = tmp_path / "continuity"
    (outcome,) = run_blocked(
        ["torch", "stable_baselines3"], [["study", "continuity", "--out", str(out)]], tmp_path
    )
    check_refused(outcome, "deep")
    assert "learner 'ppo'" in str(outcome["err"])


def test_require_names_the_extra_and_its_install(monkeypatch: pytest.MonkeyPatch) -> None:
    assert extras.installed("physics") == (extras.missing_module("physics") is None)
    monkeypatch.setitem(sys.modules, "optuna", None)
    assert extras.missing_module("tuning") == "optuna" and not extras.installed("tuning")
    with pytest.raises(UserError) as refused:
        extras.require("tuning", "skidnav tune")
    assert str(refused.value) == (
        "skidnav tune needs the tuning extra (no module 'optuna'): pip install \"skidnav[tuning]\""
    )
    installed = [extra for extra in extras.EXTRAS if extras.installed(extra)]
    for extra in installed:
        extras.require(extra, "anything")  # returns


def test_every_extra_is_in_pyproject_and_in_all() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    optional = project["optional-dependencies"]
    assert set(extras.EXTRAS) <= set(optional)
    assert optional["all"] == [f"skidnav[{','.join(extras.EXTRAS)}]"]
    core = " ".join(project["dependencies"])
    for heavy in ("opencv", "dask", "optuna", "roslibpy", "pyserial", "mujoco", "torch", "cmaes"):
        assert heavy not in core
