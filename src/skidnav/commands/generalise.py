"""``skidnav study generalise``: agents trained on a set of maps, run on maps never seen
(:mod:`skidnav.studies.generalisation`).

A shortcut: the flags become a ``kind = "generalisation"`` config
(:mod:`skidnav.studies.generalisation.grid`), run as ``skidnav run`` runs it
(:mod:`skidnav.commands.shortcut`) into ``--out DIR``; then the runs, the summary and the
reference policies are printed from the results, and ``DIR/generalisation.csv`` holds one row
per run.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import fields
from typing import Any

from skidnav.commands.shortcut import add_run_arguments, run_document
from skidnav.errors import UserError, shown
from skidnav.files.atomic import write_user_file
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.studies.generalisation.grid import KIND, LAYOUT, OBSERVATIONS, GeneralisationGrid
from skidnav.world.grid import MAP_KINDS

MAX_PARAMS_CHARS = 10_000
DEFAULT_AGENTS = ("dqn", "linear-q")
DEFAULT_PARAMS: dict[str, dict[str, Any]] = {
    "linear-q": {"dimensions": [4, 5, 6, 7, 8, 14], "tiles": [5]},
}
"""Parameters of an agent unless ``--params`` gives its own: ``linear-q`` tiles the goal's
distance and bearing and the front, front-left and front-right range readings of the default 8
rays (all 15 features would need ~10^11 tiles)."""
DEFAULTS = {field.name: field.default for field in fields(GeneralisationGrid)}
"""The study's settings when a config leaves them out (the flags' defaults)."""
SETTINGS = ("seeds", "training_maps", "held_out_maps", "episodes", "max_steps", "map_kind",
            "slip", "observation", "rollouts", "eval_epsilon", "root_seed")  # fmt: skip
"""The flags that are keys of ``[generalisation]`` (``--held-out-maps`` is ``held_out_maps``)."""
CSV_NAME = "generalisation.csv"


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``generalise``."""
    parser = subparsers.add_parser(
        "generalise",
        help="train agents on a set of maps, evaluate them on maps never seen",
        description="Write a generalisation config from the flags and run it as 'skidnav run' "
        "does (resumable in --out); print the tables and write --out/generalisation.csv.",
    )
    parser.add_argument(
        "--agent",
        action="append",
        help=f"repeatable; default: {' and '.join(DEFAULT_AGENTS)} (dqn needs the deep extra)",
    )
    counts = {
        "seeds": "runs per agent (seeds 0 .. N−1)", "training_maps": "training worlds",
        "held_out_maps": "held-out worlds", "episodes": "training episodes per run",
        "max_steps": "actions per episode", "rollouts": "greedy rollouts per map",
        "root_seed": "the maps and every run's seeds",
    }  # fmt: skip
    for key, text in counts.items():
        flag = "--" + key.replace("_", "-")
        parser.add_argument(flag, type=int, default=DEFAULTS[key], help=f"{text} (%(default)s)")
    parser.add_argument("--map-kind", choices=MAP_KINDS, default=DEFAULTS["map_kind"])
    parser.add_argument("--slip", choices=SLIP_PRESETS, default=DEFAULTS["slip"])
    parser.add_argument("--observation", choices=OBSERVATIONS, default=DEFAULTS["observation"])
    parser.add_argument(
        "--eval-epsilon", type=float, default=DEFAULTS["eval_epsilon"],
        help="ε of the second, ε-greedy evaluation (%(default)s)",
    )  # fmt: skip
    parser.add_argument(
        "--params", action="append", default=[], metavar="AGENT=JSON",
        help="an agent's parameters as a JSON object (repeatable)",
    )  # fmt: skip
    add_run_arguments(parser, KIND)
    parser.set_defaults(func=_generalise)


def agent_params(texts: list[str]) -> dict[str, dict[str, Any]]:
    """Each agent's parameters: :data:`DEFAULT_PARAMS` overridden by the ``--params AGENT=JSON``
    ``texts``; UserError in one line naming the flag otherwise."""
    params = {name: dict(values) for name, values in DEFAULT_PARAMS.items()}
    for text in texts:
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


def config_document(args: argparse.Namespace) -> dict[str, Any]:
    """The generalisation config of the flags (what ``configs/generalisation.toml`` holds for
    the defaults)."""
    params = agent_params(args.params)
    settings = {"name": KIND, **{key: getattr(args, key) for key in SETTINGS}}
    agents = [
        {"name": name, **({"params": params[name]} if params.get(name) else {})}
        for name in args.agent or DEFAULT_AGENTS
    ]
    return {"kind": KIND, KIND: settings, "agents": agents}


def _generalise(args: argparse.Namespace) -> int:
    grid, outcome = run_document(config_document(args), args)
    from skidnav.studies.agent_grid import results_csv, study_results
    from skidnav.studies.generalisation import report
    from skidnav.studies.generalisation.evaluation import grid_split

    results = report.results_of(study_results(outcome.out_dir, LAYOUT)[1])
    print(report.split_line(grid_split(grid)))
    for result in results:
        print(report.run_line(result))
    print(report.summary_text(results))
    for reference in report.grid_references(grid):
        print(report.reference_line(reference))
    path = outcome.out_dir / CSV_NAME
    write_user_file(path, results_csv(results).encode(), "results")
    print(f"wrote {path}")
    return 0
