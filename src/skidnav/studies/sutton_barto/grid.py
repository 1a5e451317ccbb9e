"""The config of the textbook checks of Sutton & Barto (2018) ch. 8, and the runs it makes.

A config is a TOML file (``configs/sutton-barto-checks.toml``, the defaults of ``skidnav study
reproduce sutton-barto``)::

    kind = "sutton-barto-checks"
    name = "sutton-barto-checks"  # the results directory's default name (runs/NAME)
    examples = ["dyna-maze", "blocking-maze", "shortcut-maze", "prioritized-sweeping"]
    runs = 30                     # independent runs of every check
    root_seed = 0                 # every run's streams derive from it
    planning_steps = [0, 5, 50]   # Example 8.1: Dyna-Q's n
    scales = [1, 2, 3]            # Example 8.4: the Dyna Maze scaled ×1, ×2, ×3

Its checks (:class:`Check`, one agent on one maze, :meth:`TextbookChecks.checks`):

* ``dyna-maze`` — Example 8.1: Dyna-Q with each n of ``planning_steps`` (:data:`BOOK`),
  :data:`DYNA_MAZE_EPISODES` episodes;
* ``blocking-maze``, ``shortcut-maze`` — Examples 8.2/8.3: Dyna-Q and Dyna-Q+ (:data:`CHANGING`,
  κ = :data:`KAPPA`) for a fixed number of steps, the walls changing part-way
  (:data:`CHANGING_MAZES`);
* ``prioritized-sweeping`` — Example 8.4: Dyna-Q and prioritized sweeping (:data:`SWEEP`, θ =
  :data:`THETA`) on the Dyna Maze of each scale, until the greedy path is near-optimal.

:class:`TextbookChecks` is that config, validated on construction, and the runner's grid
(:class:`~skidnav.experiments.runs.Grid`): its agents are the checks (label
:attr:`Check.label`, name the algorithm, params its settings), one placeholder map and preset,
``runs`` seeds. Run (check, k) draws from the runner's stream of its own position in the grid
(``RunSpec.run_seed``, :mod:`skidnav.experiments.runs`; :mod:`skidnav.studies.sutton_barto.trial`),
so its numbers depend on ``root_seed`` and its place alone, not on the backend, the order or a
resume.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

from skidnav.checks import check_integer
from skidnav.errors import shown
from skidnav.experiments.config import AgentSpec, MapSpec, Params
from skidnav.experiments.store import RunLayout
from skidnav.files.configtables import build_dataclass, check_keys, toml_value
from skidnav.files.saved import ArraySpec, up_to

KIND = "sutton-barto-checks"
"""The ``kind`` of a textbook-checks config (``configs/sutton-barto.toml`` is an ordinary
experiment of the Dyna Maze, not this)."""
EXAMPLES = ("dyna-maze", "blocking-maze", "shortcut-maze", "prioritized-sweeping")
"""The checks' examples, in report order: Sutton & Barto (2018) Examples 8.1, 8.2, 8.3, 8.4."""
BOOK = {"alpha": 0.1, "gamma": 0.95, "epsilon": 0.1}
"""Example 8.1's settings (Dyna-Q's n aside)."""
CHANGING = {"alpha": 1.0, "gamma": 0.95, "epsilon": 0.1, "planning_steps": 10}
"""Examples 8.2/8.3's settings (ours: the book does not give all of them)."""
SWEEP = {"alpha": 1.0, "gamma": 0.95, "epsilon": 0.1, "planning_steps": 5}
"""Example 8.4's settings."""
KAPPA = 1e-3
"""Dyna-Q+'s exploration bonus κ (its reward bonus is κ √τ)."""
THETA = 1e-4
"""Prioritized sweeping's priority threshold θ."""
DYNA_MAZE_EPISODES = 50
"""Episodes of every Dyna Maze run (Example 8.1, Figure 8.2)."""
CHANGING_MAZES = {"blocking-maze": (3000, 1000), "shortcut-maze": (6000, 3000)}
"""Example → (time steps of a run, the step after which the walls change)."""
MAX_SWEEP_EPISODES = 300
"""Episodes a prioritized-sweeping check runs at most before it counts as never near-optimal."""
MAX_RUNS, MAX_PLANNING_STEPS, MAX_SCALE = 1000, 10_000, 10
MAP = MapSpec("sutton-barto-mazes", kind="maze")
"""The grid's one map: a placeholder; each check builds its own maze (:mod:`skidnav.envs.mazes`)."""
PRESET = "none"
"""The grid's one slip preset: a placeholder; the mazes are deterministic."""
EPISODE_COLUMNS = ("steps", "reward")
"""Per episode of a run (the results' episode table, one row per episode, in order): actions
taken and reward gathered (1 at the goal, else 0; the last episode of a blocking- or
shortcut-maze run may be cut short by the end of its time steps, with reward 0)."""


