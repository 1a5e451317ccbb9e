"""``skidnav world simulate``: drive the simulated robot with an action script or a random policy,
and draw its trajectory (PNG) and optionally save it as CSV.

A script runs to its last action (the env's usual 500-action episode limit does not cut it), or
until the robot reaches the goal, which ends the episode: the summary then says how many of the
script's actions ran. Scripts and ``--random`` hold at most :data:`MAX_ACTIONS` actions, an
action file at most :data:`MAX_ACTIONS_FILE_BYTES` bytes; longer ones are refused in one line.
"""

from __future__ import annotations

import argparse
import csv
import io
from pathlib import Path
from typing import Any

import numpy as np

from skidnav.commands.parsing import path_argument
from skidnav.errors import UserError, excerpt
from skidnav.files.atomic import write_atomic
from skidnav.files.outputs import check_output_file
from skidnav.files.user import read_limited
from skidnav.robot.kinematics import ACTION_NAMES
from skidnav.robot.params import RobotParams
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.seeding import ARENA_ROLES, child_sequences, seed_int
from skidnav.statistics.formatting import plural
from skidnav.world.grid import MAP_KINDS

ACTION_ALIASES = {name: index for index, name in enumerate(ACTION_NAMES)} | {
    name[0]: index for index, name in enumerate(ACTION_NAMES)
}
MAX_ACTIONS = 100_000
"""Most actions one ``simulate`` runs (a script or ``--random N``)."""
MAX_ACTIONS_FILE_BYTES = 2 * 2**20
"""Longest ``--actions-file`` read [bytes] (a regular file or a pipe)."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``simulate``."""
    parser = subparsers.add_parser("simulate", help="run an action script or a random policy")
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--map", type=path_argument, help="map file (default: a generated map)")
    source.add_argument("--map-kind", choices=MAP_KINDS, default="obstacles")
    parser.add_argument("--world-seed", type=int, default=0, help="draws the map and slip field")
    parser.add_argument("--slip", choices=SLIP_PRESETS, default="thesis")
    parser.add_argument("--drift", type=float, default=0.0, help="relative slip drift amplitude")
    parser.add_argument("--integrator", choices=("euler", "exact"), default="euler")
    parser.add_argument("--seed", type=int, default=0, help="root of the slip noise and policy")
    script = parser.add_mutually_exclusive_group()
    script.add_argument("--actions", help="actions, e.g. 'f f l f r' or '0,0,2,0,3'")
    script.add_argument("--actions-file", type=path_argument, help="file of actions (same syntax)")
    script.add_argument("--random", type=int, default=200, metavar="N", help="random actions")
    parser.add_argument(
        "--out", type=path_argument, default=Path("trajectory.png"), help="PNG to write"
    )
    parser.add_argument("--csv", type=path_argument, help="also write the trajectory as CSV")
    parser.set_defaults(func=_simulate)


def parse_actions(text: str, where: str = "--actions") -> list[int]:
    """Parse an action script: names (forward/backward/left/right), initials or digits 0–3,
    separated by spaces, commas or newlines.

    >>> parse_actions("f, f left 3")
    [0, 0, 2, 3]
    """
    actions = []
    for token in text.replace(",", " ").split():
        key = token.lower()
        if key in ACTION_ALIASES:
            actions.append(ACTION_ALIASES[key])
        elif key in ("0", "1", "2", "3"):
            actions.append(int(key))
        else:
            raise UserError(
                f"{where}: unknown action {excerpt(token)} (use 0-3 or forward/backward/left/right)"
            )
    if not actions:
        raise UserError(f"{where}: no actions given")
    if len(actions) > MAX_ACTIONS:
        raise UserError(f"{where}: {len(actions):,} actions, expected at most {MAX_ACTIONS:,}")
    return actions


def _script(args: argparse.Namespace) -> list[int] | None:
    if args.actions is not None:
        return parse_actions(args.actions)
    if args.actions_file is not None:
        data = read_limited(
            args.actions_file, MAX_ACTIONS_FILE_BYTES, "action file", UserError, pipes=True
        )
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError:
            raise UserError(f"{args.actions_file}: cannot read the action file") from None
        return parse_actions(text, str(args.actions_file))
    if not 1 <= args.random <= MAX_ACTIONS:
        raise UserError(f"expected --random >= 1 and <= {MAX_ACTIONS:,}, got {args.random}")
    return None


def _make_env(args: argparse.Namespace, max_steps: int) -> Any:
    """The env of the arguments, truncated by Gymnasium's ``TimeLimit`` after ``max_steps``
    actions instead of the registered 500; a bad value (negative drift, seed, …) raises
    UserError."""
    import gymnasium

    from skidnav.envs.registration import ENV_ID

    for option, seed in (("--world-seed", args.world_seed), ("--seed", args.seed)):
        if seed < 0:
            raise UserError(f"expected {option} >= 0, got {seed}")
    try:
        return gymnasium.make(
            ENV_ID,
            max_episode_steps=max_steps,
            render_mode="rgb_array",
            map_file=args.map,
            map_kind=args.map_kind,
            world_seed=args.world_seed,
            slip=args.slip,
            drift_amplitude=args.drift,
            robot=RobotParams(integrator=args.integrator),
        )
    except ValueError as error:
        raise UserError(str(error)) from None


def _write_csv(path: Path, rows: list[tuple[Any, ...]]) -> None:
    """Write the trajectory table atomically (all rows or, on failure, the old file)."""
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(["step", "action", "x", "y", "heading", "reward", "collision"])
    writer.writerows(rows)
    try:
        write_atomic(path, text.getvalue().encode("utf-8"))
    except OSError as error:
        raise UserError(f"{path}: cannot write the CSV file ({error.strerror or error})") from None


def _simulate(args: argparse.Namespace) -> int:
    from skidnav.world.rendering import save_frame, with_legend

    check_output_file(args.out)
    if args.csv is not None:
        check_output_file(args.csv, "--csv")
    script = _script(args)
    env = _make_env(args, len(script) if script else args.random)
    streams = child_sequences(args.seed, ARENA_ROLES)  # env noise and policy never share one
    _, info = env.reset(seed=seed_int(streams["robot"]))
    policy = np.random.default_rng(streams["agent"])
    rows: list[tuple[Any, ...]] = [(0, -1, *info["pose"], 0.0, False)]
    total, step, done = 0.0, 0, False
    while not done:
        action = script[step] if script else int(policy.integers(4))
        _, reward, terminated, truncated, info = env.step(action)
        step += 1
        total += float(reward)
        rows.append((step, action, *info["pose"], reward, info["collision"]))
        done = terminated or truncated or (script is not None and step >= len(script))
    save_frame(with_legend(np.asarray(env.render())), args.out)
    if args.csv is not None:
        _write_csv(args.csv, rows)
    collisions = sum(1 for row in rows if row[-1])
    outcome = "reached the goal" if terminated else "did not reach the goal"
    if terminated and script is not None and step < len(script):
        unrun = plural(len(script) - step, "action")
        outcome += f" (the episode ended there: {unrun} of the script not run)"
    print(
        f"{plural(step, 'action')}, return {total:.2f}, {plural(collisions, 'collision')}, "
        f"{outcome}; wrote {args.out}"
    )
    return 0
