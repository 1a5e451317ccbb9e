"""``skidnav study continuity``: discrete agents against wheel-speed learners on one world
(:mod:`skidnav.studies.continuity.comparison`).

Writes into ``--out DIR``: ``runs.csv`` (one row per learner run: seed, real episodes used and to
learn, wall time, success of its rollouts), ``table.csv`` (per learner and metric: mean and 95 %
bootstrap interval over every rollout of every seed, :func:`~skidnav.studies.continuity.traces.
comparison_table`), ``table.md`` (the same as markdown, with the runs' learning costs) and
``trajectories.png`` (each learner's first rollout of its first seed on the arena).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.atomicfile import write_user_file
from skidnav.errors import UserError
from skidnav.outputs import check_output_dir, make_output_dir
from skidnav.robot.slip import SLIP_PRESETS

SHOWN = ("success", "time_to_goal", "path_length", "wheel_change", "reversals_per_metre", "energy")
"""The metrics of the markdown table, in order."""


def add_parser(subparsers: Any) -> None:
    """Add ``continuity``."""
    from skidnav.studies.continuity.comparison import LEARNERS

    parser = subparsers.add_parser(
        "continuity", help="discrete agents against wheel-speed learners: what continuity buys"
    )
    parser.add_argument("--map", choices=("free", "obstacles", "maze"), default="obstacles")
    parser.add_argument("--world-seed", type=int, default=3)
    parser.add_argument("--slip", choices=SLIP_PRESETS, default="slippery")
    parser.add_argument("--max-steps", type=int, default=200, help="actions per episode")
    parser.add_argument("--control-period", type=float, default=1.0, help="seconds per action")
    parser.add_argument(
        "--learners", default=",".join(LEARNERS), help=f"comma-separated, of {', '.join(LEARNERS)}"
    )
    parser.add_argument("--seeds", type=int, default=3, help="runs per learner")
    parser.add_argument("--root-seed", type=int, default=0)
    parser.add_argument("--episodes", type=int, default=300, help="discrete and deep learners")
    parser.add_argument("--generations", type=int, default=100, help="CMA-ES generations")
    parser.add_argument("--population", type=int, default=32, help="CMA-ES candidates")
    parser.add_argument("--rollouts", type=int, default=5, help="evaluation rollouts per run")
    parser.add_argument("--out", type=Path, required=True, help="output directory")
    parser.set_defaults(func=continuity_command)


def continuity_command(args: argparse.Namespace) -> int:
    """Run the comparison; write and print its table."""
    from skidnav.studies.continuity.comparison import ComparisonConfig, run_comparison

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
    check_output_dir(args.out)
    if args.out.exists() and any(args.out.iterdir()):
        raise UserError(f"{args.out}: not empty (choose a new --out)")
    make_output_dir(args.out)
    runs = run_comparison(config, progress=_progress)
    write_results(args.out, config, runs)
    print((args.out / "table.md").read_text(encoding="utf-8"))
    return 0


def _progress(run: Any) -> None:
    successes = sum(trace.terminated for trace in run.traces)
    print(
        f"{run.learner} seed {run.seed}: {run.episodes_used} episodes, learned at "
        f"{run.episodes_to_learn:g}, {successes}/{len(run.traces)} rollouts at the goal, "
        f"{run.wall_time:.0f} s",
        flush=True,
    )


def write_results(out: Path, config: Any, runs: list[Any]) -> None:
    """``runs.csv``, ``table.csv``, ``table.md`` and ``trajectories.png`` (module doc)."""
    import gymnasium
    import pandas as pd

    from skidnav.envs.registration import ENV_ID
    from skidnav.studies.continuity.traces import comparison_table
    from skidnav.studies.continuity.trajectory_plot import save_trajectory_picture

    rows = [
        {"learner": r.learner, "seed": r.seed, "episodes_used": r.episodes_used,
         "episodes_to_learn": r.episodes_to_learn, "wall_time": r.wall_time,
         "success": float(np.mean([t.terminated for t in r.traces]))}
        for r in runs
    ]  # fmt: skip
    frame = pd.DataFrame(rows)
    traces = {name: [t for r in runs if r.learner == name for t in r.traces]
              for name in dict.fromkeys(r.learner for r in runs)}  # fmt: skip
    table = comparison_table(traces, np.random.default_rng(config.root_seed))
    write_user_file(out / "runs.csv", frame.to_csv(index=False).encode(), "runs")
    write_user_file(out / "table.csv", table.to_csv(index=False).encode(), "table")
    write_user_file(out / "table.md", markdown(config, frame, table).encode(), "table")
    nav: Any = gymnasium.make(ENV_ID, **config.env_kwargs(False)).unwrapped
    grid_map = nav.grid_map
    firsts = {name: runs_of[0] for name, runs_of in traces.items()}
    title = f"{config.map_kind} world {config.world_seed}, {config.slip}"
    save_trajectory_picture(out / "trajectories.png", grid_map, firsts, title=title)


def _cell(row: Any) -> str:
    if not math.isfinite(row["mean"]):
        return "–"
    scale = 100.0 if row["metric"] == "success" else 1.0
    if math.isnan(row["low"]):
        return f"{scale * row['mean']:.2f}"
    return f"{scale * row['mean']:.2f} [{scale * row['low']:.2f}, {scale * row['high']:.2f}]"


def markdown(config: Any, runs: Any, table: Any) -> str:
    """The comparison as one markdown table: a row per learner."""
    header = ["learner", "runs", "episodes used", "episodes to learn (runs that did)"]
    header += [
        "success [%]", "time to goal [s]", "path [m]", "wheel change Δω [rad/s]",
        "reversals [1/m]", "energy [rad²/s]",
    ]  # fmt: skip
    lines = [
        f"{config.map_kind} world {config.world_seed}, slip {config.slip}, {config.max_steps} "
        f"actions of {config.control_period:g} s, {config.rollouts} rollouts per run on shared "
        "seeds; means with 95 % bootstrap intervals over every rollout.\n",
        "| " + " | ".join(header) + " |",
        "|" + "---|" * len(header),
    ]
    for learner, cells in table.groupby("policy", sort=False):
        learner_runs = runs[runs["learner"] == learner]
        learned = learner_runs["episodes_to_learn"].dropna()
        to_learn = f"{learned.median():g} ({len(learned)})" if len(learned) else "– (0)"
        by_metric = {row["metric"]: row for row in cells.to_dict("records")}
        values = [_cell(by_metric[name]) for name in SHOWN]
        lines.append(
            f"| {learner} | {len(learner_runs)} | {int(learner_runs['episodes_used'].median())} "
            f"| {to_learn} | {' | '.join(values)} |"
        )
    return "\n".join(lines) + "\n"
