"""The wheel-speed navigator's targets (docs/agents/mppi-kinematic.md, "Over many worlds"),
read from the results of ``configs/navigator-targets-*.toml``: a navigator's results
directory and, optionally, that of the tabular reference on the same worlds (same root seed,
maps, floors and seeds: the worlds are equal, :func:`skidnav.experiments.runs.expand_runs`).

Per floor and map: the final greedy success (the share of the last evaluation's starts that
reach the goal) pooled over worlds with its 95 % bootstrap interval; the worlds where the
reference's final greedy success is 100 % but the navigator's is under 90 %; the runs that
learn (sustained ≥ 90 % greedy success from some episode on); the Kaplan–Meier median seconds
of driving to that sustained success (runs that never reach it censored at their driving time)
with its interval; and the median collisions per episode.

    python benchmarks/navigator_targets.py runs/navigator-targets-obstacles \\
        [--reference runs/navigator-targets-obstacles-reference]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd

from skidnav.experiments.store import EXPERIMENT_LAYOUT, ResultStore
from skidnav.statistics.intervals import bootstrap_interval
from skidnav.statistics.survival import median_interval

WORLD = ["map", "preset", "seed"]
"""The columns naming a world."""
SAME_WORLDS = ("root_seed", "maps", "presets", "seeds")
"""The config keys two results directories must share for their worlds to be equal."""


def final_greedy(run_dir: Path) -> pd.DataFrame:
    """Per run (one row per world): its summary and ``final_greedy``, the last episode's greedy
    success share."""
    episodes, summaries = ResultStore(run_dir, EXPERIMENT_LAYOUT).load_tables()
    last = episodes.sort_values("episode").groupby("run_id").tail(1)
    return summaries.merge(last[["run_id", "greedy_success"]], on="run_id").rename(
        columns={"greedy_success": "final_greedy"}
    )


def world_config(run_dir: Path) -> tuple[object, ...]:
    """The values of :data:`SAME_WORLDS` of the results' config."""
    config = ResultStore(run_dir, EXPERIMENT_LAYOUT).config()
    return tuple(getattr(config, key) for key in SAME_WORLDS)


def targets(runs: pd.DataFrame, reference: pd.DataFrame | None) -> pd.DataFrame:
    """One row per (preset, map) of the measures of the module docstring."""
    rng = np.random.default_rng(0)
    rows = []
    for (preset, map_kind), group in runs.groupby(["preset", "map"], sort=False):
        success = bootstrap_interval(group["final_greedy"].to_numpy(float), rng)
        learned = group["seconds_to_success90"].notna()
        times = np.where(learned, group["seconds_to_success90"], group["driving_seconds"])
        seconds = median_interval(times, learned.to_numpy(), rng)
        row = {
            "floor": preset, "map": map_kind, "worlds": len(group),
            "final greedy success":
                f"{success.estimate:.0%} [{success.low:.0%}, {success.high:.0%}]",
            "runs that learn": f"{int(learned.sum())}/{len(group)}",
            "seconds to ≥ 90 %": f"{seconds.estimate:.0f} [{seconds.low:.0f}, {seconds.high:.0f}]",
            "collisions/episode": f"{group['collisions_per_episode'].median():.2f}",
        }  # fmt: skip
        if reference is not None:
            paired = group.merge(reference, on=WORLD, suffixes=("", "_reference"))
            solved = paired[paired["final_greedy_reference"] >= 1.0]
            missed = solved[solved["final_greedy"] < 0.9]
            row["reference at 100 %"] = len(solved)
            row["of those under 90 %"] = f"{len(missed)}" + (
                f" (seeds {', '.join(map(str, missed['seed']))})" if len(missed) else ""
            )
        rows.append(row)
    return pd.DataFrame(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run_dir", type=Path, help="the navigator's results")
    parser.add_argument("--reference", type=Path, help="the tabular reference's results")
    options = parser.parse_args()
    runs = final_greedy(options.run_dir)
    reference = None
    if options.reference is not None:
        if world_config(options.run_dir) != world_config(options.reference):
            raise SystemExit(
                f"{options.reference}: not the worlds of {options.run_dir} (the root seed, maps, "
                "presets and seeds must be equal)"
            )
        reference = final_greedy(options.reference)[[*WORLD, "final_greedy"]]
    table = targets(runs, reference)
    print(table.to_markdown(index=False))
    pooled = bootstrap_interval(runs["final_greedy"].to_numpy(float), np.random.default_rng(0))
    print(
        f"\npooled over {len(runs)} worlds: final greedy success {pooled.estimate:.1%} "
        f"[{pooled.low:.1%}, {pooled.high:.1%}]"
    )


if __name__ == "__main__":
    main()