class Check(NamedTuple):
    """One agent on one maze of one example.

    Attributes:
        example: one of :data:`EXAMPLES`.
        agent: the algorithm (:func:`skidnav.agents.tabular.registry.make_agent`).
        params: its settings, sorted (key, value) pairs.
        scale: the Dyna Maze's scale (``prioritized-sweeping``; 1 for the other examples).
    """

    example: str
    agent: str
    params: Params
    scale: int = 1

    @property
    def planning_steps(self) -> int:
        """The agent's planning steps per real step."""
        value = dict(self.params)["planning_steps"]
        assert isinstance(value, int)
        return value

    @property
    def label(self) -> str:
        """Unique within a config, e.g. ``"dyna-maze dyna-q n=5"``,
        ``"prioritized-sweeping dyna-q x2"``."""
        if self.example == "dyna-maze":
            return f"{self.example} {self.agent} n={self.planning_steps}"
        if self.example == "prioritized-sweeping":
            return f"{self.example} {self.agent} x{self.scale}"
        return f"{self.example} {self.agent}"


def _params(*settings: Mapping[str, Any]) -> Params:
    merged: dict[str, Any] = {}
    for setting in settings:
        merged.update(setting)
    return tuple(sorted(merged.items()))


CHANGING_AGENTS = (
    ("dyna-q", _params(CHANGING)),
    ("dyna-q-plus", _params(CHANGING, {"kappa": KAPPA})),
)
"""The agents of Examples 8.2/8.3 with their settings."""
SWEEP_AGENTS = (
    ("dyna-q", _params(SWEEP)),
    ("prioritized-sweeping", _params(SWEEP, {"theta": THETA})),
)
"""The agents of Example 8.4 with their settings."""


def _distinct_integers(name: str, values: object, low: int, high: int) -> None:
    """ValueError unless ``values`` is a non-empty tuple of distinct integers in [low, high]."""
    if not (isinstance(values, tuple) and values and len(set(values)) == len(values)):
        shown_values = list(values) if isinstance(values, tuple) else values
        raise ValueError(f"expected {name} to be distinct integers, got {shown(shown_values)}")
    for value in values:
        check_integer(name, value, low, high)


