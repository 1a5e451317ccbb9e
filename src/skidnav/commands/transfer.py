"""``skidnav study transfer``: the sim-to-sim gap — agents trained on the kinematic simulator, their
greedy policies run on the MuJoCo robot (:mod:`skidnav.studies.transfer`)."""

from __future__ import annotations

import argparse
import csv
import io
import math
from dataclasses import asdict, fields
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from skidnav.agents.tabular.registry import available_agents
from skidnav.atomicfile import write_user_file
from skidnav.errors import UserError
from skidnav.outputs import check_output_file
from skidnav.physics.backend import PhysicsUnavailable
from skidnav.physics.materials import MATERIALS
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.stats import bootstrap_interval

if TYPE_CHECKING:  # the experiment modules load numba and the agents: only when run
    from skidnav.studies.transfer import TransferResult

MAX_SEEDS = 1000
MAX_EPISODES = 100_000


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``transfer``."""
    parser = subparsers.add_parser(
        "transfer", help="run policies learned on the kinematic simulator on the MuJoCo robot"
    )
    parser.add_argument("--agent", action="append", choices=available_agents(), help="repeatable")
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0 .. N−1 (world, agent)")
    parser.add_argument("--episodes", type=int, default=300, help="training episodes")
    parser.add_argument("--planning-steps", type=int, default=100, help="model-based agents")
    parser.add_argument("--slip", choices=SLIP_PRESETS, default="slippery")
    parser.add_argument("--floor", choices=sorted(MATERIALS), help="one material everywhere")
    parser.add_argument("--rollouts", type=int, default=5, help="greedy rollouts per dynamics")
    parser.add_argument("--out", type=Path, help="CSV of the per-seed results")
    parser.set_defaults(func=_transfer)


def _check(args: argparse.Namespace) -> None:
    bounds = {
        "--seeds": (args.seeds, 1, MAX_SEEDS),
        "--episodes": (args.episodes, 1, MAX_EPISODES),
        "--planning-steps": (args.planning_steps, 0, 10_000_000),
        "--rollouts": (args.rollouts, 1, 100),
    }
    for flag, (value, low, high) in bounds.items():
        if not low <= value <= high:
            raise UserError(f"expected {flag} in [{low}, {high}], got {value}")


def _transfer(args: argparse.Namespace) -> int:
    _check(args)
    if args.out is not None:
        check_output_file(args.out)
    from skidnav.studies.transfer import TransferResult, transfer_run

    results: list[TransferResult] = []
    for name in args.agent or ["q-learning", "dyna-full"]:
        params = {} if name == "q-learning" else {"planning_steps": args.planning_steps}
        for seed in range(args.seeds):
            try:
                results.append(
                    transfer_run(
                        name, seed, args.episodes, params=params, rollouts=args.rollouts,
                        env_options={"slip": args.slip, "floor": args.floor},
                    )
                )  # fmt: skip
            except PhysicsUnavailable as error:
                raise UserError(str(error)) from None
    _print_summary(results)
    if args.out is not None:
        buffer = io.StringIO()
        writer = csv.DictWriter(buffer, [field.name for field in fields(TransferResult)])
        writer.writeheader()
        writer.writerows(asdict(result) for result in results)
        write_user_file(args.out, buffer.getvalue().encode(), "results")
        print(f"wrote {args.out}")
    return 0


def _print_summary(results: list[TransferResult]) -> None:
    """Per agent: mean success and length on each dynamics with 95 % bootstrap intervals."""
    rng = np.random.default_rng(0)
    print(f"{'agent':24s} {'success, kinematic':>22s} {'success, physics':>22s} "
          f"{'length, kinematic':>22s} {'length, physics':>22s}")  # fmt: skip
    for name in dict.fromkeys(result.agent for result in results):
        rows = [result for result in results if result.agent == name]
        cells = []
        for column in (
            "success_kinematic",
            "success_physics",
            "length_kinematic",
            "length_physics",
        ):
            estimate = bootstrap_interval([getattr(row, column) for row in rows], rng)
            cells.append(
                "n/a" if math.isnan(estimate.estimate)
                else f"{estimate.estimate:.2f} [{estimate.low:.2f}, {estimate.high:.2f}]"
            )  # fmt: skip
        print(f"{name:24s} " + " ".join(f"{cell:>22s}" for cell in cells))
