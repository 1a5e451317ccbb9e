"""Reference pages written from the code at build time (a hook of mkdocs.yml), so that they cannot
drift from it.

A page marks where a generated part goes with an HTML comment on a line of its own:

* ``<!-- generated: cli -->``: every command of ``skidnav``, its ``--help`` as argparse prints it
  (:func:`skidnav.cli.build_parser`), one section per command, groups first;
* ``<!-- generated: prior-gap -->``: how far every floor is from the robot's datasheet
  (``skidnav world floors prior``);
* ``<!-- generated: configs -->``: one row per file of ``configs/``: its kind, the command that
  runs it and the header comment that says what it is;
* ``<!-- generated: agents -->``: every agent family in catalog order
  (:func:`skidnav.agents.catalog.families`): its summary, what it observes and answers, its saved
  formats and extra, one row per agent (its name, what it is, its page) and each agent's settings.
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import inspect
import itertools
import json
import os
import re
import sys
import tomllib
import unittest.mock
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
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


def import_source() -> None:
    """Make ``skidnav`` importable from this tree's ``src/``."""
    if str(ROOT / "src") not in sys.path:
        sys.path.insert(0, str(ROOT / "src"))


def cli_reference() -> str:
    """One section per command: its name as a heading, its help as text."""
    import_source()
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


ROLE = re.compile(r":(?:py:)?\w+:`~?([^`]+)`")
"""A Sphinx cross-reference role in a docstring and its target."""
POINTER = re.compile(r"\s*\((?:module doc|docs/[^)]*)\)|\s*;?\s*docs/[\w/.-]+\.md(?:, \"[^\"]*\")?")
"""A docstring's pointer to another text ("(module doc)", "docs/agents/x.md"): not for readers of
the site, who are on that text."""
SENTENCE_END = re.compile(r"(?<=[.!?])\s+(?=[A-Z])")
OBSERVES = {
    "discrete": "the env's `Discrete` state (the discretized pose: cell and heading bin)",
    "box": 'a `Box` observation (`[env] observation`: `"pose"` or `"features"`)',
}
"""What a family's agents learn over, by :data:`skidnav.agents.family.Observation`."""
ANSWERS = {
    "discrete": "one of the env's `Discrete` actions",
    "wheel-speeds": 'the two wheel speeds [rad/s] (`[env] action = "continuous"`)',
}
"""What an agent answers, by :data:`skidnav.agents.family.Actions`."""


def markdown_text(docstring: str) -> str:
    """A docstring's words as Markdown on one line: roles and ````code```` as code spans,
    pointers to other texts dropped, ``|`` escaped for a table cell."""
    text = " ".join(docstring.split())
    text = POINTER.sub("", ROLE.sub(lambda match: f"``{match.group(1)}``", text))
    text = re.sub(r"``([^`]+)``", lambda match: f"`{match.group(1).rsplit('.', 1)[-1]}`", text)
    return text.replace("|", "\\|")


def first_sentence(docstring: str | None) -> str:
    """The first sentence of a docstring's first paragraph, as :func:`markdown_text` writes it."""
    paragraph = inspect.cleandoc(docstring or "").split("\n\n")[0]
    sentence = SENTENCE_END.split(" ".join(paragraph.split()))[0]
    return markdown_text(sentence)


def agent_description(cls: type) -> str:
    """What an agent is: the first sentence of its class's docstring, up to a ``;``. A class
    docstring that leaves its agent to its module's ("(module doc)") gives way to the module's
    first sentence when that one says more."""
    own = first_sentence(cls.__doc__).split(";")[0].rstrip(".") + "."
    if "(module doc)" not in (cls.__doc__ or ""):
        return own
    module: ModuleType = sys.modules[cls.__module__]
    described = first_sentence(module.__doc__)
    described = re.sub(r"^`[\w-]+`: | \(`[\w-]+`\)", "", described)
    return described[:1].upper() + described[1:] if len(described) > len(own) else own


def field_docstrings(cls: type) -> dict[str, str]:
    """Each field's docstring over the class and its bases: the string under its annotation,
    else its entry in the class docstring's ``Attributes:`` section."""
    names = [field.name for field in dataclasses.fields(cls)]
    documented: dict[str, str] = {}
    for klass in reversed(cls.__mro__[:-1]):
        documented.update(attribute_entries(klass.__dict__.get("__doc__"), names))
        try:
            tree = ast.parse(inspect.cleandoc("\n" + inspect.getsource(klass)))
        except (OSError, TypeError, SyntaxError):
            continue
        body = tree.body[0].body if isinstance(tree.body[0], ast.ClassDef) else []
        for node, after in itertools.pairwise(body):
            if (
                isinstance(node, ast.AnnAssign)
                and isinstance(node.target, ast.Name)
                and isinstance(after, ast.Expr)
                and isinstance(after.value, ast.Constant)
                and isinstance(after.value.value, str)
            ):
                documented[node.target.id] = after.value.value
    return documented


def attribute_entries(docstring: str | None, names: list[str]) -> dict[str, str]:
    """The ``name: what it is`` entries of a docstring's ``Attributes:`` section, for ``names``
    (an entry ends where the next name starts, on its own line or not)."""
    section = (docstring or "").partition("Attributes:")[2]
    if not section or not names:
        return {}
    section = re.split(r"\n\s*\n\s*[A-Z]\w*:\n", section)[0]
    pieces = re.split(r"(?:^|\s)(" + "|".join(map(re.escape, names)) + r"):\s", section)
    return {name: text.strip() for name, text in zip(pieces[1::2], pieces[2::2], strict=True)}


