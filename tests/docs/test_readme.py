"""The README a new user reads first: short, every link and image it names is in the repository,
the thesis cited in full, and the headline figure still shows what docs/results.md says."""

from __future__ import annotations

import json
import re
import unicodedata
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest
from PIL import Image

from tests.docs.docs_tools import ROOT, load_tool

README = ROOT / "README.md"
MAX_LINES = 150
"""A README read top to bottom in five minutes."""
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def slug(heading: str) -> str:
    """A heading's anchor as mkdocs writes it (Python-Markdown's toc: ASCII, lower case,
    punctuation dropped, runs of spaces and hyphens one hyphen)."""
    text = unicodedata.normalize("NFKD", heading).encode("ascii", "ignore").decode("ascii")
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def anchors(markdown: str) -> set[str]:
    """The anchors of a Markdown file's headings."""
    return {slug(line.lstrip("#")) for line in markdown.splitlines() if line.startswith("#")}


def relative_links(markdown: str) -> list[str]:
    """Every link and image target that is not another site."""
    return [target for target in LINK.findall(markdown) if not urlsplit(target).scheme]


def test_readme_is_short() -> None:
    assert len(README.read_text(encoding="utf-8").splitlines()) <= MAX_LINES


def test_every_link_and_image_of_the_readme_is_in_the_repository() -> None:
    text = README.read_text(encoding="utf-8")
    targets = relative_links(text)
    assert targets, "expected links in the README"
    for target in targets:
        parts = urlsplit(target)
        path = ROOT / unquote(parts.path) if parts.path else README
        assert path.exists(), target
        if parts.fragment and path.suffix == ".md":
            assert parts.fragment in anchors(path.read_text(encoding="utf-8")), target


def test_the_readme_images_are_pictures() -> None:
    images = [target for target in LINK.findall(README.read_text(encoding="utf-8"))]
    pictures = [ROOT / target for target in images if target.endswith((".png", ".svg", ".jpg"))]
    assert pictures, "expected the headline figure in the README"
    for picture in pictures:
        with Image.open(picture) as image:
            assert image.width > 0 and image.height > 0


def test_the_thesis_is_cited_in_full() -> None:
    references = README.read_text(encoding="utf-8").split("## References", 1)[1]
    assert "M. Alhawary (2020)" in references
    assert "*Reinforcement learning based navigation for autonomous mobile robots in" in references
    assert "MSc thesis, University of Twente" in references


def test_headline_figure_shows_the_numbers_of_the_results_page() -> None:
    figure = load_tool("speed_up_figure")
    measured = figure.measured_rows(figure.RESULTS.read_text(encoding="utf-8"))
    with Image.open(figure.FIGURE) as image:
        shown = json.loads(image.info["numbers"])
    expected = json.loads(json.dumps([[agent, list(p), list(e)] for agent, p, e in measured]))
    assert shown == expected, "run `python docs/tools/speed_up_figure.py` to draw it again"


def test_headline_figure_refuses_a_results_page_without_its_rows() -> None:
    figure = load_tool("speed_up_figure")
    text = figure.RESULTS.read_text(encoding="utf-8").replace("dyna-q, expected |", "dyna-q |")
    with pytest.raises(ValueError, match="dyna-q, expected"):
        figure.measured_rows(text)


def test_slug_matches_the_headings_links_use() -> None:
    assert slug(" The thesis's claims") == "the-thesiss-claims"
    assert slug("Files written (`--out DIR`)") == "files-written-out-dir"
    assert slug("What continuity buys") == "what-continuity-buys"
    assert "references" in anchors(Path(README).read_text(encoding="utf-8"))
