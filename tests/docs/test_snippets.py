"""The Python snippets of the agents' pages and of Getting started run as written.

The rule: every fenced ```` ```python ```` block of ``docs/agents/*.md`` and
``docs/guide/getting-started.md`` runs, top to bottom, in a fresh namespace, in an empty
working folder (what it saves goes there), with matplotlib drawing to files only; a block
that is a sketch, not a program, says so on the line before its fence with
``<!-- not run: … -->``. Every agent of the catalog has a page with at least one block that
runs. An agent whose extra is missing is skipped (failed under ``make test``, which installs
every extra). The snippets keep their sizes small (a few episodes), so a reader can paste them
too; the first run of a kernel compiles it (numba's cache keeps it), which the time limit allows
for."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from skidnav.extras import MissingExtraError
from tests.browser_support import missing_tool
from tests.docs.docs_tools import ROOT
from tests.saved_file_support import within

PAGES = [*sorted((ROOT / "docs" / "agents").glob("*.md")), ROOT / "docs/guide/getting-started.md"]
"""The pages whose snippets run."""
NOT_RUN = "<!-- not run:"
"""How a sketch's preceding line marks it."""
SECONDS = 600.0
"""Longest one snippet may take (a first compile of its kernels included)."""


def snippets(page: Path) -> list[tuple[str, bool]]:
    """The ```python blocks of ``page``, each with whether it runs (not marked a sketch)."""
    text = "\n" + page.read_text(encoding="utf-8")
    found = []
    for match in re.finditer(r"\n```python\n(.*?)^```$", text, flags=re.MULTILINE | re.DOTALL):
        before = text[: match.start()].rsplit("\n", 1)[-1]
        found.append((match.group(1), not before.startswith(NOT_RUN)))
    return found


RUN = [
    pytest.param(code, id=f"{page.stem}-{index}")
    for page in PAGES
    for index, (code, runs) in enumerate(snippets(page))
    if runs
]


def test_every_agent_has_a_page_with_a_snippet_that_runs() -> None:
    from skidnav.agents.catalog import families

    for family in families():
        for name in family.agents:
            page = ROOT / "docs" / "agents" / f"{family.page(name)}.md"
            assert any(runs for _, runs in snippets(page)), page.name


def test_a_sketch_is_marked_and_left_out() -> None:
    core = snippets(ROOT / "docs" / "agents" / "core.md")
    assert core and not any(runs for _, runs in core)
    assert len(RUN) > len(PAGES) // 2


@pytest.mark.parametrize("code", RUN)
def test_the_snippet_runs(code: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import matplotlib

    matplotlib.use("Agg")  # figures go to files; nothing opens a window
    monkeypatch.chdir(tmp_path)
    try:
        with within(SECONDS):
            exec(compile(code, "<snippet>", "exec"), {"__name__": "__snippet__"})
    except MissingExtraError as error:  # the deep agents' PyTorch: make test installs it
        missing_tool(str(error))
