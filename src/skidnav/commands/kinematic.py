"""``skidnav study kinematic compare``: the Bayesian-ridge and the Gaussian-process kinematic
models on held-out sub-steps of the fast simulator (docs/gp-kinematic.md).

Per seed: drive the env ``skidnav/SkidSteerNav-v0`` with uniformly random actions until
``--samples`` free sub-steps are logged (``info["kinematic_log"]``), fit both models on the first
``--train-fraction`` of them in time order and score their predictions of the later ones from
(region, commanded wheel speeds): RMSE, coverage of the central 90 % predictive interval and its
mean width per output, and the fit time. Means over seeds with 95 % percentile-bootstrap intervals
(:func:`skidnav.stats.bootstrap_interval`).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from statistics import NormalDist
from typing import NamedTuple

import numpy as np

from skidnav.errors import UserError
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.seeding import ARENA_ROLES, child_sequences, seed_int

LEVEL = 0.90
"""Level of the central predictive interval whose coverage is measured."""
Z_LEVEL = NormalDist().inv_cdf(0.5 + LEVEL / 2.0)
"""Half-width of the central :data:`LEVEL` interval in standard deviations (1.645)."""
OUTPUTS = ("v_x", "v_y", "yaw_rate")
MODELS = ("ridge", "gp")
MAX_SAMPLES = 1_000_000
MAX_SEEDS = 1000

Predictor = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
"""(regions (n,), commanded wheels (n, 2)) → (mean, std), each (n, 3)."""


class Score(NamedTuple):
    """One model's held-out score on one seed: per output (v_x, v_y, yaw_rate), shape (3,)."""

    rmse: np.ndarray
    """Root-mean-square error of the mean [m/s, m/s, rad/s]."""
    coverage: np.ndarray
    """Fraction of held-out samples inside the central 90 % interval."""
    width: np.ndarray
    """Mean width of that interval [m/s, m/s, rad/s]."""
    fit_seconds: float
    """Wall time of the fit [s]."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``kinematic`` with its ``compare`` subcommand."""
    parser = subparsers.add_parser("kinematic", help="learned kinematic models")
    actions = parser.add_subparsers(dest="kinematic_command", required=True)
    compare = actions.add_parser(
        "compare", help="Bayesian ridge vs Gaussian process on held-out simulated sub-steps"
    )
    compare.add_argument("--seeds", type=int, default=5, help="seeds 0..N-1 (worlds and drives)")
    compare.add_argument("--samples", type=int, default=20_000, help="sub-steps logged per seed")
    compare.add_argument("--slip", choices=SLIP_PRESETS, default="slippery", help="slip preset")
    compare.add_argument("--drift", type=float, default=0.0, help="drift amplitude A (0: none)")
    compare.add_argument(
        "--drift-period", type=float, help="drift period [s] (default: the logged time)"
    )
    compare.add_argument(
        "--train-fraction", type=float, default=0.5, help="first part of the log fitted on"
    )
    compare.add_argument("--window", type=int, default=500, help="samples kept per region")
    compare.set_defaults(func=_compare)


def _check(args: argparse.Namespace) -> None:
    from skidnav.models.gp_kinematic import MAX_WINDOW

    if not 1 <= args.seeds <= MAX_SEEDS:
        raise UserError(f"expected --seeds in [1, {MAX_SEEDS}], got {args.seeds}")
    if not 100 <= args.samples <= MAX_SAMPLES:
        raise UserError(f"expected --samples in [100, {MAX_SAMPLES:,}], got {args.samples}")
    if not (np.isfinite(args.drift) and args.drift >= 0):
        raise UserError(f"expected --drift >= 0, got {args.drift}")
    period = args.drift_period
    if period is not None and not (np.isfinite(period) and period > 0):
        raise UserError(f"expected --drift-period > 0 s, got {args.drift_period}")
    if not 0.1 <= args.train_fraction <= 0.9:
        raise UserError(f"expected --train-fraction in [0.1, 0.9], got {args.train_fraction}")
    if not 20 <= args.window <= MAX_WINDOW:
        raise UserError(f"expected --window in [20, {MAX_WINDOW}], got {args.window}")


def _compare(args: argparse.Namespace) -> int:
    _check(args)
    from skidnav.robot.params import RobotParams

    period = args.drift_period or args.samples * RobotParams().dt
    scores: dict[str, list[Score]] = {name: [] for name in MODELS}
    for seed in range(args.seeds):
        log = drive_log(seed, args.samples, args.slip, args.drift, period)
        for name, score in compare_models(log, args.train_fraction, args.window).items():
            scores[name].append(score)
    n_train = int(args.train_fraction * args.samples)
    print(
        f"{args.slip}, drift A = {args.drift:g} over P = {period:g} s; per seed "
        f"{args.samples:,} sub-steps ({args.samples * RobotParams().dt:g} s): the first "
        f"{n_train:,} fitted, the other {args.samples - n_train:,} predicted; window "
        f"{args.window}; means over {args.seeds} seeds [95 % bootstrap interval]"
    )
    print_table(scores)
    return 0


