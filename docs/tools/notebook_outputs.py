"""The notebooks' stored outputs: what the site shows of them, executed by this tree's code.

The site renders notebooks/ with the outputs stored in them (mkdocs-jupyter does not execute
them: a site build needs no kernel, no compiled kernels and no robot server). So the outputs are
stored, and tests/test_notebooks.py checks that they are there and that a fresh execution prints
the same (:func:`comparable`). After changing a notebook, or code whose printed results it
shows, store them anew from the repository's root::

    python docs/tools/notebook_outputs.py notebooks/tutorial.ipynb

Each notebook runs top to bottom in its own folder, on the running Python's kernel; the cells'
timing metadata is not kept, so that the file changes only where an output does. A cell tagged
``outputs-vary`` (:data:`VARYING`) is not compared: the tutorial's drive on the robot server,
whose episodes have come out differently on a loaded machine (an episode aborted at once).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import Any

VARIES = re.compile(r"\d+(?:\.\d+)? s\b|127\.0\.0\.1:\d+")
"""What differs between two executions of the same code: a duration printed in seconds, and the
free port a server was given."""


VARYING = "outputs-vary"
"""The tag of a code cell whose outputs two executions need not agree on."""


def execute(path: Path, timeout: float = 900.0) -> Any:
    """The notebook at ``path`` executed top to bottom (an ``nbformat`` node), as stored: no
    timing metadata, no widget state [timeout: seconds per cell]."""
    import nbformat
    from nbclient import NotebookClient

    notebook = nbformat.read(path, as_version=4)
    client = NotebookClient(
        notebook,
        timeout=timeout,
        kernel_name="python3",
        record_timing=False,
        store_widget_state=False,
        resources={"metadata": {"path": str(path.resolve().parent)}},
    )
    client.execute()
    for cell in notebook.cells:
        cell.metadata.pop("execution", None)
    return notebook


def comparable(notebook: Any) -> list[list[str]]:
    """Per code cell, its printed text and plain-text results, durations and ports masked: what
    two executions by the same code agree on (standard error, a warning or a progress bar, is
    left out)."""
    cells = []
    for cell in notebook["cells"]:
        if cell["cell_type"] != "code" or VARYING in cell["metadata"].get("tags", []):
            continue
        texts = []
        for output in cell["outputs"]:
            if output["output_type"] == "stream" and output["name"] == "stdout":
                texts.append("".join(output["text"]))
            elif "data" in output and "text/plain" in output["data"]:
                texts.append("".join(output["data"]["text/plain"]))
        cells.append([VARIES.sub("…", text) for text in texts])
    return cells


def main(paths: list[str]) -> int:
    """Execute each notebook named and store it with its outputs."""
    import nbformat

    for name in paths:
        nbformat.write(execute(Path(name)), name)
        print(f"stored the outputs of {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
