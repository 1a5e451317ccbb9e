"""A config names environments by registered id only: nothing named in it is ever imported or
called; a module's environments need the user's ``--env-module``."""

from __future__ import annotations

import pickle
import subprocess
import sys
from pathlib import Path

import gymnasium
import pytest

from skidnav.cli import main
from skidnav.envs import registration
from skidnav.errors import UserError
from skidnav.experiments.config_checks import check_config
from skidnav.experiments.configfile import load_config, parse_config
from skidnav.experiments.runs import expand_runs
from skidnav.experiments.trial import default_trial, run_trial
from tests.experiments.exp_support import cli_command, cli_env

CONFIG = """
[experiment]
name = "hostile"
env_id = "{env_id}"
episodes = 2
seeds = 1

[env]
command = "touch {marker}"

[[agents]]
name = "q-learning"
"""


MAZE = """
[experiment]
name = "maze"
env_id = "{env_id}"
episodes = 3
max_steps = 200
seeds = 2
eval_rollouts = 1

[[agents]]
name = "dyna-q"
params = {{ planning_steps = 5 }}
"""


def _run(tmp_path: Path, env_id: str) -> tuple[subprocess.CompletedProcess[str], Path]:
    marker = tmp_path / "ran"
    config = tmp_path / "hostile.toml"
    config.write_text(CONFIG.format(env_id=env_id, marker=marker))
    result = subprocess.run(
        cli_command("run", str(config), "--out", str(tmp_path / "out")),
        capture_output=True, text=True, env=cli_env(), timeout=120,
    )  # fmt: skip
    return result, marker


def test_a_callable_named_in_a_config_is_not_called(tmp_path: Path) -> None:
    for env_id in ("os:system", "subprocess:getoutput"):
        result, marker = _run(tmp_path, env_id)
        assert result.returncode == 2, result.stderr
        assert not marker.exists()
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and env_id in lines[0], result.stderr
        assert not (tmp_path / "out").exists()


def test_the_mazes_are_registered_ids() -> None:
    import gymnasium

    import skidnav  # noqa: F401

    for env_id in ("skidnav/DynaMaze-v0", "skidnav/BlockingMaze-v0", "skidnav/ShortcutMaze-v0"):
        assert gymnasium.make(env_id).unwrapped.shortest_path_length() > 0


PLANTED = "open({marker!r}, 'a').write('imported ')\n"
"""A module that leaves a mark when it is imported."""


def test_a_module_beside_the_config_is_never_imported(tmp_path: Path) -> None:
    """``python -m skidnav.cli`` run from the config's folder has that folder on sys.path: a
    module there named by ``env_id`` stays unimported, as does a standard one (``this`` prints
    the Zen of Python)."""
    marker = tmp_path / "imported"
    (tmp_path / "planted.py").write_text(PLANTED.format(marker=str(marker)))
    for env_id in ("planted:Planted-v0", "this:Zen-v0"):
        config = tmp_path / "hostile.toml"
        config.write_text(CONFIG.format(env_id=env_id, marker=tmp_path / "ran"))
        result = subprocess.run(
            cli_command("run", config.name, "--out", "out"),
            capture_output=True, text=True, env=cli_env(), timeout=120, cwd=tmp_path,
        )  # fmt: skip
        assert result.returncode == 2, result.stderr
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and f"env_id {env_id!r}: module" in lines[0], result.stderr
        assert "--env-module" in lines[0] and "Beautiful is better" not in result.stdout
        assert not marker.exists() and not (tmp_path / "out").exists()


def test_an_unregistered_env_id_is_refused_in_one_line(tmp_path: Path) -> None:
    config = tmp_path / "hostile.toml"
    config.write_text(CONFIG.format(env_id="skidnav/NoSuchMaze-v0", marker=tmp_path / "ran"))
    with pytest.raises(
        UserError, match=r"^env_id 'skidnav/NoSuchMaze-v0' is not a .* in \S*hostile\.toml$"
    ):
        check_config(load_config(config), config)


def _extra_mazes(folder: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A module ``extra_mazes`` in ``folder`` (on sys.path) registering Sutton & Barto's Dyna
    Maze as ``extra/Maze-v0``; no module allowed yet."""
    monkeypatch.setattr(registration, "_allowed_modules", set())
    (folder / "extra_mazes.py").write_text(
        "import gymnasium\n"
        "gymnasium.register(id='extra/Maze-v0', entry_point='skidnav.envs.mazes:dyna_maze')\n"
    )
    monkeypatch.syspath_prepend(str(folder))


def test_an_allowed_module_registers_its_environment(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--env-module MODULE`` (never the config) imports MODULE, whose environments the config
    may then name as ``MODULE:Env-v0``."""
    _extra_mazes(tmp_path, monkeypatch)
    config = tmp_path / "maze.toml"
    config.write_text(MAZE.format(env_id="extra_mazes:extra/Maze-v0"))
    argv = ["run", str(config), "--out", str(tmp_path / "out"), "--no-progress"]
    assert main(argv) == 2 and "extra_mazes" not in sys.modules
    assert main([*argv, "--env-module", "extra_mazes"]) == 0
    assert len(list((tmp_path / "out" / "runs").glob("run-*.npz"))) == 2


def test_a_worker_imports_the_allowed_modules_before_its_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The trial a worker process receives imports the modules allowed in the parent first: here
    a fresh process is played by forgetting the module, its registration and the allow-list."""
    _extra_mazes(tmp_path, monkeypatch)
    registration.allow_env_modules(["extra_mazes"])
    trial = pickle.loads(pickle.dumps(default_trial()))
    spec = expand_runs(parse_config(MAZE.format(env_id="extra_mazes:extra/Maze-v0")))[0]
    monkeypatch.setattr(registration, "_allowed_modules", set())
    monkeypatch.delitem(sys.modules, "extra_mazes")
    monkeypatch.delitem(gymnasium.registry, "extra/Maze-v0")
    with pytest.raises(UserError, match="module 'extra_mazes' is not allowed"):
        run_trial(spec)
    assert trial(spec).run_id == spec.run_id


@pytest.mark.parametrize(
    ("module", "message"),
    [
        ("no_such_module_here", "^--env-module no_such_module_here: No module named"),
        ("os; rm", "^--env-module: expected a dotted module name, got 'os; rm'$"),
        ("", "^--env-module: expected a dotted module name, got ''$"),
    ],
)
def test_a_bad_env_module_is_one_line(module: str, message: str) -> None:
    with pytest.raises(UserError, match=message):
        registration.allow_env_modules([module])
