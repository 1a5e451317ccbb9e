"""The results pages have figures, every figure of docs/data is on a page, and a figure drawn
from a run's results by ``docs/tools/report_figure.py`` says which run and config it shows."""

from __future__ import annotations

import re

from PIL import Image

from tests.docs.docs_tools import ROOT

DOCS = ROOT / "docs"
IMAGE = re.compile(r"!\[[^\]]*\]\((data/[^)\s]+\.png)\)")
"""A markdown image of docs/data."""
HEADLINE_PAGES = (
    "summary.md",
    "results.md",
    "continuity.md",
    "kinematic-value.md",
    "kinematic-model.md",
    "sutton-barto.md",
    "discretization-gap.md",
)
"""Results pages that must show at least one figure."""


def results_pages() -> list[str]:
    """The pages under "Results" in mkdocs.yml's nav, in order."""
    lines = (ROOT / "mkdocs.yml").read_text(encoding="utf-8").splitlines()
    start = next(n for n, line in enumerate(lines) if line.strip() == "- Results:")
    pages = []
    for line in lines[start + 1 :]:
        if not line.startswith("      - "):
            break
        pages.append(line.rsplit(":", 1)[1].strip())
    return pages


def images(page: str) -> list[str]:
    return IMAGE.findall((DOCS / page).read_text(encoding="utf-8"))


def test_the_headline_results_pages_show_figures_that_exist() -> None:
    assert set(HEADLINE_PAGES) <= set(results_pages())
    for page in HEADLINE_PAGES:
        shown = images(page)
        assert shown, f"docs/{page} has no figure"
        for path in shown:
            with Image.open(DOCS / path) as picture:
                assert picture.width > 300 and picture.height > 200, path


def test_every_figure_of_docs_data_is_on_a_page() -> None:
    referenced = {
        path for page in DOCS.rglob("*.md") for path in images(str(page.relative_to(DOCS)))
    }
    figures = {f"data/{path.name}" for path in (DOCS / "data").glob("*.png")}
    assert figures <= referenced, f"not on any page: {sorted(figures - referenced)}"


def test_a_figure_of_a_run_names_its_run_and_config_and_the_page_its_script() -> None:
    for name, config in (
        ("kinematic-value-seconds-convergence", "kinematic-value-seconds"),
        ("kinematic-value-seconds-mppi-learning", "kinematic-value-seconds-mppi"),
    ):
        with Image.open(DOCS / "data" / f"{name}.png") as picture:
            assert picture.info["config"] == config and picture.info["Source"] == config
        page = (DOCS / "kinematic-value.md").read_text(encoding="utf-8")
        assert "docs/tools/report_figure.py" in page and f"configs/{config}.toml" in page
