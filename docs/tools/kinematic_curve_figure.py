"""The learned kinematic model's error against seconds of driving (docs/kinematic-model.md),
drawn from the results of a ``kinematic-curve`` study (``configs/kinematic-models-curve.toml``):
writes docs/data/kinematic-curve.png and prints the page's table.

    skidnav run configs/kinematic-models-curve.toml --out runs/kinematic-curve
    PYTHONPATH=src python docs/tools/kinematic_curve_figure.py runs/kinematic-curve
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from skidnav.experiments.store import ResultStore
from skidnav.studies.kinematic_models.curve_grid import LAYOUT, MODELS
from skidnav.studies.kinematic_models.curve_table import (
    curve_means,
    floor_label,
    markdown_table,
    plateau_note,
)

OUT = Path(__file__).resolve().parents[1] / "data" / "kinematic-curve.png"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run_dir", type=Path, help="results of a kinematic-curve study")
    run_dir = parser.parse_args().run_dir
    store = ResultStore(run_dir, LAYOUT)
    curve, episodes = store.config(), store.load_tables()[0]
    figure, axes = plt.subplots(1, 2, figsize=(10, 4))
    floors = [(dynamics, floor) for dynamics in curve.dynamics for floor in curve.floors]
    for index, (dynamics, floor) in enumerate(floors):
        colour, label = plt.get_cmap("tab10")(index % 10), floor_label(dynamics, floor)
        for model in MODELS:
            mean = 1e3 * curve_means(episodes, dynamics, floor, model)
            style = "-" if model == "learned" else ":"
            for axis, column in zip(axes, (0, 1), strict=True):
                axis.plot(curve.driving_seconds, mean[:, column], style, marker="o",
                          color=colour, label=f"{label}, {model}")  # fmt: skip
    for axis, title in zip(axes, ("one 0.1-s sub-step", "1 s ahead"), strict=True):
        axis.set(xscale="log", yscale="log", xlabel="seconds of driving fitted on",
                 ylabel="RMS position error [mm]", title=title)  # fmt: skip
    axes[1].legend(fontsize=6)
    figure.tight_layout()
    figure.savefig(OUT, dpi=120)
    print(markdown_table(run_dir))
    print(plateau_note())
    print(f"written to {OUT}")


if __name__ == "__main__":
    main()