def drive_log(seed: int, samples: int, slip: str, drift: float, period: float) -> np.ndarray:
    """The first ``samples`` free sub-steps (rows of ``LOG_COLUMNS``), shape (samples, 6), of
    uniformly random actions in the world of ``seed`` (map and floor as the env's
    ``world_seed``; the env's reset seed and the actions from the ARENA_ROLES "robot" and
    "agent" children). Episodes ending at the goal or the time limit restart without a seed,
    so the slip clock runs on."""
    import gymnasium

    from skidnav.envs.registration import ENV_ID, register_envs

    register_envs()
    env = gymnasium.make(
        ENV_ID, world_seed=seed, slip=slip, drift_amplitude=drift, drift_period=period
    )
    children = child_sequences(seed, ARENA_ROLES)
    actions = np.random.default_rng(children["agent"])
    env.reset(seed=seed_int(children["robot"]))
    parts, n_rows = [], 0
    while n_rows < samples:
        _, _, terminated, truncated, info = env.step(int(actions.integers(4)))
        parts.append(info["kinematic_log"])
        n_rows += len(info["kinematic_log"])
        if terminated or truncated:
            env.reset()
    env.close()
    return np.concatenate(parts)[:samples]


def compare_models(log: np.ndarray, train_fraction: float, window: int) -> dict[str, Score]:
    """Fit both models on the first ``train_fraction`` of ``log`` (n, 6), score them on the
    rest (:func:`score`)."""
    from skidnav.models.gp_kinematic import GaussianProcessConfig, GaussianProcessKinematicModel
    from skidnav.models.kinematic import KinematicModel, KinematicModelConfig
    from skidnav.robot.params import RobotParams
    from skidnav.world.discretization import Discretization

    split = int(train_fraction * len(log))
    train, test = log[:split], log[split:]
    grid = Discretization()
    ridge = KinematicModel(RobotParams(), grid, KinematicModelConfig(window=window))
    gp = GaussianProcessKinematicModel(grid.n_regions, GaussianProcessConfig(window=window))
    fitted: dict[str, tuple[Predictor, float]] = {}
    for name, model, predictor in (
        ("ridge", ridge, ridge.predict_twist),
        ("gp", gp, gp.predict),
    ):
        start = time.perf_counter()
        model.feed(train)
        model.refit()
        fitted[name] = (predictor, time.perf_counter() - start)
    return {name: score(p, test, seconds) for name, (p, seconds) in fitted.items()}


def score(predictor: Predictor, test: np.ndarray, fit_seconds: float) -> Score:
    """Held-out RMSE, 90 % coverage and width of ``predictor`` on log rows ``test`` (n, 6);
    samples without a finite prediction are left out."""
    mean, std = predictor(test[:, 0].astype(np.int64), test[:, 1:3])
    truth = test[:, 3:6]
    error = np.where(np.isfinite(mean) & np.isfinite(std), truth - mean, np.nan)
    half = Z_LEVEL * std
    return Score(
        rmse=np.sqrt(np.nanmean(error**2, axis=0)),
        coverage=np.nanmean(np.where(np.isnan(error), np.nan, np.abs(error) <= half), axis=0),
        width=np.nanmean(np.where(np.isnan(error), np.nan, 2.0 * half), axis=0),
        fit_seconds=fit_seconds,
    )


def print_table(scores: dict[str, list[Score]]) -> None:
    """One row per model and output: each metric's mean over seeds [95 % bootstrap interval]."""
    from skidnav.stats import bootstrap_interval

    rng = np.random.default_rng(0)
    header = ("RMSE [mm/s | mrad/s]", "90 % coverage", "width [mm/s | mrad/s]", "fit [s]")
    widths, digits = (26, 24, 26, 22), (2, 3, 2, 2)
    titles = [f"{title:>{width}s}" for title, width in zip(header, widths, strict=True)]
    print(f"{'model':6s} {'output':9s} " + " ".join(titles))
    for name, runs in scores.items():
        for k, output in enumerate(OUTPUTS):
            metrics = (
                [1000 * run.rmse[k] for run in runs],
                [run.coverage[k] for run in runs],
                [1000 * run.width[k] for run in runs],
                [run.fit_seconds for run in runs],
            )
            cells = [
                f"{_cell(bootstrap_interval(values, rng), d):>{w}s}"
                for values, d, w in zip(metrics, digits, widths, strict=True)
            ]
            print(f"{name:6s} {output:9s} " + " ".join(cells))


def _cell(interval: tuple[float, float, float], digits: int) -> str:
    """``estimate [low, high]``."""
    estimate, low, high = interval
    return f"{estimate:.{digits}f} [{low:.{digits}f}, {high:.{digits}f}]"
