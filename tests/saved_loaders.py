"""Every loader of a file a user hands to skidnav, each with a valid file of its own: the catalog
that the hostile-file and property tests run through.

A :class:`Loader` writes valid files into an empty folder (``make``: the path to load and the
files a test may damage) and loads a path (``load``); whatever is wrong with the files, a load
may only succeed or raise :class:`~skidnav.errors.UserError` (its :class:`CorruptFileError`
included) in one line. The valid files are made once per test session (:func:`pristine`).
"""

from __future__ import annotations

import atexit
import dataclasses
import shutil
import tempfile
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

REPOSITORY = Path(__file__).resolve().parents[1]


class Loader(NamedTuple):
    """A loader and how to make valid files for it."""

    make: Callable[[Path], tuple[Path, list[Path]]]
    """Write valid files into an empty folder; (the path to load, the files to damage)."""
    load: Callable[[Path], Any]


def _experiment_config(folder: Path) -> tuple[Path, list[Path]]:
    from tests.experiments.exp_support import TINY_TOML

    path = folder / "tiny.toml"
    path.write_text(TINY_TOML)
    return path, [path]


def _tune_config(folder: Path) -> tuple[Path, list[Path]]:
    from tests.experiments.test_tune import TINY_TUNE

    path = folder / "tune.toml"
    path.write_text(TINY_TUNE)
    return path, [path]


def _realtime_config(folder: Path) -> tuple[Path, list[Path]]:
    path = folder / "realtime.toml"
    shutil.copy(REPOSITORY / "configs" / "realtime.toml", path)
    shutil.copytree(REPOSITORY / "configs" / "maps", folder / "maps")
    return path, [path]


def _map_file(folder: Path) -> tuple[Path, list[Path]]:
    from skidnav.world.grid import generate_map
    from skidnav.world.mapfile import save_map

    path = folder / "room.txt"
    save_map(generate_map("obstacles", np.random.default_rng(0), (12, 10)), path)
    return path, [path]


def _tabular_agent(folder: Path) -> tuple[Path, list[Path]]:
    from skidnav.agents.tabular.registry import make_agent

    agent = make_agent("dyna-q", 54, 4, {"planning_steps": 3}, np.random.default_rng(0))
    agent.q[:] = np.random.default_rng(1).random(agent.q.shape)
    npz, json_path = agent.save(folder / "agent")
    return folder / "agent", [json_path, npz]


def _linear_agent(folder: Path) -> tuple[Path, list[Path]]:
    from gymnasium.spaces import Box

    from skidnav.agents.linear.registry import make_linear_agent

    space = Box(low=np.zeros(3), high=np.ones(3), dtype=np.float64)
    agent = make_linear_agent("linear-q", space, 4, {"tiles": [4], "n_tilings": 2})
    npz, json_path = agent.save(folder / "linear")
    return folder / "linear", [json_path, npz]


def _linear_policy(folder: Path) -> tuple[Path, list[Path]]:
    """A linear agent over the feature observation (two rays): a wheel-speed policy."""
    from gymnasium.spaces import Box

    from skidnav.agents.linear.registry import make_linear_agent
    from skidnav.sim.features import feature_bounds

    space = Box(*feature_bounds((0.2, 0.2), 2, 0.1), dtype=np.float64)
    params = {"tiles": [3], "n_tilings": 2, "dimensions": [4, 5, 6]}
    npz, json_path = make_linear_agent("linear-q", space, 4, params).save(folder / "linear")
    return json_path, [json_path, npz]


def _dqn_policy(folder: Path) -> tuple[Path, list[Path]]:
    from skidnav.agents.deep.dqn import DQNAgent, DQNConfig
    from tests.agents.deep.test_dqn import tiny_env

    agent = DQNAgent(tiny_env("features"), DQNConfig(buffer_size=100, hidden=(8,)))
    npz, json_path = agent.save(folder / "dqn")
    return json_path, [json_path, npz]


