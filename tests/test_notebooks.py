"""The notebooks are stored with their outputs, which the site shows (mkdocs-jupyter does not
execute them): every code cell ran, in order and without an error, each figure is there as a
picture, and a fresh execution by this tree's code prints what is stored (durations, ports and
cells tagged as varying aside: docs/tools/notebook_outputs.py, which also stores them anew).
``make test`` executes the notebooks once more with nbmake."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from tests.browser_support import missing_tool
from tests.docs.docs_tools import ROOT, load_tool

NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


def read(path: Path) -> Any:
    """The notebook at ``path`` as its JSON."""
    return json.loads(path.read_text(encoding="utf-8"))


def test_there_is_a_tutorial() -> None:
    assert "tutorial.ipynb" in [path.name for path in NOTEBOOKS]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda path: path.name)
def test_a_notebook_holds_the_outputs_of_one_run_in_order(path: Path) -> None:
    notebook = read(path)
    code = [cell for cell in notebook["cells"] if cell["cell_type"] == "code"]
    assert code
    assert [cell["execution_count"] for cell in code] == list(range(1, len(code) + 1))
    for cell in code:
        kinds = {output["output_type"] for output in cell["outputs"]}
        assert "error" not in kinds, cell["source"][:1]
        assert "execution" not in cell["metadata"]  # no timing: a diff shows only changes
        if any(line.startswith("plt.") for line in cell["source"]):
            pictures = [o for o in cell["outputs"] if "image/png" in o.get("data", {})]
            assert len(pictures) == 1, cell["source"][:1]
    assert sum(bool(cell["outputs"]) for cell in code) >= len(code) - 1
    assert "widgets" not in notebook["metadata"]


def test_masking_keeps_the_numbers_that_matter() -> None:
    tool = load_tool("notebook_outputs")
    cell = {"cell_type": "code", "metadata": {}, "outputs": [
        {"output_type": "stream", "name": "stdout", "text": ["1500 episodes in 4.3 s, 99%\n"]},
        {"output_type": "stream", "name": "stderr", "text": ["compiling…\n"]},
        {"output_type": "execute_result", "data": {"text/plain": ["listening on 127.0.0.1:4211"]}},
    ]}  # fmt: skip
    assert tool.comparable({"cells": [cell]}) == [["1500 episodes in …, 99%\n", "listening on …"]]
    varying = {**cell, "metadata": {"tags": [tool.VARYING]}}
    assert tool.comparable({"cells": [varying, cell]}) == tool.comparable({"cells": [cell]})


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda path: path.name)
def test_the_stored_outputs_are_what_the_code_prints_now(path: Path) -> None:
    try:
        import ipykernel  # noqa: F401
        import nbclient  # noqa: F401
    except ModuleNotFoundError:
        missing_tool('nbclient or ipykernel is not installed (pip install ".[notebook]")')
    tool = load_tool("notebook_outputs")
    assert tool.comparable(tool.execute(path)) == tool.comparable(read(path))
