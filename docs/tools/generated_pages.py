"""Reference pages written from the code at build time (a hook of mkdocs.yml), so that they cannot
drift from it.

A page marks where a generated part goes with an HTML comment on a line of its own:

* ``<!-- generated: cli -->``: every command of ``skidnav``, its ``--help`` as argparse prints it
  (:func:`skidnav.cli.build_parser`), one section per command, groups first;
* ``<!-- generated: configs -->``: one row per file of ``configs/``: its kind, the command that
  runs it and the header comment that says what it is.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import tomllib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
MARKER = re.compile(r"^<!-- generated: (\w+) -->$", re.MULTILINE)
HELP_WIDTH = "100"
"""Columns argparse wraps its help to (it reads ``COLUMNS``)."""


def commands(
    parser: argparse.ArgumentParser, words: tuple[str, ...] = ("skidnav",)
) -> Iterator[tuple[tuple[str, ...], argparse.ArgumentParser]]:
    """Every parser of the command tree, depth first, with its words: ``(("skidnav", "study",
    "search"), parser)``."""
    yield words, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                yield from commands(child, (*words, name))


def cli_reference() -> str:
    """One section per command: its name as a heading, its help as text."""
    if str(ROOT / "src") not in sys.path:
        sys.path.insert(0, str(ROOT / "src"))
    from skidnav.cli import build_parser

    os.environ["COLUMNS"] = HELP_WIDTH
    sections = []
    for words, parser in commands(build_parser()):
        heading = "#" * min(len(words) + 1, 4)
        sections.append(f"{heading} `{' '.join(words)}`\n\n```text\n{parser.format_help()}```\n")
    return "\n".join(sections)


def config_kind(document: dict[str, Any]) -> str:
    """A config's kind as ``skidnav run`` reads it: a study's ``kind``, else an experiment (a
    file with neither an ``[experiment]`` table nor a ``kind`` is the robot's run config)."""
    if isinstance(document.get("kind"), str):
        return f"study `{document['kind']}`"
    if "experiment" in document or "agents" in document:
        return "experiment"
    return "`skidnav robot run --config`"


def header_comment(text: str) -> str:
    """The first paragraph of a config's leading comment, without its command lines."""
    words: list[str] = []
    for line in text.splitlines():
        if not line.startswith("#"):
            break
        content = line.lstrip("#").strip()
        if not content:
            if words:
                break
            continue
        if content.startswith("skidnav "):
            continue
        words.append(content)
    return " ".join(words).replace("|", "\\|")


def configs_reference() -> str:
    """The table of every shipped config."""
    rows = ["| `configs/…` | kind | what it is |", "|---|---|---|"]
    for path in sorted((ROOT / "configs").glob("*.toml")):
        text = path.read_text(encoding="utf-8")
        kind = config_kind(tomllib.loads(text))
        rows.append(f"| `{path.name}` | {kind} | {header_comment(text)} |")
    return "\n".join(rows) + "\n"


GENERATORS = {"cli": cli_reference, "configs": configs_reference}


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    """mkdocs hook: each marker replaced by what its generator writes."""

    def generated(match: re.Match[str]) -> str:
        name = match.group(1)
        if name not in GENERATORS:
            raise ValueError(f"expected a generated part among {sorted(GENERATORS)}, got {name!r}")
        return GENERATORS[name]()

    return MARKER.sub(generated, markdown)
