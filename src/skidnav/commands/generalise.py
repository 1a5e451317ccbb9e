"""``skidnav study generalise``: agents trained on a set of maps, run on maps never seen
(:mod:`skidnav.studies.generalisation`)."""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
from dataclasses import asdict, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from skidnav.atomicfile import write_user_file
from skidnav.errors import UserError, shown
from skidnav.outputs import check_output_file
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.stats import bootstrap_interval, difference_interval

if TYPE_CHECKING:  # the experiment modules load numba and the agents: only when run
    from skidnav.studies.generalisation import GeneralisationResult

MAX_SEEDS = 1000
MAX_WORLDS = 1000
MAX_EPISODES = 1_000_000
MAX_PARAMS_CHARS = 10_000
DEFAULT_AGENTS = ("dqn", "linear-q")
DEFAULT_PARAMS: dict[str, dict[str, Any]] = {
    "linear-q": {"dimensions": [4, 5, 6, 7, 8, 14], "tiles": [5]},
}
"""Parameters of an agent unless ``--params`` gives its own: ``linear-q`` tiles the goal's
distance and bearing and the front, front-left and front-right range readings of the default 8
rays (all 15 features would need ~10^11 tiles)."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``generalise``."""
    parser = subparsers.add_parser(
        "generalise", help="train agents on a set of maps, evaluate them on maps never seen"
    )
    parser.add_argument("--agent", action="append", help=f"repeatable; default {DEFAULT_AGENTS}")
    parser.add_argument("--seeds", type=int, default=5, help="runs per agent (seeds 0 .. N−1)")
    parser.add_argument("--training-maps", type=int, default=8)
    parser.add_argument("--held-out-maps", type=int, default=4)
    parser.add_argument("--episodes", type=int, default=1000, help="training episodes per run")
    parser.add_argument("--max-steps", type=int, default=300, help="actions per episode")
    parser.add_argument("--map-kind", choices=("free", "obstacles", "maze"), default="obstacles")
    parser.add_argument("--slip", choices=SLIP_PRESETS, default="thesis")
    parser.add_argument("--observation", choices=("features", "pose"), default="features")
    parser.add_argument("--rollouts", type=int, default=5, help="greedy rollouts per map")
    parser.add_argument(
        "--eval-epsilon", type=float, default=0.05, help="ε of the second, ε-greedy evaluation"
    )
    parser.add_argument(
        "--params", action="append", default=[], metavar="AGENT=JSON",
        help="an agent's parameters as a JSON object (repeatable)",
    )  # fmt: skip
    parser.add_argument("--root-seed", type=int, default=0, help="the maps and every run's seeds")
    parser.add_argument("--out", type=Path, help="CSV of the per-run results")
    parser.set_defaults(func=_generalise)


def _check(args: argparse.Namespace) -> dict[str, dict[str, Any]]:
    """Bounds of the counts; each agent's parameters, :data:`DEFAULT_PARAMS` overridden by
    ``--params`` (UserError in one line otherwise)."""
    bounds = {
        "--seeds": (args.seeds, 1, MAX_SEEDS),
        "--training-maps": (args.training_maps, 1, MAX_WORLDS),
        "--held-out-maps": (args.held_out_maps, 1, MAX_WORLDS),
        "--episodes": (args.episodes, 1, MAX_EPISODES),
        "--max-steps": (args.max_steps, 1, 100_000),
        "--rollouts": (args.rollouts, 1, 100),
        "--root-seed": (args.root_seed, 0, 2**63 - 1),
    }
    for flag, (value, low, high) in bounds.items():
        if not low <= value <= high:
            raise UserError(f"expected {flag} in [{low}, {high}], got {value}")
    if not 0.0 <= args.eval_epsilon <= 1.0:  # NaN fails too
        raise UserError(f"expected --eval-epsilon in [0, 1], got {args.eval_epsilon}")
    params = {name: dict(values) for name, values in DEFAULT_PARAMS.items()}
    for text in args.params:
        name, _, value = text.partition("=")
        if not value or len(value) > MAX_PARAMS_CHARS:
            raise UserError(
                f"--params: expected AGENT=JSON of at most {MAX_PARAMS_CHARS} characters, "
                f"got {shown(text)}"
            )
        try:
            parsed = json.loads(value)
        except json.JSONDecodeError as error:
            raise UserError(
                f"--params {name}: not JSON ({error.msg} at character {error.pos})"
            ) from None
        if not isinstance(parsed, dict):
            raise UserError(f"--params {name}: expected a JSON object, got {shown(value)}")
        params[name] = parsed
    return params


