"""The README's Python example: ``examples/train_two_agents.py``, the same lines as the README's
``## Python`` section, trains two agents and prints when each converged."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "train_two_agents.py"
LINE = re.compile(r"^(dyna-full|q-learning): converged after episode (\d+)$")


def readme_python_block() -> str:
    """The first ```python block of the README's ``## Python`` section."""
    text = (ROOT / "README.md").read_text()
    section = text.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    return section.split("```python\n", 1)[1].split("```", 1)[0]


def test_the_readme_shows_the_example_whole_in_at_most_15_lines() -> None:
    code = EXAMPLE.read_text()
    assert readme_python_block() == code
    assert len(code.splitlines()) <= 15


def test_the_example_prints_both_convergence_episodes() -> None:
    result = subprocess.run(
        [sys.executable, str(EXAMPLE)], capture_output=True, text=True, timeout=300, check=True
    )
    matches = [LINE.match(line) for line in result.stdout.splitlines()]
    assert all(matches) and len(matches) == 2, result.stdout
    episodes = {match.group(1): int(match.group(2)) for match in matches if match}
    assert 1 <= episodes["dyna-full"] < episodes["q-learning"] <= 500  # planning pays
