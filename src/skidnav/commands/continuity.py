"""``skidnav study continuity``: discrete agents against wheel-speed learners on one world, a
shortcut for the continuity study's config (:mod:`skidnav.studies.continuity.study`).

It writes the config of its flags (saved as ``--out DIR/config.toml``) and runs it as ``skidnav
run`` does: the same runs and files, resumed when started again on the same ``--out``. Then it
writes, from the results directory (:mod:`skidnav.studies.continuity.results`): ``runs.csv``
(one row per learner run: seed index and seed, real episodes used and to learn, wall time,
success of its rollouts), ``table.csv`` (per learner and metric: mean and 95 % bootstrap
interval over every rollout of every seed), ``table.md`` (the same as markdown, with the runs'
learning costs) and ``trajectories.png`` (each learner's first rollout of its first seed on the
arena).
"""

from __future__ import annotations

import argparse
from typing import Any

from skidnav.commands.shortcut import add_run_arguments, run_text
from skidnav.errors import UserError
from skidnav.robot.slip import SLIP_PRESETS


def add_parser(subparsers: Any) -> None:
    """Add ``continuity``."""
    from skidnav.studies.continuity.comparison import LEARNERS

    parser = subparsers.add_parser(
        "continuity",
        help="discrete agents against wheel-speed learners: what continuity buys",
        description="Write the continuity study's config of these flags to OUT/config.toml and "
        "run it as 'skidnav run' does (resumable on the same --out); then the tables and the "
        "picture from the results.",
    )
    parser.add_argument("--map", choices=("free", "obstacles", "maze"), default="obstacles")
    parser.add_argument("--world-seed", type=int, default=3)
    parser.add_argument("--slip", choices=SLIP_PRESETS, default="slippery")
    parser.add_argument("--max-steps", type=int, default=200, help="actions per episode")
    parser.add_argument("--control-period", type=float, default=1.0, help="seconds per action")
    parser.add_argument(
        "--learners",
        default=",".join(LEARNERS),
        help=f"comma-separated, of {', '.join(LEARNERS)} (default: all; cmaes needs the search "
        "extra, ppo and sac the deep extra)",
    )
    parser.add_argument("--seeds", type=int, default=3, help="runs per learner")
    parser.add_argument("--root-seed", type=int, default=0)
    parser.add_argument(
        "--episodes", type=int, default=300, help="discrete, deep and model-predictive learners"
    )
    parser.add_argument("--generations", type=int, default=100, help="CMA-ES generations")
    parser.add_argument("--population", type=int, default=32, help="CMA-ES candidates")
    parser.add_argument("--rollouts", type=int, default=5, help="evaluation rollouts per run")
    add_run_arguments(parser, "continuity")
    parser.set_defaults(func=continuity_command)


def continuity_command(args: argparse.Namespace) -> int:
    """Run (or resume) the comparison; write and print its table."""
    from skidnav.studies.continuity.comparison import ComparisonConfig
    from skidnav.studies.continuity.results import markdown, read_results, write_outputs
    from skidnav.studies.continuity.study import config_text

    try:
        config = ComparisonConfig(
            map_kind=args.map, world_seed=args.world_seed, slip=args.slip,
            max_steps=args.max_steps, control_period=args.control_period,
            learners=tuple(name.strip() for name in args.learners.split(",") if name.strip()),
            seeds=args.seeds, root_seed=args.root_seed, episodes=args.episodes,
            generations=args.generations, population=args.population, rollouts=args.rollouts,
        )  # fmt: skip
    except ValueError as error:
        raise UserError(f"continuity: {error}") from None
    text = config_text(config, "the config of `skidnav study continuity`: skidnav run it to resume")
    out = run_text(text, args)[1].out_dir
    results = read_results(out)
    write_outputs(out, results)
    print(markdown(results))
    return 0