def _generalise(args: argparse.Namespace) -> int:
    params = _check(args)
    if args.out is not None:
        check_output_file(args.out)
    from skidnav.agents.catalog import check_params
    from skidnav.studies.generalisation import generalisation_run, references, split_worlds

    names = args.agent or list(DEFAULT_AGENTS)
    for name in names:
        check_params(name, params.get(name, {}))  # an unknown name or a bad value: one line
    options = {"map_kind": args.map_kind, "slip": args.slip, "observation": args.observation}
    split = split_worlds(
        args.root_seed, args.training_maps, args.held_out_maps, args.rollouts, options
    )
    print(f"training worlds {list(split.training)}; held-out worlds {list(split.held_out)}")
    results: list[GeneralisationResult] = []
    for name in names:
        for seed in range(args.seeds):
            result = generalisation_run(
                name, seed, split, args.episodes, root_seed=args.root_seed, params=params.get(name),
                env_options=options, max_steps=args.max_steps, eval_epsilon=args.eval_epsilon,
            )  # fmt: skip
            print(
                f"  {name} seed {seed}: {result.steps} steps; success on training maps "
                f"{result.success_training_maps:.2f}, held-out {result.success_held_out_maps:.2f} "
                f"(greedy), {result.epsilon_success_training_maps:.2f}, "
                f"{result.epsilon_success_held_out_maps:.2f} (ε-greedy)",
                flush=True,
            )
            results.append(result)
    print_summary(results)
    for reference in references(split, args.max_steps, options):
        print(
            f"reference {reference.policy:12s} success, training maps "
            f"{reference.success_training_maps:.2f}, held-out {reference.success_held_out_maps:.2f}"
        )
    if args.out is not None:
        buffer = io.StringIO()
        writer = csv.DictWriter(buffer, [field.name for field in fields(results[0])])
        writer.writeheader()
        writer.writerows(asdict(result) for result in results)
        write_user_file(args.out, buffer.getvalue().encode(), "results")
        print(f"wrote {args.out}")
    return 0


def _text(estimate: Any) -> str:
    if math.isnan(estimate.estimate):
        return "n/a"
    return f"{estimate.estimate:.2f} [{estimate.low:.2f}, {estimate.high:.2f}]"


def print_summary(results: list[GeneralisationResult]) -> None:
    """Per agent, greedy and ε-greedy: success on the training and held-out maps and their
    paired difference, means over runs with 95 % bootstrap intervals; and the greedy held-out
    lengths."""
    rng = np.random.default_rng(0)
    header = ("policy", "success, training maps", "success, held-out", "held-out − training",
              "length, held-out")  # fmt: skip
    print(f"{'agent':18s} {header[0]:>10s} " + " ".join(f"{name:>24s}" for name in header[1:]))
    for name in dict.fromkeys(result.agent for result in results):
        rows = [result for result in results if result.agent == name]
        for policy, prefix in (("greedy", ""), ("ε-greedy", "epsilon_")):
            trained = [getattr(row, f"{prefix}success_training_maps") for row in rows]
            held_out = [getattr(row, f"{prefix}success_held_out_maps") for row in rows]
            cells = [
                _text(bootstrap_interval(trained, rng)),
                _text(bootstrap_interval(held_out, rng)),
                _text(difference_interval(held_out, trained, rng)),
                _text(bootstrap_interval([row.length_held_out_maps for row in rows], rng))
                if not prefix
                else "",
            ]
            print(f"{name:18s} {policy:>10s} " + " ".join(f"{cell:>24s}" for cell in cells))