@dataclass(frozen=True)
class TextbookChecks:
    """The checks (module doc); validated on construction.

    Attributes:
        name: the results directory's default name.
        examples: distinct names of :data:`EXAMPLES`.
        runs: independent runs of every check, in [1, :data:`MAX_RUNS`].
        root_seed: the root of every run's streams, an integer ≥ 0.
        planning_steps: Dyna-Q's n on the Dyna Maze, distinct, in [0, 10,000].
        scales: the Dyna Maze's scales for prioritized sweeping, distinct, in [1, 10].
    """

    name: str = KIND
    examples: tuple[str, ...] = EXAMPLES
    runs: int = 30
    root_seed: int = 0
    planning_steps: tuple[int, ...] = (0, 5, 50)
    scales: tuple[int, ...] = (1, 2, 3)

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name):
            raise ValueError(f"expected name to be a non-empty string, got {shown(self.name)}")
        examples = self.examples
        if not (
            isinstance(examples, tuple)
            and examples
            and len(set(examples)) == len(examples)
            and all(example in EXAMPLES for example in examples)
        ):
            raise ValueError(
                f"expected examples to be distinct names among {', '.join(EXAMPLES)}, got "
                f"{shown(list(examples) if isinstance(examples, tuple) else examples)}"
            )
        check_integer("runs", self.runs, 1, MAX_RUNS)
        check_integer("root_seed", self.root_seed, 0, 2**63 - 1)
        _distinct_integers("planning_steps", self.planning_steps, 0, MAX_PLANNING_STEPS)
        _distinct_integers("scales", self.scales, 1, MAX_SCALE)

    def checks(self) -> tuple[Check, ...]:
        """Every check, example by example in :attr:`examples` order: the Dyna Maze's by n, the
        changing mazes' Dyna-Q then Dyna-Q+, prioritized sweeping's by agent, then scale."""
        found: list[Check] = []
        for example in self.examples:
            if example == "dyna-maze":
                found += [
                    Check(example, "dyna-q", _params(BOOK, {"planning_steps": n}))
                    for n in self.planning_steps
                ]
            elif example == "prioritized-sweeping":
                found += [
                    Check(example, agent, params, scale)
                    for agent, params in SWEEP_AGENTS
                    for scale in self.scales
                ]
            else:
                found += [Check(example, agent, params) for agent, params in CHANGING_AGENTS]
        return tuple(found)

    def check(self, label: str) -> Check:
        """The check labelled ``label`` (KeyError if none)."""
        return {check.label: check for check in self.checks()}[label]

    @property
    def agents(self) -> tuple[AgentSpec, ...]:
        """One per check: name the algorithm, label :attr:`Check.label`, params its settings."""
        return tuple(AgentSpec(check.agent, check.label, check.params) for check in self.checks())

    @property
    def maps(self) -> tuple[MapSpec, ...]:
        """The placeholder :data:`MAP`."""
        return (MAP,)

    @property
    def presets(self) -> tuple[str, ...]:
        """The placeholder :data:`PRESET`."""
        return (PRESET,)

    @property
    def seeds(self) -> int:
        """The runs of every check (the grid's seed indices 0 .. runs − 1)."""
        return self.runs

    @property
    def n_runs(self) -> int:
        """Checks × runs."""
        return len(self.checks()) * self.runs

    def fingerprint(self) -> str:
        """SHA-256 of the canonical JSON of :func:`checks_to_dict`."""
        text = json.dumps(checks_to_dict(self), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()


LIST_FIELDS = ("examples", "planning_steps", "scales")
"""The fields a config writes as lists."""


def checks_to_dict(checks: TextbookChecks) -> dict[str, Any]:
    """The config as a JSON-ready dict (read back by :func:`checks_from_dict`)."""
    values = dataclasses.asdict(checks)
    for key in LIST_FIELDS:
        values[key] = list(values[key])
    return values


def checks_from_dict(values: dict[str, Any]) -> TextbookChecks:
    """The config of :func:`checks_to_dict` (KeyError, TypeError or ValueError if invalid)."""
    return TextbookChecks(**_with_tuples(values))


def _with_tuples(values: Mapping[str, Any]) -> dict[str, Any]:
    return {
        key: tuple(value) if key in LIST_FIELDS and isinstance(value, list) else value
        for key, value in values.items()
    }


def checks_from_document(document: Mapping[str, Any], path: Path | str) -> TextbookChecks:
    """The config of a parsed TOML ``document`` (its ``kind`` aside) read from ``path``.

    Raises:
        UserError: ``path: unknown key …`` or ``path: expected …`` in one line.
    """
    keys = ("kind", *(field.name for field in dataclasses.fields(TextbookChecks)))
    check_keys(document, keys, str(path))
    values = {key: value for key, value in document.items() if key != "kind"}
    return build_dataclass(TextbookChecks, _with_tuples(values), str(path))


def checks_toml(checks: TextbookChecks, comment: str = "") -> str:
    """The config as the TOML text of a config file, after the ``comment`` line
    (:func:`checks_from_document` reads it back equal)."""
    lines = [f"# {comment}"] if comment else []
    lines.append(f"kind = {toml_value(KIND)}")
    lines += [f"{key} = {toml_value(value)}" for key, value in checks_to_dict(checks).items()]
    return "\n".join(lines) + "\n"


MAX_RUN_EPISODES = max(
    DYNA_MAZE_EPISODES, MAX_SWEEP_EPISODES, *(steps for steps, _ in CHANGING_MAZES.values())
)
"""Most episodes of one run: a changing-maze run of n steps has at most n."""


def run_file_specs(checks: TextbookChecks) -> dict[str, ArraySpec]:
    """What a run file holds besides its document: the :data:`EPISODE_COLUMNS`, at most
    :data:`MAX_RUN_EPISODES` long (steps int64, reward float64)."""
    episodes = up_to(MAX_RUN_EPISODES)
    return {
        "episode.steps": ArraySpec((episodes,), "<i8"),
        "episode.reward": ArraySpec((episodes,), "<f8"),
    }


LAYOUT = RunLayout(KIND, EPISODE_COLUMNS, checks_to_dict, checks_from_dict, run_file_specs)
"""The results directory of the checks (:class:`~skidnav.experiments.store.RunLayout`)."""
