"""The report's first screen in a real browser (headless Chromium through Selenium, the shared
fixture ``tests.browser_support.browser``): at 1280 × 720 the verdict is on it, whole, and the
convergence table with the speed-ups starts on it."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from skidnav.experiments.report.html import write_report
from tests.browser_support import serve_directory, severe_console_messages

SCREEN = (1280, 720)
"""Width and height of the first screen [CSS pixels]."""


def test_the_first_screen_shows_the_verdict_and_the_speed_up_table(
    serial_results: Path, tmp_path: Path, browser: Callable[[int, int], Any]
) -> None:
    from selenium.webdriver.common.by import By

    page = write_report(serial_results, tmp_path / "report.html").path
    driver = browser(*SCREEN)
    with serve_directory(page.parent) as base_url:
        driver.get(base_url + page.name)
        visible = int(driver.execute_script("return window.innerHeight"))
        assert visible == SCREEN[1]
        verdict = driver.find_element(By.ID, "verdict")
        assert verdict.is_displayed() and verdict.text.startswith("Verdict:")
        top, height = verdict.rect["y"], verdict.rect["height"]
        assert top >= 0 and top + height <= visible, (top, height, visible)
        heading = driver.find_element(By.XPATH, "//h2[text()='Convergence']")
        speedups = heading.find_element(By.XPATH, "following-sibling::div[1]/table")
        assert "speed-up" in speedups.find_element(By.TAG_NAME, "thead").text
        assert speedups.rect["y"] < visible, f"the speed-up table starts at {speedups.rect['y']}"
        assert severe_console_messages(driver) == []
        shot = tmp_path / "first-screen.png"
        assert driver.save_screenshot(str(shot))
    pixels = np.asarray(Image.open(shot).convert("L"), dtype=np.int16)
    assert pixels.shape[1] >= SCREEN[0] * 0.95  # the whole width of the screen
    assert pixels.std() > 10 and (pixels < 100).mean() > 0.005  # text on it, not a blank page