def _kinematic_model(folder: Path) -> tuple[Path, list[Path]]:
    from skidnav.models.kinematic import KinematicModel
    from skidnav.models.kinematic_config import KinematicModelConfig
    from skidnav.models.kinematic_files import save_model
    from skidnav.robot.params import RobotParams
    from skidnav.world.discretization import Discretization

    grid = Discretization(n_x=6, n_y=5, n_headings=4, regions_x=2, regions_y=2)
    model = KinematicModel(RobotParams(), grid, KinematicModelConfig(window=8))
    save_model(model, folder / "model")
    return folder / "model", [folder / "model.json", folder / "model.npz"]


def _load_kinematic_model(path: Path) -> Any:
    from skidnav.models.kinematic_files import load_model

    return load_model(path)


def _tanh_policy(folder: Path) -> tuple[Path, list[Path]]:
    from skidnav.agents.policies.search.policy_file import save_policy
    from skidnav.agents.policies.search.tanh_policy import PolicyLayout, TanhPolicy

    layout = PolicyLayout(np.zeros(9), np.ones(9), hidden=2, wheel_speed=1.7, lidar_rays=2)
    parameters = np.linspace(-1.0, 1.0, layout.n_parameters)
    npz, json_path = save_policy(TanhPolicy(layout, parameters), folder / "policy")
    return json_path, [json_path, npz]


def _ppo_policy(folder: Path) -> tuple[Path, list[Path]]:
    from tests.agents.deep.test_wheel_speed_agents import new_agent

    npz, json_path = new_agent("ppo").save(folder / "ppo")
    return json_path, [json_path, npz]


def _cma_checkpoint(folder: Path) -> tuple[Path, list[Path]]:
    from skidnav.agents.policies.search.cmaes import run_search
    from tests.agents.policies.test_search import TINY

    config = dataclasses.replace(TINY, generations=1, population=4, eval_every=1)
    run_search(config, checkpoint=folder / "checkpoint")
    return folder / "checkpoint", [folder / "checkpoint.npz", folder / "checkpoint.json"]


def _load_cma_checkpoint(path: Path) -> Any:
    from skidnav.agents.policies.search.checkpoint import load_checkpoint
    from skidnav.agents.policies.search.tanh_policy import parameter_count

    return load_checkpoint(path, parameter_count(7 + 8, 0))


def _realtime_checkpoint(folder: Path) -> tuple[Path, list[Path]]:
    from tests.saved_file_support import write_checkpoint

    directory = write_checkpoint(folder / "run")
    root = directory.parent
    return root, [root / "latest.json", directory / "loop.json"]


def _latest_checkpoint(root: Path) -> Any:
    from skidnav.realtime.control.checkpoint import Checkpoints

    return Checkpoints(root).latest()


def _calibration(folder: Path) -> tuple[Path, list[Path]]:
    from skidnav.realtime.camera.calibration import FloorCalibration
    from skidnav.realtime.camera.markers import ArenaLayout

    path = folder / "calibration.json"
    FloorCalibration(np.diag([0.001, 0.001, 1.0]), ArenaLayout(), (640, 480)).save(path)
    return path, [path]


def _intrinsics(folder: Path) -> tuple[Path, list[Path]]:
    from tests.realtime.camera_scenes import true_intrinsics

    path = folder / "intrinsics.json"
    true_intrinsics().save(path)
    return path, [path]


def _image(folder: Path) -> tuple[Path, list[Path]]:
    from skidnav.realtime.camera.opencv import cv2

    path = folder / "view.png"
    image = (np.arange(24 * 32 * 3) % 251).astype(np.uint8).reshape(24, 32, 3)
    cv2.imwrite(str(path), image)
    return path, [path]


def _results(folder: Path) -> tuple[Path, list[Path]]:
    from skidnav.experiments.configfile import parse_config
    from skidnav.experiments.runner import run_experiment
    from tests.experiments.exp_support import TINY_TOML

    text = TINY_TOML.replace("seeds = 2", "seeds = 1").replace(', "slippery"', "")
    text = text[: text.index('[[agents]]\nname = "dyna-q"')]
    run_experiment(parse_config(text), folder / "results", backend="serial")
    root = folder / "results"
    return root, sorted(root.glob("runs/run-*.npz"))


