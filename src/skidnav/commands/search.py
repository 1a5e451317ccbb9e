"""``skidnav study search``: a tanh wheel-speed policy found by CMA-ES
(:mod:`skidnav.agents.policies.search`).

A shortcut: the flags make a ``kind = "policy-search"`` config of one search
(:mod:`skidnav.studies.policy_search`: one slip preset, one seed, the root seed ``--seed``),
which the runner runs into ``--out`` serially (the config saved there as ``config.toml``), with
the search's checkpoint in ``OUT/checkpoints/`` rewritten after every generation. The same
command on the same ``--out`` resumes: a finished search is not run again, one cut short
continues from its checkpoint. From the results it writes into ``--out``: ``policy.npz`` +
``policy.json`` (the final mean policy), ``curve.csv`` (one row per generation,
:class:`~skidnav.agents.policies.search.curve.GenerationRecord`) and ``search.json`` (the
search's config and the last row).
"""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING

from skidnav.commands.parsing import path_argument
from skidnav.commands.shortcut import FLAGS
from skidnav.errors import UserError
from skidnav.experiments.runs import expand_runs
from skidnav.files.outputs import check_output_dir
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.studies.loading import parse_grid, run_loaded
from skidnav.studies.policy_search.export import export_search
from skidnav.studies.policy_search.grid import PolicySearchGrid, grid_toml
from skidnav.studies.policy_search.trial import SearchTrial

if TYPE_CHECKING:
    from skidnav.agents.policies.search.curve import GenerationRecord
    from skidnav.experiments.runs import RunSpec

FLAG_FIELDS = {
    "map": "map_kind", "world_seed": "world_seed", "max_steps": "max_episode_steps",
    "control_period": "control_period", "lidar_rays": "lidar_rays", "hidden": "hidden",
    "population": "population", "sigma": "sigma0", "generations": "generations",
    "episodes": "episodes_per_candidate", "progress_weight": "progress_weight",
    "eval_episodes": "eval_episodes", "eval_every": "eval_every",
}  # fmt: skip
"""Argument → :class:`~skidnav.agents.policies.search.config.SearchConfig` field (``--slip``
and ``--seed`` are the study's preset and root seed)."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``search``."""
    parser = subparsers.add_parser(
        "search",
        help="search a tanh wheel-speed policy by CMA-ES on the feature observation (resumable)",
        description="Run one CMA-ES policy search as a policy-search study into --out and write "
        "its policy file; started again on the same --out it continues the search.",
    )
    parser.add_argument("--map", choices=("free", "obstacles", "maze"), default="obstacles")
    parser.add_argument("--world-seed", type=int, default=0, help="the env's map and slip field")
    parser.add_argument("--slip", choices=SLIP_PRESETS, default="thesis")
    parser.add_argument("--max-steps", type=int, default=200, help="actions per episode")
    parser.add_argument("--control-period", type=float, default=1.0, help="seconds per action")
    parser.add_argument("--lidar-rays", type=int, default=8)
    parser.add_argument("--hidden", type=int, default=8, help="tanh units (0: linear policy)")
    parser.add_argument("--population", type=int, default=16, help="candidates per generation")
    parser.add_argument("--sigma", type=float, default=0.5, help="initial CMA-ES step size")
    parser.add_argument("--generations", type=int, default=50)
    parser.add_argument("--episodes", type=int, default=2, help="episodes per candidate")
    parser.add_argument(
        "--progress-weight", type=float, default=0.0,
        help="score per metre of goal distance gained, added to the return (0: plain return)",
    )  # fmt: skip
    parser.add_argument("--eval-episodes", type=int, default=10, help="episodes of the mean")
    parser.add_argument("--eval-every", type=int, default=1, help="generations between them")
    parser.add_argument("--seed", type=int, default=0, help="root seed of the study")
    parser.add_argument("--out", type=path_argument, required=True, help="folder of the results")
    parser.set_defaults(func=_search)


def grid_from_flags(args: argparse.Namespace) -> PolicySearchGrid:
    """The study of the arguments; UserError naming the flag of a bad value."""
    from skidnav.agents.policies.search.config import SearchConfig

    values = {field: getattr(args, flag) for flag, field in FLAG_FIELDS.items()}
    try:
        search = SearchConfig(**values, slip=args.slip)
        return PolicySearchGrid(search, (args.slip,), seeds=1, root_seed=args.seed)
    except ValueError as error:
        message = str(error)
        for flag, field in (*FLAG_FIELDS.items(), ("seed", "root_seed")):
            message = message.replace(f" {field} ", f" --{flag.replace('_', '-')} ")
        raise UserError(message) from None


def print_generation(spec: RunSpec[PolicySearchGrid], record: GenerationRecord) -> None:
    """One line per record of the search: episodes, wall time, σ, scores."""
    success = "" if math.isnan(record.mean_success) else f", success {record.mean_success:.2f}"
    evaluated = "" if math.isnan(record.mean_return) else f"; mean policy {record.mean_return:.1f}"
    best = "" if math.isnan(record.best_return) else f", best {record.best_return:.1f}"
    print(
        f"generation {record.generation}/{spec.config.search.generations}: {record.episodes} "
        f"episodes, {record.wall_time:.1f} s, σ {record.sigma:.3f}{best}{evaluated}{success}",
        flush=True,
    )


def _search(args: argparse.Namespace) -> int:
    grid = grid_from_flags(args)
    out = check_output_dir(args.out)
    if (out / "checkpoint.json").exists() and not (out / "config.json").exists():
        raise UserError(f"{out}: holds a search in an earlier format; choose another --out")
    loaded = parse_grid(grid_toml(grid), FLAGS)
    trial = SearchTrial(out / "checkpoints", print_generation)  # the study's, printing progress
    outcome = run_loaded(loaded, out, backend="serial", trial=trial)
    if outcome.executed == 0:
        print(f"{out}: the search had finished already")
    (run,) = expand_runs(grid)
    paths = export_search(out, run.run_id, out)
    print("wrote " + ", ".join(path.name for path in paths) + f" in {out}")
    return 0
