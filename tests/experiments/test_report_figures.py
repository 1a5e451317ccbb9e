"""The report's figures and page a reader can use: one colour per agent whatever else is drawn,
one colour scale per value-map figure, tables that scroll with their label column fixed, the
resolved config folded."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from skidnav.agents.catalog import agent_names
from skidnav.experiments.report import plots
from skidnav.experiments.report.colours import PALETTE, agent_colour, agent_colours
from skidnav.experiments.report.html import build_report
from skidnav.experiments.report.maps import value_limits, value_maps_figure
from skidnav.experiments.report.page import config_and_provenance, page, table
from skidnav.experiments.store import TrialResult
from tests.browser_support import serve_directory


def _line_colours(monkeypatch: pytest.MonkeyPatch, draw: Callable[[], bytes]) -> dict[str, Any]:
    """The colour of each labelled line of the figure ``draw`` makes (caught before its PNG)."""
    seen: dict[str, Any] = {}

    def catch(figure: Figure, *args: Any, **kwargs: Any) -> bytes:
        for axes in figure.axes:
            for line in axes.get_lines():
                if not line.get_label().startswith("_"):
                    seen[line.get_label()] = line.get_color()
        return b""

    monkeypatch.setattr(plots, "to_png", catch)
    draw()
    return seen


def _profile(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    episodes = np.arange(1.0, 11.0)
    share = np.sort(np.random.default_rng(seed).uniform(size=10))
    return episodes, share, share * 0.8, np.minimum(share * 1.2, 1.0)


def test_an_agent_keeps_its_colour_in_reports_of_other_agent_sets(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    first = {label: _profile(n) for n, label in enumerate(["q-learning", "dyna-full"])}
    second = {label: _profile(n) for n, label in enumerate(["my-agent", "dyna-q", "dyna-full"])}
    one = _line_colours(monkeypatch, lambda: plots.performance_profiles(first, 10, "a"))
    other = _line_colours(monkeypatch, lambda: plots.performance_profiles(second, 10, "b"))
    assert one["dyna-full"] == other["dyna-full"] == agent_colour("dyna-full")
    assert one["q-learning"] != one["dyna-full"]  # not the first colour of every figure
    assert (
        agent_colours(["dyna-full", "x"])["dyna-full"] == agent_colours(["dyna-full"])["dyna-full"]
    )


def test_registered_agents_have_distinct_palette_colours_in_catalog_order() -> None:
    names = agent_names()
    colours = [agent_colour(name) for name in names]
    assert len(set(colours)) == len(names) <= len(PALETTE)
    assert colours == list(PALETTE[: len(names)])


def test_the_agents_of_one_report_never_share_a_colour() -> None:
    variants = [f"mppi-kinematic[kinematic_model={model}]" for model in ("learned", "prior")]
    labels = agent_names()[:15] + variants + ["dyna-full-expected", "my-agent", "another"]
    colours = agent_colours(labels)
    assert len(set(colours.values())) == len(labels) == len(PALETTE)
    assert all(colours[name] == agent_colour(name) for name in agent_names()[:15])
    assert agent_colours(reversed(labels)) == colours  # not the order the figure lists them in


def test_an_unknown_label_keeps_its_colour_beside_other_agents() -> None:
    label = "dyna-full-expected"
    alone = agent_colour(label)
    others = [name for name in agent_names() if agent_colour(name) != alone]
    assert agent_colours([others[0], label])[label] == alone
    assert agent_colours([label, *others[1:4], "x"])[label] == alone
    # where a registered agent of the same report has its colour, it takes another one
    owner = next(name for name in agent_names() if agent_colour(name) == alone)
    assert agent_colours([owner, label])[label] != alone


def _run(agent: str, values: np.ndarray) -> TrialResult:
    n_x, n_y = values.shape
    arrays = {
        "value_map": values,
        "heading_map": np.zeros((n_x, n_y), dtype=np.int64),
        "occupancy": np.zeros((n_x, n_y), dtype=bool),
        "start": np.array([0, 0]),
        "goal": np.array([n_x - 1, n_y - 1]),
        "slip_eta": np.zeros((3, 3)),
    }
    return TrialResult(f"run-{agent}", {"agent": agent, "seed": 0}, {}, {}, arrays)


def test_the_value_maps_of_one_figure_share_one_scale_and_one_colour_bar() -> None:
    low = np.full((6, 5), -10.0)
    low[0, 0] = np.nan
    high = np.linspace(0.0, 50.0, 30).reshape(6, 5)
    runs = [_run("q-learning", low), _run("dyna-full", high)]
    assert value_limits(runs) == (-10.0, 50.0)
    figure = value_maps_figure(runs, "values")
    images = [
        im for axes in figure.axes for im in axes.get_images() if im.get_cmap().name == "viridis"
    ]
    assert len(images) == 2
    assert {image.get_clim() for image in images} == {(-10.0, 50.0)}
    colour_bars = [axes for axes in figure.axes if axes.get_label() == "<colorbar>"]
    assert len(colour_bars) == 1


def test_value_limits_of_runs_without_values() -> None:
    empty = np.full((3, 3), np.nan)
    assert value_limits([_run("q-learning", empty)]) == (0.0, 1.0)
    assert value_limits([_run("q-learning", np.full((3, 3), 2.0))]) == (1.5, 2.5)


def _wide_table(columns: int = 14, rows: int = 4) -> str:
    frame = pd.DataFrame(
        [[f"row {r}"] + [f"{r * c}.5 [1.2, 3.4]" for c in range(1, columns)] for r in range(rows)],
        columns=["label"] + [f"column {c}" for c in range(1, columns)],
    )
    return table(frame)


def test_every_table_scrolls_with_its_label_column_fixed() -> None:
    text = page("t", [_wide_table(), "<table><tr><td>a study's own</td></tr></table>"])
    style = text[text.index("<style>") : text.index("</style>")]
    assert re.search(r"\.scroll\{[^}]*overflow-x:auto", style)
    assert re.search(r"td:first-child,th:first-child\{[^}]*position:sticky;left:0", style)
    assert text.count("<table") == text.count("<div class='scroll'><table") == 2


def test_the_resolved_config_is_folded() -> None:
    parts = "".join(config_and_provenance({"name": "x", "seeds": 3}, {}))
    folded = re.search(
        r"<details[^>]*><summary>[^<]+</summary><pre>(.*?)</pre></details>", parts, re.DOTALL
    )
    assert folded is not None and "&quot;seeds&quot;: 3" in folded.group(1)


def test_the_report_has_its_tables_in_scroll_boxes_and_its_config_folded(
    serial_results: Path,
) -> None:
    text = build_report(serial_results)
    assert text.count("<table") == text.count("<div class='scroll'><table") > 2
    assert "<details class='config'><summary>" in text


def test_a_wide_table_scrolls_and_keeps_its_labels_in_view(
    tmp_path: Path, browser: Callable[[int, int], Any]
) -> None:
    from selenium.webdriver.common.by import By

    (tmp_path / "wide.html").write_text(page("wide", [_wide_table()]), encoding="utf-8")
    driver = browser(700, 600)
    with serve_directory(tmp_path) as base_url:
        driver.get(base_url + "wide.html")
        box = driver.find_element(By.CLASS_NAME, "scroll")
        width, inner = driver.execute_script(
            "return [arguments[0].clientWidth, arguments[0].scrollWidth]", box
        )
        assert inner > width, "the table fits: nothing to test"
        label = driver.find_element(By.XPATH, "//tbody/tr[1]/td[1]")
        before = label.rect["x"]
        driver.execute_script("arguments[0].scrollLeft = arguments[0].scrollWidth", box)
        assert driver.execute_script("return arguments[0].scrollLeft", box) > 0
        assert label.rect["x"] == pytest.approx(before, abs=1.0)  # the label column stays
        last = driver.find_element(By.XPATH, "//tbody/tr[1]/td[14]")
        right = last.rect["x"] + last.rect["width"]
        assert right <= box.rect["x"] + box.rect["width"] + 1.0  # the last column is reachable
