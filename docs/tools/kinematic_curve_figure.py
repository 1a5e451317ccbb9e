"""The learned kinematic model's error against seconds of driving on each floor
(docs/kinematic-model.md): drives, fits and scores
(:func:`skidnav.studies.kinematic_models.curve.learning_curve`), then draws
docs/data/kinematic-curve.png and prints the table of the page.

    PYTHONPATH=src python docs/tools/kinematic_curve_figure.py
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from skidnav.studies.kinematic_models.curve import learning_curve
from skidnav.studies.kinematic_models.trial import drive_log

FLOORS = (("thesis", "kinematic"), ("slippery", "kinematic"), ("rough-physics", "kinematic"),
          ("slippery-physics", "kinematic"), ("rough-physics", "mujoco"))  # fmt: skip
SECONDS = (1.0, 2.0, 5.0, 10.0, 20.0, 40.0)
TEST_SECONDS, SEEDS, DT = 60.0, 3, 0.1
OUT = Path(__file__).resolve().parents[1] / "data" / "kinematic-curve.png"


def main() -> None:
    figure, axes = plt.subplots(1, 2, figsize=(10, 4))
    print("| floor | model | " + " | ".join(f"{t:g} s" for t in SECONDS) + " |")
    print("|---|---|" + "---|" * len(SECONDS))
    for slip, dynamics in FLOORS:
        points = {"learned": [], "prior": []}
        for seed in range(SEEDS):
            log = drive_log(seed, int((max(SECONDS) + TEST_SECONDS) / DT), slip, 0.0, 1e9, dynamics)
            for name, curve in learning_curve(log, SECONDS, TEST_SECONDS, DT).items():
                points[name].append(np.array([tuple(point) for point in curve]))
        label = slip if dynamics == "kinematic" else f"MuJoCo, {slip}"
        for name, runs in points.items():
            mean = np.mean(runs, axis=0)  # (n_seconds, 3): one-step, 1-s, coverage
            cells = [
                f"{1e3 * row[0]:.2f} / {1e3 * row[1]:.1f}"
                + ("" if np.isnan(row[2]) else f" / {100 * row[2]:.0f} %")
                for row in mean
            ]
            print(f"| {label} | {name} | " + " | ".join(cells) + " |")
            style = "-" if name == "learned" else ":"
            for axis, column in zip(axes, (0, 1), strict=True):
                axis.plot(
                    SECONDS, 1e3 * mean[:, column], style, marker="o", label=f"{label}, {name}"
                )
    for axis, title in zip(axes, ("one 0.1-s sub-step", "1 s ahead"), strict=True):
        axis.set(xscale="log", yscale="log", xlabel="seconds of driving fitted on",
                 ylabel="RMS position error [mm]", title=title)  # fmt: skip
    axes[1].legend(fontsize=6)
    figure.tight_layout()
    figure.savefig(OUT, dpi=120)
    print(f"written to {OUT}")


if __name__ == "__main__":
    main()
