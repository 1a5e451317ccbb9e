"""A real browser for the tests: headless Debian ``chromium`` driven through ``chromedriver``
(selenium), and a static HTTP server on 127.0.0.1 to open pages from.

The ``browser`` fixture is found by name once a conftest.py imports it (as tests/docs/conftest.py
does: ``from tests.browser_support import browser  # noqa: F401``); then, in a test::

    from selenium.webdriver.common.by import By

    from tests.browser_support import serve_directory, severe_console_messages

    def test_first_screen(browser, tmp_path):
        driver = browser(1280, 720)                    # viewport of exactly 1280 × 720 CSS px
        with serve_directory(report_dir) as base_url:  # "http://127.0.0.1:PORT/"
            driver.get(base_url + "report.html")
            verdict = driver.find_element(By.ID, "verdict")
            assert verdict.rect["y"] + verdict.rect["height"] <= 720
            assert severe_console_messages(driver) == []
            driver.save_screenshot(str(tmp_path / "first-screen.png"))

``browser(width, height)`` opens a new headless window whose viewport (``window.innerWidth`` ×
``window.innerHeight``) is ``width`` × ``height`` CSS pixels, with the browser's console log
kept (:func:`severe_console_messages`); every window it opened is closed at the end of the test
module. :func:`broken_images` lists the ``<img>`` of a page that did not load.

Where chromium, chromedriver or selenium is missing the test is skipped, with the reason; under
``make test`` (which installs them: Debian's ``chromium`` and ``chromium-driver`` by apt-get, and
selenium with the ``dev`` extra, and sets ``SKIDNAV_MAKE_TEST=1``) it fails instead, so that CI
never skips it. Nothing is downloaded at run time: the browser and its driver are the system's.
"""

from __future__ import annotations

import contextlib
import functools
import os
import shutil
import threading
from collections.abc import Callable, Iterator
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any, NoReturn

import pytest

MAKE_TEST = "SKIDNAV_MAKE_TEST"
"""Set to 1 by ``make test``, which installs every optional tool: a missing one then fails."""
PAGE_LOAD_SECONDS = 30


def missing_tool(reason: str) -> NoReturn:
    """Skip the calling test for ``reason``, or fail it under ``make test``."""
    if os.environ.get(MAKE_TEST) == "1":
        pytest.fail(f"{reason} (make test installs it)")
    pytest.skip(reason)


class QuietHandler(SimpleHTTPRequestHandler):
    """Serves files without logging each request to stderr."""

    def log_message(self, format: str, *args: Any) -> None:
        pass


@contextlib.contextmanager
def serve_directory(directory: Path) -> Iterator[str]:
    """Serve ``directory`` over HTTP on 127.0.0.1 (a free port) while the block runs; yields the
    base URL, ending in ``/``."""
    handler = functools.partial(QuietHandler, directory=str(directory))
    server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()
        thread.join(timeout=5)


def new_driver(width: int, height: int) -> Any:
    """A headless chromium window with a ``width`` × ``height`` viewport [CSS px]."""
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ModuleNotFoundError:
        missing_tool("selenium is not installed")
    chromium, chromedriver = shutil.which("chromium"), shutil.which("chromedriver")
    if chromium is None or chromedriver is None:
        missing_tool(
            "chromium or chromedriver is not installed (apt-get install chromium chromium-driver)"
        )
    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for argument in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                     "--disable-extensions", f"--window-size={width},{height}"):  # fmt: skip
        options.add_argument(argument)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(options=options, service=Service(executable_path=chromedriver))
    driver.set_page_load_timeout(PAGE_LOAD_SECONDS)
    fit_viewport(driver, width, height)
    return driver


def fit_viewport(driver: Any, width: int, height: int) -> None:
    """Resize the window so that its viewport is ``width`` × ``height`` [CSS px]."""
    inner = driver.execute_script("return [window.innerWidth, window.innerHeight];")
    if inner != [width, height]:
        outer = driver.get_window_size()
        driver.set_window_size(
            outer["width"] + width - inner[0], outer["height"] + height - inner[1]
        )


@pytest.fixture(scope="module")
def browser() -> Iterator[Callable[[int, int], Any]]:
    """``browser(width, height)`` → a new headless chromium driver (see the module docstring);
    all of them quit at the end of the module."""
    drivers: list[Any] = []

    def open_window(width: int = 1280, height: int = 720) -> Any:
        drivers.append(new_driver(width, height))
        return drivers[-1]

    yield open_window
    for driver in drivers:
        driver.quit()


def wait_until_loaded(driver: Any) -> None:
    """Wait until the page and its images have finished loading."""
    from selenium.webdriver.support.ui import WebDriverWait

    WebDriverWait(driver, PAGE_LOAD_SECONDS).until(
        lambda d: d.execute_script(
            "return document.readyState === 'complete' && "
            "Array.from(document.images).every(image => image.complete);"
        )
    )


def broken_images(driver: Any) -> list[str]:
    """The ``src`` of every ``<img>`` of the current page that did not load (no pixels)."""
    wait_until_loaded(driver)
    sources: list[str] = driver.execute_script(
        "return Array.from(document.images)"
        ".filter(image => !(image.complete && image.naturalWidth > 0))"
        ".map(image => image.currentSrc || image.src);"
    )
    return sources


def severe_console_messages(driver: Any) -> list[str]:
    """The browser console's SEVERE entries (errors, failed loads) since the last call."""
    return [entry["message"] for entry in driver.get_log("browser") if entry["level"] == "SEVERE"]
