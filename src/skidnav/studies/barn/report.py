"""The report section of a BARN study: the benchmark's scores with their intervals.

Every interval is a 95 % percentile bootstrap over the scored runs of a cell (worlds × seeds;
:func:`skidnav.statistics.intervals.bootstrap_interval`), its generator keyed by the root seed
and the cell's labels. A share (success, collision, timeout) is the mean of its 0/1 column.
The tables read the last scored run of every run (zero-shot: the only one; learning: the one
after the last training episode); the learning table reads every episode.

1. **Scores**: per agent and floor, the mean BARN metric, the three shares, the mean AT of the
   successes.
2. **By difficulty**: the mean metric per world-index quintile (worlds 0–59 … 240–299, from open
   to cluttered).
3. **Paired differences**: per floor and pair of agents, the mean over (world, seed) of the
   difference of their metrics, with the paired bootstrap interval
   (:func:`~skidnav.statistics.intervals.difference_interval`): both agents met the same worlds
   and floor noise.
4. **Learning** (learning protocol): the mean metric and success share after each episode, with
   the mean seconds of driving it took (at most :data:`LEARNING_ROWS` episodes evenly spread,
   :func:`shown_episodes`).
5. **Worlds**: a few worlds spread over the selection, each agent's last scored trajectory.
"""

from __future__ import annotations

import html
import itertools
import zlib
from pathlib import Path

import numpy as np
import pandas as pd

from skidnav.experiments.report.page import image, interval_text, table
from skidnav.experiments.store import ResultStore
from skidnav.statistics.formatting import plural
from skidnav.statistics.intervals import Interval, bootstrap_interval, difference_interval
from skidnav.studies.barn.grid import CONTROL_PERIOD, LAYOUT, QUINTILE_SIZE, BarnGrid
from skidnav.studies.barn.picture import worlds_picture

PICTURE_WORLDS = 4
"""Worlds drawn in the picture."""
PAIR_KEYS = ["world", "preset", "seed"]
"""What pairs two agents' scored runs: the same world, floor and seed."""
LEARNING_ROWS = 20
"""About the most episodes the learning table shows per agent and floor (the results hold
every one)."""


def _rng(grid: BarnGrid, *labels: object) -> np.random.Generator:
    """The bootstrap generator of one table cell, keyed by the root seed and its labels."""
    key = zlib.crc32("|".join(str(label) for label in labels).encode())
    return np.random.default_rng([grid.root_seed, 0xBA27, key])


def _text(estimate: Interval) -> str:
    """``0.38 [0.25, 0.50]``; the estimate alone when its interval is undefined (one run)."""
    return interval_text(*estimate, digits=2)


def _cell(values: pd.Series, grid: BarnGrid, *labels: object) -> str:
    """The mean of ``values`` with its bootstrap interval (:func:`_text`)."""
    return _text(bootstrap_interval(values.to_numpy(float), _rng(grid, *labels)))


def scores_table(last: pd.DataFrame, grid: BarnGrid) -> str:
    """Table 1 of the module doc."""
    records = []
    for (agent, floor), rows in last.groupby(["agent", "preset"], sort=False):
        successes = rows.loc[rows["success"].astype(bool), "time"]
        records.append(
            {
                "agent": agent,
                "floor": floor,
                "runs": str(len(rows)),
                "metric": _cell(rows["metric"], grid, agent, floor, "metric"),
                **{
                    share: _cell(rows[share].astype(float), grid, agent, floor, share)
                    for share in ("success", "collision", "timeout")
                },
                "AT of successes [s]": f"{successes.mean():.1f}" if len(successes) else "n/a",
            }
        )
    return table(pd.DataFrame.from_records(records), labels=2)


def difficulty_table(last: pd.DataFrame, grid: BarnGrid) -> str:
    """Table 2 of the module doc: one column per quintile present, cells ``metric [CI] (n)``."""
    records = []
    quintiles = sorted(int(q) for q in last["quintile"].unique())
    for (agent, floor), rows in last.groupby(["agent", "preset"], sort=False):
        record = {"agent": agent, "floor": floor}
        for q in quintiles:
            cell = rows[rows["quintile"] == q]
            title = f"worlds {q * QUINTILE_SIZE}–{(q + 1) * QUINTILE_SIZE - 1}"
            record[title] = (
                f"{_cell(cell['metric'], grid, agent, floor, q)} ({len(cell)})" if len(cell) else ""
            )
        records.append(record)
    return table(pd.DataFrame.from_records(records), labels=2)


def differences_table(last: pd.DataFrame, grid: BarnGrid) -> str:
    """Table 3 of the module doc (empty with one agent)."""
    records = []
    agents = list(dict.fromkeys(last["agent"]))
    for first, second in itertools.combinations(agents, 2):
        for floor, rows in last.groupby("preset", sort=False):
            metric = rows.pivot_table(index=PAIR_KEYS, columns="agent", values="metric")
            pairs = metric[[first, second]].dropna()
            difference = difference_interval(
                pairs[first].to_numpy(), pairs[second].to_numpy(),
                _rng(grid, first, second, floor), paired=True,
            )  # fmt: skip
            records.append(
                {
                    "agent A": first,
                    "agent B": second,
                    "floor": floor,
                    "pairs": str(len(pairs)),
                    "metric A − B": _text(difference),
                    "A better / B better": f"{(pairs[first] > pairs[second]).sum()} / "
                    f"{(pairs[first] < pairs[second]).sum()}",
                }
            )
    if not records:
        return "<p class='note'>One agent: no paired differences.</p>"
    return table(pd.DataFrame.from_records(records), labels=3)


