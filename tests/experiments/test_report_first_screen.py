"""The report's first screen in a real browser (headless Chromium through Selenium, the shared
fixture ``tests.browser_support.browser``): at 1280 × 720 the verdict is on it, whole, and the
convergence table with the speed-ups starts on it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from skidnav.experiments.report.html import write_report

SCREEN = (1280, 720)
"""Width and height of the first screen [CSS pixels]."""


def test_the_first_screen_shows_the_verdict_and_the_speed_up_table(
    serial_results: Path, tmp_path: Path
) -> None:
    browser_support = pytest.importorskip("tests.browser_support")
    from selenium.webdriver.common.by import By

    page = write_report(serial_results, tmp_path / "report.html").path
    driver = browser_support.browser(*SCREEN)
    try:
        driver.get(page.resolve().as_uri())
        visible = min(SCREEN[1], int(driver.execute_script("return window.innerHeight")))
        verdict = driver.find_element(By.ID, "verdict")
        assert verdict.is_displayed() and verdict.text.startswith("Verdict:")
        top, height = verdict.rect["y"], verdict.rect["height"]
        assert top >= 0 and top + height <= visible, (top, height, visible)
        heading = driver.find_element(By.XPATH, "//h2[text()='Convergence']")
        speedups = heading.find_element(By.XPATH, "following-sibling::table[1]")
        assert "speed-up" in speedups.find_element(By.TAG_NAME, "thead").text
        assert speedups.rect["y"] < visible, f"the speed-up table starts at {speedups.rect['y']}"
        shot = tmp_path / "first-screen.png"
        assert driver.save_screenshot(str(shot))
    finally:
        driver.quit()
    pixels = np.asarray(Image.open(shot).convert("L"), dtype=np.int16)
    assert pixels.shape[1] >= SCREEN[0] * 0.95  # the whole width of the screen
    assert pixels.std() > 10 and (pixels < 100).mean() > 0.005  # text on it, not a blank page
