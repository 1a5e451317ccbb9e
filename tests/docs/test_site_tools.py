"""The helpers that build the site (docs/tools/): the check of images, scripts and links in the
built HTML and of starred symbols, the docstring rewriting of the API reference, and the
generated reference pages."""

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
        '<script src="sub/local.js"></script><script src="https://example.org/shim"></script>'
        '<a href="sub/page.html#part">ok</a><a href="nowhere.html">bad</a>'
        '<a href="#top">fragment</a><a href="https://example.org/">another site</a>'
    )
    (site / "sub" / "page.html").write_text('<a href="../index.html">up</a><a href="/index.html">')


def test_site_check_names_missing_and_remote_images_and_dead_links(tmp_path: Path) -> None:
    write_site(tmp_path)
    assert load_tool("site_check").problems(tmp_path) == [
        "index.html: missing image gone.png",
        "index.html: image from another host: https://example.org/a.png",
        "index.html: script from another host: https://example.org/shim",
        "index.html: link to a missing file nowhere.html",
    ]


def strict_build(folder: Path, page: str) -> subprocess.CompletedProcess[str]:
    """``mkdocs build --strict`` of a site of one page (Markdown ``page``) checked by
    site_check.py, in ``folder``."""
    try:
        import mkdocs  # noqa: F401
    except ModuleNotFoundError:
        missing_tool('mkdocs is not installed (pip install ".[docs]")')
    (folder / "docs").mkdir()
    (folder / "docs" / "index.md").write_text(page, encoding="utf-8")
    (folder / "mkdocs.yml").write_text(
        "site_name: check\nstrict: true\ntheme:\n  name: material\n  font: false\n"
        f"hooks:\n  - {TOOLS / 'site_check.py'}\n"
    )
    return subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict"],
        cwd=folder,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_a_broken_raw_html_image_fails_the_strict_build(tmp_path: Path) -> None:
    built = strict_build(tmp_path, '# Page\n\n<img src="missing.png" alt="none">\n')
    assert built.returncode != 0
    assert "index.html: missing image missing.png" in built.stderr


def test_bare_starred_symbols_fail_the_strict_build(tmp_path: Path) -> None:
    built = strict_build(tmp_path, "# Page\n\nWithin 10 % of L*, the oracle's V*(start), is L*.\n")
    assert built.returncode != 0
    assert "index.md: line 3: Within 10 % of L*" in built.stderr
    assert "italics opened by a bare starred symbol" in built.stderr  # L<em>, the oracle's …


def test_escaped_starred_symbols_build(tmp_path: Path) -> None:
    built = strict_build(tmp_path, "# Page\n\nWithin 10 % of L\\*, *k* and `L*` and V\\*.\n")
    assert built.returncode == 0, built.stderr
    assert "<em>k</em>" in (tmp_path / "site" / "index.html").read_text(encoding="utf-8")


@pytest.mark.parametrize(
    ("markdown", "bare"),
    [
        ("L* and L*", ["line 1: L* and L*"]),
        ("a\n| L* of its grid |\nV*(start)", ["line 2: | L* of its grid |", "line 3: V*(start)"]),
        ("L\\*, *K*, **L**, 2*3, x* and `L*`", []),
        ("```text\nL* and L*\n```\n~~~\nC*\n~~~", []),
    ],
)
def test_bare_stars_outside_code(markdown: str, bare: list[str]) -> None:
    assert load_tool("site_check").bare_stars(markdown) == bare


def test_escaping_leaves_code_and_emphasis_alone() -> None:
    tool = load_tool("site_check")
    text = "L* is *k* times `C*`;\n```\nV*\n```\nA* and ``Q* `x` ``"
    assert (
        tool.escape_starred(text) == "L\\* is *k* times `C*`;\n```\nV*\n```\nA\\* and ``Q* `x` ``"
    )
    assert tool.bare_stars(tool.escape_starred(text)) == []


def test_emphasis_inside_a_word_is_found() -> None:
    tool = load_tool("site_check")
    assert tool.emphasis_inside_words("<p>of L<em>, V</em>(start)</p>") == [
        "<p>of L<em>, V</em>(start)</p>"
    ]
    assert tool.emphasis_inside_words("<p>child <em>k</em> and (<em>a</em>)</p>") == []


def test_docstrings_lose_sphinx_roles_fence_their_doctests_and_escape_stars() -> None:
    try:
        import griffe  # noqa: F401
    except ModuleNotFoundError:
        missing_tool('griffe is not installed (pip install ".[docs]")')
    tool = load_tool("griffe_docstrings")
    text = "See :func:`~skidnav.a.train` and :mod:`skidnav.envs`.\n\n    >>> 1 + 1\n    2\n\nEnd."
    text += " L* is its optimum; `L*` in code."
    assert tool.rewrite(text) == (
        "See `train` and `skidnav.envs`.\n\n    ```pycon\n    >>> 1 + 1\n    2\n    ```\n\n"
        "End. L\\* is its optimum; `L*` in code."
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


def test_the_agents_reference_describes_the_deep_agents_without_pytorch(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from skidnav import extras

    # As in the venv of `make docs` (the core and the docs extra): the deep extra is not found.
    monkeypatch.setitem(extras.EXTRAS, "deep", ("skidnav_no_such_module",))
    assert not extras.installed("deep")
    text = load_tool("generated_pages").agents_reference()
    for name in ("dqn", "ppo", "sac"):
        row = next(line for line in text.splitlines() if line.startswith(f"| `{name}` |"))
        assert "Stable-Baselines3" in row and "not described" not in row, row
        assert f'??? note "`{name}`: its `params`' in text
    assert not extras.installed("deep")  # the check is back once the reference is written
