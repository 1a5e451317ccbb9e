"""The helpers that build the site (docs/tools/): the check of images and links in the built
HTML, the docstring rewriting of the API reference, and the generated reference pages."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from tests.browser_support import missing_tool
from tests.docs.docs_tools import ROOT, TOOLS, load_tool


def write_site(site: Path) -> None:
    """A built site with one good and one of each bad reference."""
    (site / "sub").mkdir(parents=True)
    (site / "picture.png").write_bytes(b"\x89PNG")
    (site / "index.html").write_text(
        '<img src="picture.png"><img src="gone.png"><img src="https://example.org/a.png">'
        '<a href="sub/page.html#part">ok</a><a href="nowhere.html">bad</a>'
        '<a href="#top">fragment</a><a href="https://example.org/">another site</a>'
    )
    (site / "sub" / "page.html").write_text('<a href="../index.html">up</a><a href="/index.html">')


def test_site_check_names_missing_and_remote_images_and_dead_links(tmp_path: Path) -> None:
    write_site(tmp_path)
    assert load_tool("site_check").problems(tmp_path) == [
        "index.html: missing image gone.png",
        "index.html: image from another host: https://example.org/a.png",
        "index.html: link to a missing file nowhere.html",
    ]


def test_a_broken_raw_html_image_fails_the_strict_build(tmp_path: Path) -> None:
    try:
        import mkdocs  # noqa: F401
    except ModuleNotFoundError:
        missing_tool('mkdocs is not installed (pip install ".[docs]")')
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "index.md").write_text('# Page\n\n<img src="missing.png" alt="none">\n')
    (tmp_path / "mkdocs.yml").write_text(
        f"site_name: check\nstrict: true\nhooks:\n  - {TOOLS / 'site_check.py'}\n"
    )
    built = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict"],
        cwd=tmp_path,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert built.returncode != 0
    assert "index.html: missing image missing.png" in built.stderr


def test_docstrings_lose_sphinx_roles_and_fence_their_doctests() -> None:
    try:
        import griffe  # noqa: F401
    except ModuleNotFoundError:
        missing_tool('griffe is not installed (pip install ".[docs]")')
    tool = load_tool("griffe_docstrings")
    text = "See :func:`~skidnav.a.train` and :mod:`skidnav.envs`.\n\n    >>> 1 + 1\n    2\n\nEnd."
    rewritten = tool.fence_doctests(tool.ROLE.sub(tool.role_as_code, text))
    assert rewritten == (
        "See `train` and `skidnav.envs`.\n\n    ```pycon\n    >>> 1 + 1\n    2\n    ```\n\nEnd."
    )


def test_configs_reference_has_one_row_per_shipped_config() -> None:
    tool = load_tool("generated_pages")
    table = tool.configs_reference()
    configs = sorted((ROOT / "configs").glob("*.toml"))
    assert len(table.splitlines()) == 2 + len(configs)
    for path in configs:
        document = tomllib.loads(path.read_text(encoding="utf-8"))
        row = next(line for line in table.splitlines() if f"| `{path.name}` |" in line)
        if isinstance(document.get("kind"), str):
            assert f"| study `{document['kind']}` |" in row
        elif "experiment" in document:
            assert "| experiment |" in row


@pytest.mark.parametrize(
    ("comment", "expected"),
    [
        ("# What it is,\n# on two lines.\n#\n# More.\nkind = 1\n", "What it is, on two lines."),
        ("# Planning | budget\n#   skidnav run x.toml\n# ends.\n", "Planning \\| budget ends."),
        ("kind = 1\n", ""),
    ],
)
def test_header_comment(comment: str, expected: str) -> None:
    assert load_tool("generated_pages").header_comment(comment) == expected
