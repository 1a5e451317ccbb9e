"""Docstrings as the API reference shows them (a griffe extension of mkdocs.yml).

skidnav's docstrings name other objects the Sphinx way (``:func:`train_agent```,
``:class:`~skidnav.envs.step_info.StepInfo```) and carry doctests (``>>>`` lines) that pytest
runs. Markdown knows neither: a role would print as its raw text and a ``>>>`` line would open
three nested quotes; and a docstring's plain ``L*`` would open italics up to the next star. This
extension rewrites each docstring before it is rendered: a role becomes a code span of its target
(``~`` keeps the last name only), each doctest block a fenced ``pycon`` block, and each bare
starred symbol outside code is escaped (``L\\*``, the convention of docs/tools/site_check.py). The
source files are not touched.
"""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import griffe

ROLE = re.compile(r":(?:py:)?(?:func|class|mod|data|attr|meth|obj|exc|const|ref):`([^`]+)`")
"""A Sphinx cross-reference role and its target."""


def role_as_code(match: re.Match[str]) -> str:
    """``:func:`~a.b.c``` → `` `c` ``; ``:mod:`a.b``` → `` `a.b` ``."""
    target = match.group(1)
    if target.startswith("~"):
        target = target[1:].rsplit(".", 1)[-1]
    return f"`{target}`"


def fence_doctests(text: str) -> str:
    """Each run of doctest lines (from a ``>>>`` line to the next blank line) in a ``pycon``
    fence, indented as its first line."""
    lines = text.split("\n")
    out: list[str] = []
    index = 0
    while index < len(lines):
        line = lines[index]
        if not line.lstrip().startswith(">>>"):
            out.append(line)
            index += 1
            continue
        indent = line[: len(line) - len(line.lstrip())]
        out.append(f"{indent}```pycon")
        while index < len(lines) and lines[index].strip():
            out.append(lines[index])
            index += 1
        out.append(f"{indent}```")
    return "\n".join(out)


def site_check() -> ModuleType:
    """docs/tools/site_check.py (where the starred-symbol convention lives), imported once by
    file path: the tools are not a package."""
    name = "skidnav_docs_site_check"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            name, Path(__file__).with_name("site_check.py")
        )
        assert spec is not None and spec.loader is not None
        sys.modules[name] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(sys.modules[name])
    return sys.modules[name]


def rewrite(docstring: str) -> str:
    """``docstring`` as the API reference renders it (see the module docstring)."""
    return site_check().escape_starred(fence_doctests(ROLE.sub(role_as_code, docstring)))


class SphinxRolesAndDoctests(griffe.Extension):
    """Rewrite every docstring griffe loads (see the module docstring)."""

    def on_object(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        """Called by griffe once per object (module, class, function, attribute) of the loaded
        tree."""
        if obj.docstring is not None:
            obj.docstring.value = rewrite(obj.docstring.value)
