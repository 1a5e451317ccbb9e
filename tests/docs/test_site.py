"""The documentation site as a reader gets it: built as ``make docs`` builds it (``mkdocs build
--strict``: a broken link, anchor or image, or a docstring the API reference cannot read, fails
the build), served over HTTP on 127.0.0.1 and opened in headless chromium (the ``browser``
fixture, tests/docs/conftest.py): each page renders its title, heading and navigation, every
image loads, and the console shows no error; the notebook's page shows its stored outputs; and
opened from disk (file://), as a reader who built it would, the site's search finds a page."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

import skidnav
from tests.browser_support import (
    broken_images,
    missing_tool,
    serve_directory,
    severe_console_messages,
)

ROOT = Path(__file__).resolve().parents[2]
PAGES = {
    "index.html": ("skidnav", "skidnav", 1),
    "guide/getting-started.html": ("Getting started - skidnav", "Getting started", 0),
    "guide/tutorial.html": (
        "skidnav in one notebook: train, compare, plot, drive - skidnav",
        "skidnav in one notebook: train, compare, plot, drive",
        3,
    ),
    "reference/cli.html": ("Command line - skidnav", "Command line", 0),
    "reference/configs.html": ("Configs - skidnav", "Configs", 0),
    "reference/api/agents.html": ("Agents - skidnav", "Agents", 0),
    "agents/index.html": ("Agents - skidnav", "Agents", 0),
    "summary.html": ("At a glance - skidnav", "Results at a glance", 0),
    "continuity.html": ("What continuity buys - skidnav", "What continuity buys", 2),
    "speed.html": ("Speed - skidnav", "Speed", 0),
}
"""Pages opened in the browser: their title, heading and how many images they show at least."""
SECTIONS = ("Guide", "Reference", "Agents", "Results")
"""The top sections of the navigation."""


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The site built into a temporary folder, as ``make docs`` builds it."""
    try:
        import mkdocs  # noqa: F401
        import mkdocstrings  # noqa: F401
    except ModuleNotFoundError:
        missing_tool('mkdocs is not installed (pip install ".[docs]")')
    out = tmp_path_factory.mktemp("site")
    built = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert built.returncode == 0, f"mkdocs build --strict failed:\n{built.stderr[-4000:]}"
    return out


def test_every_page_of_docs_is_built(site: Path) -> None:
    pages = [
        path.relative_to(ROOT / "docs").with_suffix(".html")
        for path in (ROOT / "docs").rglob("*.md")
        if "tools" not in path.relative_to(ROOT / "docs").parts
    ]
    assert [page for page in pages if not (site / page).is_file()] == []


def test_api_reference_shows_docstrings_as_markdown(site: Path) -> None:
    envs = (site / "reference" / "api" / "envs.html").read_text(encoding="utf-8")
    assert "SkidSteerNavEnv" in envs
    assert '<span class="gp">&gt;&gt;&gt; </span>' in envs  # doctests as code, not as quotes
    assert "<blockquote>" not in envs
    for page in (site / "reference" / "api").glob("*.html"):
        assert ":func:`" not in page.read_text(encoding="utf-8"), page.name


def test_the_search_finds_every_name_of_the_python_api(site: Path) -> None:
    index = json.loads((site / "search" / "search_index.json").read_text(encoding="utf-8"))
    assert re.split(index["config"]["separator"], "make_env") == ["make_env"]  # one search word
    titles = {entry["location"]: entry["title"] for entry in index["docs"]}
    for name in skidnav.API:
        assert titles.get(f"reference/api/python.html#skidnav.api.{name}", "").startswith(name)
    listed = (ROOT / "docs" / "reference" / "api" / "index.md").read_text(encoding="utf-8")
    assert re.findall(r"^\| \[[^]]+\]\(([\w.]+)\)", listed, flags=re.MULTILINE)[0] == "python.md"


def test_cli_reference_has_every_command(site: Path) -> None:
    from skidnav.cli import COMMANDS

    cli = (site / "reference" / "cli.html").read_text(encoding="utf-8")
    for verb, entry in COMMANDS.items():
        verbs = [f"{verb} {name}" for name in entry] if isinstance(entry, dict) else [verb]
        for command in verbs:
            assert f"<code>skidnav {command}</code>" in cli, command
            assert f"usage: skidnav {command}" in cli, command


@pytest.fixture(scope="module")
def window(site: Path, browser: Any) -> Iterator[tuple[Any, str]]:
    """One browser window and the base URL of the site, served while the module's tests run."""
    with serve_directory(site) as base_url:
        yield browser(1280, 900), base_url


@pytest.mark.parametrize("page", PAGES)
def test_page_renders_in_a_browser(window: tuple[Any, str], page: str) -> None:
    from selenium.webdriver.common.by import By

    driver, base_url = window
    title, heading, least_images = PAGES[page]
    severe_console_messages(driver)  # forget the previous page's
    driver.get(base_url + page)
    missing = broken_images(driver)
    assert driver.title == title
    assert driver.find_element(By.CSS_SELECTOR, "article h1").text == heading
    navigation = driver.find_element(By.CSS_SELECTOR, "nav.md-nav--primary")
    assert all(section in navigation.get_attribute("textContent") for section in SECTIONS)
    assert len(driver.find_elements(By.TAG_NAME, "img")) >= least_images
    assert missing == []
    assert severe_console_messages(driver) == []


def test_the_checks_see_a_broken_page(
    window: tuple[Any, str], tmp_path_factory: pytest.TempPathFactory
) -> None:
    driver, _ = window
    folder = tmp_path_factory.mktemp("broken")
    (folder / "broken.html").write_text(
        '<!doctype html><title>broken</title><img src="missing.png" alt="none">'
    )
    with serve_directory(folder) as base_url:
        severe_console_messages(driver)
        driver.get(base_url + "broken.html")
        assert broken_images(driver) == [base_url + "missing.png"]
        assert any("missing.png" in message for message in severe_console_messages(driver))


def test_the_notebook_page_shows_its_stored_outputs(site: Path) -> None:
    page = (site / "guide" / "tutorial.html").read_text(encoding="utf-8")
    assert page.count('src="data:image/png;base64,') == 3  # the arena and two figures
    assert "convergence episode</th>" in page  # a table the notebook printed
    assert "L* = " in page  # a stored printout (the text cells write L\*)
    assert "L<em>" not in page


def test_search_works_on_the_site_opened_from_disk(site: Path, browser: Any) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    driver = browser(1280, 900)
    driver.get((site / "index.html").as_uri())  # without the offline plugin: box hidden
    box = driver.find_element(By.CSS_SELECTOR, "input.md-search__input")
    WebDriverWait(driver, 30).until(lambda d: box.is_displayed())
    box.click()
    box.send_keys("make_env")

    links = WebDriverWait(driver, 30).until(
        lambda d: [
            result.get_attribute("href")
            for result in d.find_elements(By.CSS_SELECTOR, "li.md-search-result__item > a")
        ]
    )
    assert all(link.startswith(site.as_uri() + "/") for link in links), links
