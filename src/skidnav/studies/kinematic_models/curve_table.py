"""The table of a data curve: per dynamics, floor and model, the mean over seeds of each t's
one-step error, 1-s error and 95 % coverage; per dynamics and floor the learned model's plateau
time (median over seeds) and its coverage after 10 s — as Markdown rows (the docs' table,
``docs/tools/kinematic_curve_figure.py``) and as the report's HTML section."""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np
import pandas as pd

from skidnav.experiments.store import ResultStore
from skidnav.studies.kinematic_models.curve import PLATEAU_RATIO
from skidnav.studies.kinematic_models.curve_grid import LAYOUT, MODELS, KinematicCurve


def curve_means(episodes: pd.DataFrame, dynamics: str, floor: str, model: str) -> np.ndarray:
    """The mean over seeds of one model's scores, shape (len(driving_seconds), 3): one-step
    error [m], 1-s error [m], coverage (NaN for the prior)."""
    rows = episodes[(episodes["algorithm"] == dynamics) & (episodes["preset"] == floor)]
    columns = [f"{model}_one_step", f"{model}_one_second", f"{model}_coverage"]
    return rows.groupby("episode")[columns].mean().sort_index().to_numpy(float)


def floor_label(dynamics: str, floor: str) -> str:
    """``floor``, or ``MuJoCo, floor`` on the physics robot."""
    return floor if dynamics == "kinematic" else f"MuJoCo, {floor}"


def curve_rows(run_dir: Path) -> tuple[KinematicCurve, list[list[str]]]:
    """(the config, the table's rows): floor, model, then per t the cell ``one-step [mm] /
    1-s [mm] / coverage``, the last two columns the learned model's median plateau time [s]
    and mean coverage after 10 s (blank on the prior's row)."""
    store = ResultStore(run_dir, LAYOUT)
    curve: KinematicCurve = store.config()
    episodes, summaries = store.load_tables()
    rows = []
    for dynamics in curve.dynamics:
        for floor in curve.floors:
            runs = summaries[(summaries["algorithm"] == dynamics) & (summaries["preset"] == floor)]
            if runs.empty:
                continue
            for model in MODELS:
                cells = [
                    f"{1e3 * one_step:.2f} / {1e3 * one_second:.1f}"
                    + ("" if np.isnan(coverage) else f" / {100 * coverage:.0f} %")
                    for one_step, one_second, coverage in curve_means(
                        episodes, dynamics, floor, model
                    )
                ]
                tail = ["", ""]
                if model == "learned":
                    tail = [
                        f"{runs['plateau_seconds'].median():g}",
                        f"{100 * runs['coverage_late'].mean():.0f} %",
                    ]
                rows.append([floor_label(dynamics, floor), model, *cells, *tail])
    return curve, rows


def header(curve: KinematicCurve) -> list[str]:
    """The column titles of :func:`curve_rows`."""
    seconds = [f"{t:g} s" for t in curve.driving_seconds]
    return ["floor", "model", *seconds, "plateau [s]", "coverage ≥ 10 s"]


def markdown_table(run_dir: Path) -> str:
    """The rows of :func:`curve_rows` as a Markdown table."""
    curve, rows = curve_rows(run_dir)
    titles = header(curve)
    lines = ["| " + " | ".join(titles) + " |", "|" + "---|" * len(titles)]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows])


def report_section(run_dir: Path) -> str:
    """The curve's section of the HTML report of ``run_dir``.

    Raises:
        UserError: ``run_dir`` holds no curve results, or none finished.
    """
    curve, rows = curve_rows(run_dir)
    frame = pd.DataFrame(rows, columns=header(curve))
    return (
        "<h2>The learned kinematic model against seconds of driving</h2>"
        f"<p>{len(rows) // len(MODELS)} floors, {curve.seeds} seeds each; the model refitted on "
        f"the first t s of a random drive and scored on the next {curve.test_seconds:g} s. "
        "Cells: RMS one-sub-step error [mm] / RMS 1-s error [mm] / share of observed outputs "
        "inside the 95 % predictive interval.</p>"
        + frame.to_html(index=False, escape=True, border=0)
        + f'<p class="note">{html.escape(plateau_note())}</p>'
    )


def plateau_note() -> str:
    """What the plateau column means."""
    return (
        "Plateau: the first t from which the learned model's 1-s error stays within "
        f"{PLATEAU_RATIO:g}× its error at the longest t, median over seeds."
    )
