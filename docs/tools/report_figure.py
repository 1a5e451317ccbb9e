"""A figure of an experiment's report (``skidnav report``) for a results page, drawn by the
report's own code (each agent in its one colour), every map × preset cell side by side in one PNG:
``convergence``, the share of runs converged by each episode per agent with its 95 % bootstrap
band (the report's performance profiles); ``learning``, the return and success rate per episode,
mean over seeds with its band (the report's learning curves).

    skidnav run configs/kinematic-value-seconds.toml --out runs/kinematic-value-seconds
    PYTHONPATH=src python docs/tools/report_figure.py convergence runs/kinematic-value-seconds \
        docs/data/kinematic-value-seconds-convergence.png

The run directory's name and its config's name are stored in the PNG's metadata (keys
``Source`` and ``config``).
"""

from __future__ import annotations

import argparse
import io
import math
from pathlib import Path

from PIL import Image, PngImagePlugin

from skidnav.experiments.report import plots
from skidnav.experiments.report.analysis import cells
from skidnav.experiments.report.html import profile_figure
from skidnav.experiments.store import ResultStore

FIGURES = ("convergence", "learning")
"""The report's figures this script draws."""
COLUMNS = 2
"""Cells per row of the figure."""


def cell_pictures(figure: str, run_dir: Path) -> tuple[str, list[Image.Image]]:
    """(the config's name, the report's ``figure`` (one of :data:`FIGURES`) of each cell of
    ``run_dir``)."""
    store = ResultStore(run_dir)
    config, (episodes, summaries) = store.config(), store.load_tables()
    pictures = []
    for map_label, preset, _ in cells(summaries):
        if figure == "convergence":
            png = profile_figure(summaries, config, (map_label, preset))
        else:
            png = plots.learning_curves(episodes, config, map_label, preset)
        pictures.append(Image.open(io.BytesIO(png)))
    return config.name, pictures


def tile(pictures: list[Image.Image], columns: int = COLUMNS) -> Image.Image:
    """``pictures`` left to right, top to bottom, ``columns`` to a row, on white."""
    width = max(picture.width for picture in pictures)
    height = max(picture.height for picture in pictures)
    rows = math.ceil(len(pictures) / columns)
    sheet = Image.new("RGB", (width * min(columns, len(pictures)), height * rows), "white")
    for index, picture in enumerate(pictures):
        row, column = divmod(index, columns)
        sheet.paste(picture.convert("RGB"), (column * width, row * height))
    return sheet


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("figure", choices=FIGURES, help="which of the report's figures")
    parser.add_argument("run_dir", type=Path, help="results of an experiment (skidnav run)")
    parser.add_argument("out", type=Path, help="the PNG to write, e.g. docs/data/NAME.png")
    arguments = parser.parse_args()
    name, pictures = cell_pictures(arguments.figure, arguments.run_dir)
    metadata = PngImagePlugin.PngInfo()
    metadata.add_text("Source", arguments.run_dir.name)
    metadata.add_text("config", name)
    columns = 1 if arguments.figure == "learning" else COLUMNS  # two panels each already
    tile(pictures, columns).save(arguments.out, pnginfo=metadata, optimize=True)
    print(f"written {arguments.out} ({len(pictures)} cells of {name})")


if __name__ == "__main__":
    main()
