"""docs/architecture.md against the code: its layer rows are the import contract's layers, and
every module and path it names exists."""

from __future__ import annotations

import importlib
import re
import tomllib
from pathlib import Path

import pytest

from tests.docs.docs_tools import ROOT

PAGE = ROOT / "docs" / "architecture.md"
SRC = ROOT / "src"
CODE = re.compile(r"`([^`\n]+)`")
LAYER_ROW = re.compile(r"^\| `([^`]+)` \|", re.MULTILINE)
DOTTED = re.compile(r"^skidnav(?:\.\w+)+$")
PATH = re.compile(r"^[\w./-]+(?:\.py|/)$")


def page_text() -> str:
    return PAGE.read_text(encoding="utf-8")


def contract_layers() -> list[str]:
    """The rows of the layers contract of pyproject.toml, top to bottom."""
    settings = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    contracts = settings["tool"]["importlinter"]["contracts"]
    (layers,) = [contract["layers"] for contract in contracts if contract["type"] == "layers"]
    return [str(layer) for layer in layers]


def drawn_layers() -> list[str]:
    """The first column of the table under "## Layers"."""
    section = page_text().split("## Layers", 1)[1].split("\n## ", 1)[0]
    return LAYER_ROW.findall(section)


def named_code() -> list[str]:
    """Every code span of the page, outside fenced blocks."""
    text = re.sub(r"^```.*?^```", "", page_text(), flags=re.MULTILINE | re.DOTALL)
    return CODE.findall(text)


def test_the_layer_rows_are_the_contracts_layers() -> None:
    assert drawn_layers() == contract_layers()


def test_every_layer_row_names_packages_of_skidnav() -> None:
    for row in drawn_layers():
        for name in re.split(r" [|:] ", row):
            package = SRC / "skidnav" / name
            assert package.is_dir() or package.with_suffix(".py").is_file(), name


def dotted_names() -> list[str]:
    return sorted({name for name in named_code() if DOTTED.match(name)})


def path_names() -> list[str]:
    return sorted({name for name in named_code() if PATH.match(name) and "/" in name})


def test_the_page_names_modules_and_paths() -> None:
    assert len(dotted_names()) >= 10
    assert len(path_names()) >= 20


@pytest.mark.parametrize("name", dotted_names())
def test_every_dotted_name_exists(name: str) -> None:
    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            found: object = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError:
            continue
        for attribute in parts[cut:]:
            found = getattr(found, attribute)
        return
    pytest.fail(f"{name}: no such module")


@pytest.mark.parametrize("name", path_names())
def test_every_path_exists(name: str) -> None:
    """A path is the repository's (``src/…``, ``tests/…``), else under ``src/skidnav/``, else under
    ``src/skidnav/agents/`` (the tables of the agents' modules)."""
    bases = [ROOT, SRC / "skidnav", SRC / "skidnav" / "agents"]
    assert any((base / name).exists() for base in bases), name


def table_rows() -> list[str]:
    """Each row of the page's tables, after its table's header (which may name the folder its
    modules are under)."""
    rows, header = [], ""
    for line in page_text().splitlines():
        if not line.startswith("|"):
            header = ""
        elif not header:
            header = line
        elif not line.startswith("|---"):
            rows.append(f"{header}\n{line}")
    return rows


def row_folders(row: str) -> list[Path]:
    """The folders a table row speaks of: its layer's packages, the folders it names, and the
    folders its named paths sit in."""
    roots = [ROOT, SRC / "skidnav", SRC / "skidnav" / "agents"]
    folders: list[Path] = []
    for name in CODE.findall(row):
        for part in re.split(r" [|:] ", name):
            if "/" in part or re.fullmatch(r"\w+", part):
                for root in roots:
                    target = root / part
                    if target.is_dir():
                        folders.append(target)
                    elif target.is_file():
                        folders.append(target.parent)
    return folders


@pytest.mark.parametrize("row", table_rows(), ids=lambda row: row.split("\n")[1][:40])
def test_every_module_a_row_names_is_in_a_folder_it_names(row: str) -> None:
    """A bare ``module.py`` in a table row is in a folder the row or its table's header names (or
    a folder below it)."""
    line = row.split("\n")[1]
    modules = [name for name in CODE.findall(line) if re.fullmatch(r"\w+\.py", name)]
    folders = row_folders(row)
    for module in modules:
        assert any(next(folder.rglob(module), None) for folder in folders), (module, line[:60])