def toml_value(value: object) -> str:
    """A default as a config file writes it."""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(toml_value(item) for item in value) + "]"
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    return repr(value)


def field_default(field: dataclasses.Field[Any]) -> str:
    """A config field's default, or "required"."""
    if field.default is not dataclasses.MISSING:
        return f"`{toml_value(field.default)}`"
    if field.default_factory is not dataclasses.MISSING:
        return f"`{toml_value(field.default_factory())}`"
    return "required"


def settings_table(name: str, config: type) -> str:
    """A collapsed block with one row per field of agent ``name``'s config dataclass."""
    documented = field_docstrings(config)
    rows = [
        f'??? note "`{name}`: its `params` (`{config.__name__}`)"',
        "",
        "    | setting | default | what it sets |",
        "    |---|---|---|",
    ]
    for field in dataclasses.fields(config):
        meaning = first_sentence(documented.get(field.name))
        meaning = meaning[:1].upper() + meaning[1:]
        rows.append(f"    | `{field.name}` | {field_default(field)} | {meaning} |")
    return "\n".join(rows) + "\n"


def agent_actions(cls: type, family: Any) -> str:
    """What agent class ``cls`` answers: its family's ``actions``, unless the class declares an
    action space of its own (``action_space_class``: a ``Box`` is the two wheel speeds)."""
    import gymnasium

    declared = getattr(cls, "action_space_class", None)
    if declared is None:
        return str(family.actions)
    return "wheel-speeds" if issubclass(declared, gymnasium.spaces.Box) else "discrete"


def family_facts(family: Any, module: str, answers: set[str]) -> str:
    """What a family's agents learn over and answer, how they are saved, what they need."""
    observes = OBSERVES[family.observation]
    if family.observation == "box":
        observes = observes.replace("`)", f'`; `"{family.box_observation}"` by default)')
    if len(answers) == 1:
        replies = ANSWERS[answers.pop()]
    else:
        replies = "either " + " or ".join(ANSWERS[kind] for kind in sorted(answers))
        replies += ", each agent as its row says"
    formats = ", ".join(f"`{save_format}`" for save_format in family.save_formats)
    facts = [f"Described by `{module}`.", f"Its agents learn over {observes} and answer {replies}."]
    facts.append(f'Their saved `.json` files have the `"format"` {formats}.')
    if family.policy is not None:
        facts.append(
            "A saved one that drives the wheel speeds also runs on the robot as a frozen policy "
            "(`skidnav robot run --policy-file`)."
        )
    if family.extra:
        facts.append(
            f'They need the `{family.extra}` extra (`pip install "skidnav[{family.extra}]"`).'
        )
    return " ".join(facts)


def described_classes(family: Any, name: str) -> tuple[type, type]:
    """Agent ``name``'s class and config class, also where its family's extra is missing
    (``make docs`` installs the core and the docs extra alone): the check that refuses an agent
    of a missing extra up front (:func:`skidnav.extras.require`) is lifted while they are
    looked up, since the deep agents' modules import PyTorch only when an agent is built. A
    module that imports its extra all the same still raises ``MissingExtraError``."""
    with unittest.mock.patch("skidnav.extras.missing_module", return_value=None):
        return family.agent_class(name), family.config_class(name)


def family_section(family: Any, module: str) -> str:
    """One family (its descriptor ``FAMILY`` in ``module``): a heading, what it is, its table of
    agents, their settings."""
    from skidnav.extras import MissingExtraError

    rows = ["| name | what it is | answers | page |", "|---|---|---|---|"]
    settings, answers = [], set()
    for name in family.agents:
        link = f"[{family.page(name)}]({family.page(name)}.md)"
        try:
            cls, config = described_classes(family, name)
        except MissingExtraError as error:
            missing = f"(not described in this build: {error})"
            rows.append(f"| `{name}` | {missing} | | {link} |")
            continue
        actions = agent_actions(cls, family)
        answers.add(actions)
        short = "wheel speeds" if actions == "wheel-speeds" else "a discrete action"
        rows.append(f"| `{name}` | {agent_description(cls)} | {short} | {link} |")
        settings.append(settings_table(name, config))
    summary = family.summary[:1].upper() + family.summary[1:] + "."
    facts = family_facts(family, module, answers or {family.actions})
    heading = f"## The {family.name} family"
    return "\n".join([heading, "", summary, "", facts, "", *rows, "", *settings])


def agents_reference() -> str:
    """Every family in catalog order (:func:`family_section`). Importing the families imports no
    optional dependency: the deep agents' modules import PyTorch only when one is built."""
    import_source()
    from skidnav.agents.catalog import FAMILY_MODULES, families

    return "\n".join(map(family_section, families(), FAMILY_MODULES))


def prior_gap_reference() -> str:
    """How far every floor is from the robot's datasheet (``skidnav world floors prior``)."""
    import_source()
    from skidnav.commands.floors import prior_gap_table

    return prior_gap_table()


GENERATORS = {
    "cli": cli_reference,
    "configs": configs_reference,
    "agents": agents_reference,
    "prior-gap": prior_gap_reference,
}


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    """mkdocs hook: each marker replaced by what its generator writes."""

    def generated(match: re.Match[str]) -> str:
        name = match.group(1)
        if name not in GENERATORS:
            raise ValueError(f"expected a generated part among {sorted(GENERATORS)}, got {name!r}")
        return GENERATORS[name]()

    return MARKER.sub(generated, markdown)
