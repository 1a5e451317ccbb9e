"""The browser fixture of tests/browser_support.py, for the tests of the documentation site."""

from tests.browser_support import browser  # noqa: F401  (a fixture, found by name)
