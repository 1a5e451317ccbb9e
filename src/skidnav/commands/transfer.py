"""``skidnav study transfer``: the sim-to-sim gap — agents trained on the kinematic simulator, their
greedy policies run on the MuJoCo robot (:mod:`skidnav.studies.transfer`).

A shortcut: the flags become a ``kind = "transfer"`` config (:mod:`skidnav.studies.transfer.grid`),
run as ``skidnav run`` runs it (:mod:`skidnav.commands.shortcut`) into ``--out DIR``; then the
table is printed from the results, and ``DIR/transfer.csv`` holds one row per run.
"""

from __future__ import annotations

import argparse
from dataclasses import fields
from typing import Any

from skidnav.agents.catalog import family
from skidnav.commands.shortcut import add_run_arguments, run_document
from skidnav.files.atomic import write_user_file
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.studies.transfer.grid import FLOORS, KIND, LAYOUT, TransferGrid
from skidnav.world.grid import MAP_KINDS

DEFAULT_AGENTS = ("q-learning", "dyna-full")
DEFAULTS = {field.name: field.default for field in fields(TransferGrid)}
"""The study's settings when a config leaves them out (the flags' defaults)."""
SETTINGS = ("seeds", "episodes", "max_steps", "map_kind", "slip", "floor", "rollouts")
"""The flags that are keys of ``[transfer]`` (``--max-steps`` is ``max_steps``)."""
CSV_NAME = "transfer.csv"


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``transfer``."""
    parser = subparsers.add_parser(
        "transfer",
        help="run policies learned on the kinematic simulator on the MuJoCo robot",
        description="Write a transfer config from the flags and run it as 'skidnav run' does "
        "(resumable in --out); print the table and write --out/transfer.csv.",
    )
    parser.add_argument(
        "--agent", action="append", choices=family("tabular").agents,
        help=f"repeatable; default {DEFAULT_AGENTS}",
    )  # fmt: skip
    counts = {
        "seeds": "seeds 0 .. N−1 (world, agent)", "episodes": "training episodes",
        "max_steps": "actions per episode", "rollouts": "greedy rollouts per dynamics",
    }  # fmt: skip
    for key, text in counts.items():
        flag = "--" + key.replace("_", "-")
        parser.add_argument(flag, type=int, default=DEFAULTS[key], help=f"{text} (%(default)s)")
    parser.add_argument(
        "--planning-steps", type=int, default=100,
        help="planning_steps of every agent but q-learning (%(default)s)",
    )  # fmt: skip
    parser.add_argument("--map-kind", choices=MAP_KINDS, default=DEFAULTS["map_kind"])
    parser.add_argument("--slip", choices=SLIP_PRESETS, default=DEFAULTS["slip"])
    parser.add_argument(
        "--floor", choices=FLOORS[1:], default=DEFAULTS["floor"], help="one material everywhere"
    )
    add_run_arguments(parser, KIND)
    parser.set_defaults(func=_transfer)


def config_document(args: argparse.Namespace) -> dict[str, Any]:
    """The transfer config of the flags (what ``configs/transfer.toml`` holds for the
    defaults): every agent but ``q-learning`` with ``planning_steps`` = ``--planning-steps``."""
    settings = {"name": KIND, **{key: getattr(args, key) for key in SETTINGS}}
    agents = [
        {"name": name}
        if name == "q-learning"
        else {"name": name, "params": {"planning_steps": args.planning_steps}}
        for name in args.agent or DEFAULT_AGENTS
    ]
    return {"kind": KIND, KIND: settings, "agents": agents}


def _transfer(args: argparse.Namespace) -> int:
    _, outcome = run_document(config_document(args), args)
    from skidnav.studies.agent_grid import results_csv, study_results
    from skidnav.studies.transfer import report

    results = report.results_of(study_results(outcome.out_dir, LAYOUT)[1])
    print(report.summary_text(results))
    path = outcome.out_dir / CSV_NAME
    write_user_file(path, results_csv(results).encode(), "results")
    print(f"wrote {path}")
    return 0