def _read_run(root: Path) -> Any:
    from skidnav.experiments.store import ResultStore

    store = ResultStore(root)
    return [store.read_run(run_id) for run_id in sorted(store.finished())]


def _tables(folder: Path) -> tuple[Path, list[Path]]:
    root, _ = _results(folder)
    return root, [root / "episodes.parquet", root / "summaries.parquet"]


def _load_tables(root: Path) -> Any:
    from skidnav.experiments.store import ResultStore

    return ResultStore(root).load_tables()


def _journal(folder: Path) -> tuple[Path, list[Path]]:
    import optuna

    from skidnav.studies.tuning.optuna_setup import open_storage

    path = folder / "journal.log"
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(storage=open_storage(path), study_name="tiny/q-learning")
    for value in (3.0, 1.0):
        trial = study.ask()
        trial.suggest_float("alpha", 0.05, 1.0)
        trial.report(value, 1)
        study.tell(trial, value)
    return path, [path]


def _import(target: str) -> Callable[[Path], Any]:
    """The function ``"module:name"``, imported when first called."""
    module, _, name = target.partition(":")

    def call(path: Path) -> Any:
        import importlib

        return getattr(importlib.import_module(module), name)(path)

    return call


DEEP_LOADERS = ("ppo policy", "dqn policy")
"""The loaders whose files need the ``deep`` extra to be made."""
LOADERS: dict[str, Loader] = {
    "experiment config": Loader(
        _experiment_config, _import("skidnav.experiments.configfile:load_config")
    ),
    "tune config": Loader(_tune_config, _import("skidnav.studies.tuning.config:load_tune_config")),
    "realtime config": Loader(_realtime_config, _import("skidnav.realtime.config:load_config")),
    "map file": Loader(_map_file, _import("skidnav.world.mapfile:load_map")),
    "tabular agent": Loader(_tabular_agent, _import("skidnav.agents.tabular.registry:load_agent")),
    "linear agent": Loader(
        _linear_agent, _import("skidnav.agents.linear.registry:load_linear_agent")
    ),
    "kinematic model": Loader(_kinematic_model, _load_kinematic_model),
    "tanh policy": Loader(_tanh_policy, _import("skidnav.agents.saved:load_policy")),
    "ppo policy": Loader(_ppo_policy, _import("skidnav.agents.saved:load_policy")),
    "linear policy": Loader(_linear_policy, _import("skidnav.agents.saved:load_policy")),
    "dqn policy": Loader(_dqn_policy, _import("skidnav.agents.saved:load_policy")),
    "CMA-ES checkpoint": Loader(_cma_checkpoint, _load_cma_checkpoint),
    "real-time checkpoint": Loader(_realtime_checkpoint, _latest_checkpoint),
    "calibration": Loader(
        _calibration, _import("skidnav.realtime.camera.calibration:load_calibration")
    ),
    "intrinsics": Loader(
        _intrinsics, _import("skidnav.realtime.camera.intrinsics:load_intrinsics")
    ),
    "image": Loader(_image, _import("skidnav.realtime.camera.imagefile:read_image")),
    "run file": Loader(_results, _read_run),
    "tidy tables": Loader(_tables, _load_tables),
    "tune journal": Loader(_journal, _import("skidnav.experiments.journalfile:check_journal")),
}
"""Name → loader (module doc)."""


@cache
def pristine(name: str) -> tuple[Path, Path, tuple[Path, ...]]:
    """(folder, path to load, files to damage) of valid files for loader ``name``, made once."""
    folder = Path(tempfile.mkdtemp(prefix=f"skidnav-{name.replace(' ', '-')}-"))
    atexit.register(shutil.rmtree, folder, True)
    path, files = LOADERS[name].make(folder)
    return folder, path, tuple(files)


def fresh_copy(name: str, into: Path) -> tuple[Path, list[Path]]:
    """A copy of :func:`pristine` files for ``name`` in the new folder ``into``; (the path to
    load, the files to damage), both in the copy."""
    folder, path, files = pristine(name)
    shutil.copytree(folder, into)
    return into / path.relative_to(folder), [into / file.relative_to(folder) for file in files]
