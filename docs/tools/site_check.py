"""Every image and every link inside the built site points at a file that is there (a hook of
mkdocs.yml).

mkdocs checks the links and images written in Markdown; this check reads the HTML it wrote, so it
also covers raw HTML, the API reference and the theme. An image from another host is refused
too: the site must render offline. Each problem is a warning, which ``--strict`` (``make docs``)
turns into a failed build.
"""

from __future__ import annotations

import logging
from html.parser import HTMLParser
from pathlib import Path
from typing import Any
from urllib.parse import unquote, urlsplit

log = logging.getLogger("mkdocs.hooks.site_check")


class References(HTMLParser):
    """Collects ``<img src>`` and ``<a href>`` of one page."""

    def __init__(self) -> None:
        super().__init__()
        self.images: list[str] = []
        self.links: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = dict(attrs)
        if tag == "img" and values.get("src"):
            self.images.append(values["src"] or "")
        elif tag == "a" and values.get("href"):
            self.links.append(values["href"] or "")


def missing_target(page: Path, site: Path, url: str) -> bool:
    """Whether ``url`` (relative to ``page``, or to the site's root when it starts with ``/``)
    names no file of ``site``; a bare fragment or another host is not checked here."""
    parts = urlsplit(url)
    if parts.scheme or parts.netloc or not parts.path:
        return False
    base = site if parts.path.startswith("/") else page.parent
    target = (base / unquote(parts.path).lstrip("/")).resolve()
    if target.is_dir():
        target = target / "index.html"
    return not (target.is_file() and target.is_relative_to(site.resolve()))


def problems(site: Path) -> list[str]:
    """One line per image that is missing or remote and per relative link that leads nowhere."""
    found = []
    for page in sorted(site.rglob("*.html")):
        references = References()
        references.feed(page.read_text(encoding="utf-8"))
        name = page.relative_to(site)
        for src in references.images:
            if urlsplit(src).scheme in ("http", "https") or src.startswith("//"):
                found.append(f"{name}: image from another host: {src}")
            elif missing_target(page, site, src):
                found.append(f"{name}: missing image {src}")
        found.extend(
            f"{name}: link to a missing file {href}"
            for href in references.links
            if missing_target(page, site, href)
        )
    return found


def on_post_build(config: Any, **kwargs: Any) -> None:
    """mkdocs hook: warn once per problem found in the site just written."""
    for problem in problems(Path(config["site_dir"])):
        log.warning(problem)
