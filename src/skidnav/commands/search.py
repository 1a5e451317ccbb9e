"""``skidnav study search``: a tanh wheel-speed policy found by CMA-ES
(:mod:`skidnav.agents.policies.search`).

Writes into ``--out DIR``: ``policy.npz`` + ``policy.json`` (the final mean policy),
``curve.csv`` (one row per generation,
:class:`~skidnav.agents.policies.search.cmaes.GenerationRecord`),
``search.json`` (the config and the last row) and ``checkpoint.npz`` + ``checkpoint.json``
(rewritten after every generation; ``--resume`` continues from it).
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from skidnav.atomicfile import write_user_file
from skidnav.errors import UserError
from skidnav.outputs import check_output_dir, make_output_dir
from skidnav.robot.slip import SLIP_PRESETS

if TYPE_CHECKING:  # the search loads the env and numba: only when run
    from skidnav.agents.policies.search.cmaes import GenerationRecord
    from skidnav.agents.policies.search.config import SearchConfig

FLAG_FIELDS = {
    "map": "map_kind", "world_seed": "world_seed", "slip": "slip", "max_steps": "max_episode_steps",
    "control_period": "control_period", "lidar_rays": "lidar_rays", "hidden": "hidden",
    "population": "population", "sigma": "sigma0", "generations": "generations",
    "episodes": "episodes_per_candidate", "progress_weight": "progress_weight",
    "eval_episodes": "eval_episodes",
    "eval_every": "eval_every", "seed": "seed",
}  # fmt: skip
"""Argument → :class:`~skidnav.agents.policies.search.config.SearchConfig` field."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``search``."""
    parser = subparsers.add_parser(
        "search", help="search a tanh wheel-speed policy by CMA-ES on the feature observation"
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
    parser.add_argument("--seed", type=int, default=0, help="root seed of the search")
    parser.add_argument("--out", type=Path, required=True, help="folder of the results")
    parser.add_argument("--resume", action="store_true", help="continue from DIR/checkpoint")
    parser.set_defaults(func=_search)


def _config(args: argparse.Namespace) -> SearchConfig:
    """The search's config from the arguments; UserError naming the flag of a bad value."""
    from skidnav.agents.policies.search.config import SearchConfig

    values = {field: getattr(args, flag) for flag, field in FLAG_FIELDS.items()}
    try:
        config = SearchConfig(**values)
        config.env_options()
    except ValueError as error:
        message = str(error)
        for flag, field in FLAG_FIELDS.items():
            message = message.replace(f" {field} ", f" --{flag.replace('_', '-')} ")
        raise UserError(message) from None
    return config


def _prepare(out: Path, resume: bool) -> Path:
    """The checkpoint ``NAME`` in ``out`` (created); UserError when ``out`` holds a search and
    ``resume`` is not set, or holds none and it is."""
    checkpoint = out / "checkpoint"
    exists = checkpoint.with_suffix(".json").exists()
    if exists and not resume:
        raise UserError(f"{out}: holds a search already (pass --resume, or another --out)")
    if resume and not exists:
        raise UserError(f"{out}: no checkpoint.json to resume from")
    make_output_dir(out)
    return checkpoint


def _search(args: argparse.Namespace) -> int:
    config = _config(args)
    checkpoint = _prepare(check_output_dir(args.out), args.resume)
    from skidnav.agents.policies.search.cmaes import record_rows, run_search
    from skidnav.agents.policies.search.policy_file import save_policy

    def progress(record: GenerationRecord) -> None:
        success = "" if math.isnan(record.mean_success) else f", success {record.mean_success:.2f}"
        evaluated = (
            "" if math.isnan(record.mean_return) else f"; mean policy {record.mean_return:.1f}"
        )
        best = "" if math.isnan(record.best_return) else f", best {record.best_return:.1f}"
        print(
            f"generation {record.generation}/{config.generations}: {record.episodes} episodes, "
            f"{record.wall_time:.1f} s, σ {record.sigma:.3f}{best}{evaluated}{success}",
            flush=True,
        )

    try:
        result = run_search(
            config, checkpoint=checkpoint, resume=args.resume, on_generation=progress
        )
    except OSError as error:
        raise UserError(
            f"{args.out}: cannot write the checkpoint ({error.strerror or error})"
        ) from None
    rows = record_rows(result.records)
    try:
        save_policy(
            result.policy, args.out / "policy", {"config": config.to_dict(), "last": rows[-1]}
        )
    except OSError as error:
        raise UserError(
            f"{args.out}: cannot write the policy ({error.strerror or error})"
        ) from None
    write_user_file(args.out / "curve.csv", _csv(rows), "learning curve")
    summary = {"config": config.to_dict(), "last": rows[-1], "policy": "policy.npz"}
    write_user_file(args.out / "search.json", json.dumps(summary, indent=1).encode(), "summary")
    print(f"wrote {args.out / 'policy.npz'}, policy.json, curve.csv, search.json")
    return 0


def _csv(rows: list[dict[str, Any]]) -> bytes:
    """The learning curve as CSV bytes (null: an empty cell)."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, list(rows[0]))
    writer.writeheader()
    writer.writerows(
        {key: "" if value is None else value for key, value in row.items()} for row in rows
    )
    return buffer.getvalue().encode()
