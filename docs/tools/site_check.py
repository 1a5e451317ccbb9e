r"""Every image and every link inside the built site points at a file that is there, and no
starred symbol turns text into italics (a hook of mkdocs.yml).

mkdocs checks the links and images written in Markdown; this check reads the HTML it wrote, so it
also covers raw HTML, the API reference and the theme. An image or a script from another host is
refused too: the site must render, and search, offline.

Starred symbols (the oracle's L*, C*, V*, Q*, A* search): Markdown reads the text between
two bare ``L*`` as emphasis (``L<em> … L</em>``). The house convention: in Markdown (the pages of
docs/ and the notebooks' text cells) write ``L\*``, escaped; docstrings keep the plain ``L*``
that ``help()`` shows, and the API reference escapes it (docs/tools/griffe_docstrings.py, with
:func:`escape_starred`). In code (a code span or a fenced block) a star is literal: leave it
bare. Two checks hold the convention: a page's Markdown with a bare starred capital outside code
(:func:`bare_stars`), and any rendered page, the API reference and the notebooks included, with an
emphasis that begins inside a word (:func:`emphasis_inside_words`).

Each problem is a warning, which ``--strict`` (``make docs``) turns into a failed build.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable
from html.parser import HTMLParser
from pathlib import Path
from typing import Any
from urllib.parse import unquote, urlsplit

log = logging.getLogger("mkdocs.hooks.site_check")

STARRED = re.compile(r"(?<![\w*\\])([A-Z])\*(?![\w*])")
"""A bare starred symbol: one capital letter, not inside a word, then a single unescaped ``*``
(``L*``, ``V*(start)``; not ``*K*``, ``**L**`` or ``L\\*``)."""
CODE = re.compile(r"^[ \t]*(`{3,}|~{3,})[^\n]*\n.*?^[ \t]*\1[ \t]*$|(`+)[^`].*?\2", re.M | re.S)
"""A fenced code block or a code span, where a star is literal."""
EMPHASIS_INSIDE_WORD = re.compile(r"\w<em>")
"""Rendered emphasis that opens right after a letter: what a bare ``L*`` paired with a later
``*`` becomes."""


def outside_code(text: str, rewrite: Callable[[str], str]) -> str:
    """``text`` with ``rewrite`` applied to every stretch outside code (see :data:`CODE`)."""
    pieces, start = [], 0
    for code in CODE.finditer(text):
        pieces += [rewrite(text[start : code.start()]), code.group(0)]
        start = code.end()
    return "".join([*pieces, rewrite(text[start:])])


def escape_starred(text: str) -> str:
    """Markdown ``text`` with each bare starred symbol outside code escaped: ``L*`` → ``L\\*``."""
    return outside_code(text, lambda prose: STARRED.sub(r"\1\\*", prose))


def bare_stars(markdown: str) -> list[str]:
    """One line per line of ``markdown`` with a bare starred symbol outside code: its number and
    text."""
    marked = outside_code(markdown, lambda prose: STARRED.sub("\0", prose))
    return [
        f"line {number}: {line.strip()}"
        for number, (line, checked) in enumerate(
            zip(markdown.split("\n"), marked.split("\n"), strict=True), 1
        )
        if "\0" in checked
    ]


def emphasis_inside_words(html: str) -> list[str]:
    """The text around each emphasis of ``html`` that opens right after a letter."""
    return [
        html[max(0, found.start() - 30) : found.end() + 30].replace("\n", " ")
        for found in EMPHASIS_INSIDE_WORD.finditer(html)
    ]


class References(HTMLParser):
    """Collects ``<img src>``, ``<script src>`` and ``<a href>`` of one page."""

    def __init__(self) -> None:
        super().__init__()
        self.images: list[str] = []
        self.scripts: list[str] = []
        self.links: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = dict(attrs)
        if tag == "img" and values.get("src"):
            self.images.append(values["src"] or "")
        elif tag == "script" and values.get("src"):
            self.scripts.append(values["src"] or "")
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


def remote(url: str) -> bool:
    """Whether ``url`` names another host."""
    return urlsplit(url).scheme in ("http", "https") or url.startswith("//")


def problems(site: Path) -> list[str]:
    """One line per image that is missing or remote, per remote script and per relative link
    that leads nowhere."""
    found = []
    for page in sorted(site.rglob("*.html")):
        references = References()
        references.feed(page.read_text(encoding="utf-8"))
        name = page.relative_to(site)
        for src in references.images:
            if remote(src):
                found.append(f"{name}: image from another host: {src}")
            elif missing_target(page, site, src):
                found.append(f"{name}: missing image {src}")
        found.extend(
            f"{name}: script from another host: {src}" for src in references.scripts if remote(src)
        )
        found.extend(
            f"{name}: link to a missing file {href}"
            for href in references.links
            if missing_target(page, site, href)
        )
    return found


def on_page_markdown(markdown: str, page: Any, **kwargs: Any) -> str:
    """mkdocs hook: warn once per line of a Markdown page with a bare starred symbol (a
    notebook's page is its JSON here: the rendered check covers it)."""
    if page.file.src_uri.endswith(".md"):
        for line in bare_stars(markdown):
            log.warning(f"{page.file.src_uri}: {line}: write a starred symbol as L\\*")
    return markdown


def on_page_content(html: str, page: Any, **kwargs: Any) -> str:
    """mkdocs hook: warn once per emphasis that opens inside a word in a rendered page."""
    for context in emphasis_inside_words(html):
        log.warning(f"{page.file.src_uri}: italics opened by a bare starred symbol: {context}")
    return html


def on_post_build(config: Any, **kwargs: Any) -> None:
    """mkdocs hook: warn once per problem found in the site just written."""
    for problem in problems(Path(config["site_dir"])):
        log.warning(problem)
