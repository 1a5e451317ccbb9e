"""What an online ``mppi-kinematic`` run on the robot did (docs/robot-learning.md, "Measured on
the MuJoCo robot"), from its output folder: the control period (robot seconds between the
control path's decisions, from ``summary.json``), the learner's refits and cost-map recomputes,
each episode's outcome, and the driving time (actions × the action duration: homing not
counted) to the first success and to 90 % success — the end of the first episode from which
at least 90 % of the run's remaining episodes (at least three) reached the goal.

    python benchmarks/robot_learning_measurement.py OUT [OUT …]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

MIN_TAIL = 3
"""Fewest remaining episodes that can show 90 % success."""


def episodes(out: Path) -> list[dict[str, Any]]:
    """The ``episode_end`` records of the run log (a torn last line skipped)."""
    records = []
    for line in (out / "run.jsonl").read_text(encoding="utf-8").splitlines():
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            continue
        if record.get("event") == "episode_end":
            records.append(record)
    return records


def driving_times(ended: list[dict[str, Any]], action: float) -> tuple[float | None, float | None]:
    """(driving time [s] to the first success, to 90 % success), None where never reached."""
    driven, first, ninety = 0.0, None, None
    for index, episode in enumerate(ended):
        driven += episode["actions"] * action
        if first is None and episode["reached_goal"]:
            first = driven
        tail = ended[index:]
        share = sum(e["reached_goal"] for e in tail) / len(tail)
        if ninety is None and len(tail) >= MIN_TAIL and share >= 0.9 and episode["reached_goal"]:
            ninety = driven
    return first, ninety


def measure(out: Path) -> dict[str, Any]:
    """One run's figures (module doc)."""
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    period = summary.get("control_period", {})
    ended = episodes(out)
    first, ninety = driving_times(ended, period.get("target", 0.1))
    return {
        "run": str(out),
        "exit_code": summary["exit_code"],
        "period_median": period.get("median"),
        "period_p95": period.get("p95"),
        "period_longest": period.get("longest"),
        "decisions": period.get("count"),
        "refits": summary.get("learning", {}).get("refits"),
        "recomputes": summary.get("learning", {}).get("recomputes"),
        "learner_longest": summary.get("learning", {}).get("longest"),
        "episodes": [
            {key: e[key] for key in ("actions", "reached_goal", "aborted", "collisions")}
            for e in ended
        ],
        "driving_to_first_success": first,
        "driving_to_90_percent": ninety,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("outs", nargs="+", type=Path, help="output folders of skidnav robot run")
    for out in parser.parse_args().outs:
        print(json.dumps(measure(out)))


if __name__ == "__main__":
    main()