def shown_episodes(episodes: int) -> list[int]:
    """The episodes (1 … ``episodes``) the learning table shows: every one up to
    :data:`LEARNING_ROWS`, else the first, every k-th (k = ⌈episodes / LEARNING_ROWS⌉) and the
    last.

    >>> shown_episodes(3)
    [1, 2, 3]
    >>> shown = shown_episodes(1000)
    >>> shown[:3], shown[-2:], len(shown)
    ([1, 50, 100], [950, 1000], 21)
    """
    step = -(-episodes // LEARNING_ROWS)
    return sorted({1, episodes, *range(step, episodes + 1, step)})


def learning_table(episodes: pd.DataFrame, grid: BarnGrid) -> str:
    """Table 4 of the module doc: one row per agent, floor and shown episode
    (:func:`shown_episodes`)."""
    records = []
    shown = episodes[episodes["episode"].isin(shown_episodes(grid.episodes))]
    for (agent, floor, episode), rows in shown.groupby(["agent", "preset", "episode"]):
        records.append(
            {
                "agent": agent,
                "floor": floor,
                "episode": str(episode),
                "driving so far [s]": f"{rows['driving_seconds'].mean():.1f}",
                "metric": _cell(rows["metric"], grid, agent, floor, episode, "metric"),
                "success": _cell(rows["success"].astype(float), grid, agent, floor, episode),
            }
        )
    return table(pd.DataFrame.from_records(records), labels=3)


def picture(store: ResultStore, last: pd.DataFrame, grid: BarnGrid) -> str:
    """The worlds picture (item 5): up to :data:`PICTURE_WORLDS` worlds evenly spread over those
    with results, each agent's run of seed 0 on the first floor."""
    shown = last[(last["seed"] == 0) & (last["preset"] == grid.floors[0])]
    worlds = sorted(int(world) for world in shown["world"].unique())
    if not worlds:
        return ""
    picks = np.unique(np.linspace(0, len(worlds) - 1, min(PICTURE_WORLDS, len(worlds))).round())
    chosen: dict[int, list[tuple[str, np.ndarray, bool]]] = {worlds[int(k)]: [] for k in picks}
    rows = shown[shown["world"].isin(list(chosen))]
    for run_id, world, agent, success in rows[["run_id", "world", "agent", "success"]].to_numpy():
        run = store.read_run(str(run_id))
        counts = run.arrays["pose_counts"]
        poses = run.arrays["poses"][int(counts[:-1].sum()) :]
        chosen[int(world)].append((str(agent), poses, bool(success)))
    title = f"Last scored run of each agent, seed 0, floor {grid.floors[0]}"
    return image(worlds_picture(chosen, title), "BARN worlds with each agent's trajectory")


def report_section(run_dir: Path) -> str:
    """The BARN section of the HTML report of ``run_dir`` (module doc).

    Raises:
        UserError: ``run_dir`` holds no BARN results, or none finished.
    """
    store = ResultStore(run_dir, LAYOUT)
    grid: BarnGrid = store.config()
    episodes, _ = store.load_tables()
    episodes = episodes.astype({"world": int, "quintile": int})
    last = episodes.loc[episodes.groupby("run_id")["episode"].idxmax()]
    parts = [
        f"<h2>BARN, {html.escape(grid.protocol)}</h2>",
        f"<p>{html.escape(grid.description)}</p>" if grid.description else "",
        f"<p class='note'>{html.escape(settings_text(grid, last))}</p>",
        "<h3>Scores</h3>",
        scores_table(last, grid),
        "<h3>By difficulty (world-index quintiles)</h3>",
        difficulty_table(last, grid),
        "<h3>Paired differences by world</h3>",
        differences_table(last, grid),
    ]
    if grid.protocol == "learning":
        shown = shown_episodes(grid.episodes)
        after = (
            "each episode"
            if len(shown) == grid.episodes
            else f"episodes {shown[0]}, {shown[1]}, {shown[2]}, …, {shown[-1]}"
        )
        parts += [f"<h3>Learning: score after {after}</h3>", learning_table(episodes, grid)]
    parts += ["<h3>Worlds</h3>", picture(store, last, grid)]
    return "".join(parts)


def settings_text(grid: BarnGrid, last: pd.DataFrame) -> str:
    """What was run and how it is scored, in one paragraph."""
    protocol = (
        "a new agent's one scored run per world"
        if grid.protocol == "zero-shot"
        else f"{plural(grid.episodes, 'training episode')} per world, each then scored"
    )
    return (
        f"{plural(len(last), 'run')} of {plural(len(grid.worlds), 'world')}, "
        f"{plural(len(grid.floors), 'floor')}, {plural(grid.seeds, 'seed')}; {protocol}; "
        f"{grid.dynamics} dynamics, {actions_text(grid)}, a {grid.lidar_rays}-ray 270° laser "
        "of 10 m. "
        "Scored as the benchmark's run.py: success within 1 m of the goal, a collision or 100 s "
        "from the first 0.1 m of motion end the run; metric = success · OT / clip(AT, 2·OT, "
        "8·OT). Intervals: 95 % bootstrap over the runs of each cell."
    )


def actions_text(grid: BarnGrid) -> str:
    """How long the agents' actions last: ``0.1-s actions``, or with longer discrete actions
    ``0.1-s actions (discrete agents: 0.5-s actions, each held for 5 of the scored runs' 0.1-s
    steps)``."""
    if grid.action_periods == 1:
        return f"{CONTROL_PERIOD:g}-s actions"
    return (
        f"{CONTROL_PERIOD:g}-s actions (discrete agents: {grid.discrete_action_duration:g}-s "
        f"actions, each held for {grid.action_periods} of the scored runs' 0.1-s steps)"
    )
