"""Studies whose runs are agents × seeds: their config, their grid and their results read back.

The generalisation study (:mod:`skidnav.studies.generalisation`) and the sim-to-sim transfer
study (:mod:`skidnav.studies.transfer`) run every agent once per seed, each run on a world and
settings the study's own table gives. Their config has three parts::

    kind = "transfer"        # the study (skidnav.studies.kind)

    [transfer]               # the study's settings: the fields of its grid (name optional,
    seeds = 10               # default: the config file's name)
    episodes = 300

    [[agents]]               # one table per agent: name, label (default: the name),
    name = "dyna-full"       # params = { ... } (its hyperparameters)
    params = { planning_steps = 100 }

:func:`read_grid` reads it (one :class:`~skidnav.errors.UserError` line naming the file and the
key otherwise), :class:`AgentSeedGrid` is the grid the runner expands (agent-major, then seed:
``run-000000`` is the first agent's seed 0), :func:`study_results` reads a results directory
back, and :func:`interval_cell` writes an estimate with its bootstrap interval as the studies'
tables show it.
"""

from __future__ import annotations

import csv
import dataclasses
import hashlib
import io
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import pandas as pd

from skidnav.agents.training import TrainingLog
from skidnav.errors import ConfigError, UserError, shown, within
from skidnav.experiments.config import AgentSpec, MapSpec, freeze_params
from skidnav.experiments.store import ResultStore, RunLayout
from skidnav.files.configtables import check_keys, table, table_array
from skidnav.files.saved import ArraySpec, up_to
from skidnav.statistics.intervals import Interval

MAX_SEEDS = 1000
"""Most seeds (runs per agent) of a study."""
AGENT_KEYS = ("name", "label", "params")
"""Keys of an ``[[agents]]`` table."""
TRAINING_COLUMNS = ("return", "length", "success", "collisions", "planning_updates", "wall_time")
"""The per-episode arrays of a run's training (:class:`~skidnav.agents.training.TrainingLog`):
undiscounted return, actions, goal reached, collisions, planning updates, wall time [s]."""

GridT = TypeVar("GridT", bound="AgentSeedGrid")


def check_count(name: str, value: object, low: int, high: int) -> None:
    """ValueError unless ``value`` is an integer in [``low``, ``high``]."""
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise ValueError(
            f"expected {name} to be an integer in [{low}, {high:,}], got {shown(value)}"
        )


def check_choice(name: str, value: object, choices: Sequence[str]) -> None:
    """ValueError unless ``value`` is one of ``choices``."""
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"expected {name} one of {', '.join(choices)}, got {shown(value)}")


@dataclass(frozen=True)
class AgentSeedGrid:
    """The grid of a study whose runs are agents × seeds (a
    :class:`~skidnav.experiments.runs.Grid`); a study's grid adds its settings as fields.

    Attributes:
        name: the study's name (the default results directory is ``runs/<name>``).
        agents: the agents, distinct labels; each runs once per seed.
        seeds: runs per agent, seeds 0 … ``seeds`` − 1.
    """

    name: str = ""
    agents: tuple[AgentSpec, ...] = ()
    seeds: int = 1

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"expected a non-empty name, got {shown(self.name)}")
        labels = [agent.label for agent in self.agents]
        if not labels or len(set(labels)) != len(labels):
            raise ValueError(f"expected one or more agents of distinct labels, got {labels}")
        check_count("seeds", self.seeds, 1, MAX_SEEDS)

    @property
    def maps(self) -> tuple[MapSpec, ...]:
        """The one map entry of the grid (a study draws its own worlds): a ``free`` placeholder
        unless the study names its map kind."""
        return (MapSpec("worlds", kind="free"),)

    @property
    def presets(self) -> tuple[str, ...]:
        """The one slip entry of the grid (a study sets its own floors)."""
        return ("-",)

    @property
    def root_seed(self) -> int:
        """The root of the runner's streams (a study seeds its runs itself)."""
        return 0

    @property
    def n_runs(self) -> int:
        """Runs of the grid: agents × seeds."""
        return len(self.agents) * self.seeds

    def to_dict(self) -> dict[str, Any]:
        """The grid as a JSON-ready dict (inverse of :meth:`from_dict`)."""
        values = {field.name: getattr(self, field.name) for field in dataclasses.fields(self)}
        values["agents"] = [
            {"name": agent.name, "label": agent.label, "params": agent.params_dict()}
            for agent in self.agents
        ]
        return values

    @classmethod
    def from_dict(cls: type[GridT], data: Mapping[str, Any]) -> GridT:
        """The grid saved by :meth:`to_dict` (KeyError, TypeError or ValueError if invalid)."""
        agents = tuple(
            AgentSpec(item["name"], item["label"], freeze_params(item["params"]))
            for item in data["agents"]
        )
        return cls(**{**data, "agents": agents})

    def fingerprint(self) -> str:
        """SHA-256 of the canonical JSON of :meth:`to_dict` (names a results directory)."""
        text = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()


def read_agents(value: Any, where: str = "agents") -> tuple[AgentSpec, ...]:
    """The ``[[agents]]`` tables of a study config (keys :data:`AGENT_KEYS`); UserError or
    ValueError naming the table (``[[agents]] #2 params``)."""
    agents = []
    for number, item in enumerate(table_array(value, where), start=1):
        place = f"[[{where}]] #{number}"
        check_keys(item, AGENT_KEYS, place)
        name, label = item.get("name"), item.get("label", item.get("name"))
        for key, text in (("name", name), ("label", label)):
            if not isinstance(text, str) or not text:
                problem = f"expected {key} to be a non-empty string, got {shown(text)}"
                raise ConfigError(problem, (place,))
        params = table(item.get("params", {}), f"{place} params")
        try:
            agents.append(AgentSpec(str(name), str(label), freeze_params(params)))
        except ValueError as error:
            raise within(error, place) from None
    return tuple(agents)


def read_grid(cls: type[GridT], document: Mapping[str, Any], path: Path, kind: str) -> GridT:
    """The grid ``cls`` of a parsed study config (module doc): its ``[kind]`` table's keys are
    the fields of ``cls`` but ``agents``; ``name`` defaults to the file's name.

    Raises:
        UserError: one line naming ``path``, the table and the key.
    """
    try:
        check_keys(document, ("kind", kind, "agents"), "top level")
        settings = dict(table(document.get(kind, {}), f"[{kind}]"))
        fields = [field.name for field in dataclasses.fields(cls) if field.name != "agents"]
        check_keys(settings, fields, f"[{kind}]")
        agents = read_agents(document.get("agents"))
        settings.setdefault("name", path.stem)
        try:
            return cls(agents=agents, **settings)
        except (ValueError, TypeError) as error:
            raise within(error, f"[{kind}]") from None
    except (UserError, ValueError) as error:
        raise within(error, str(path)) from None


def training_episodes(log: TrainingLog) -> dict[str, np.ndarray]:
    """A run's :data:`TRAINING_COLUMNS` from its training log."""
    arrays = (log.returns, log.lengths, log.successes, log.collisions, log.planning_updates,
              log.wall_time)  # fmt: skip
    return {key: np.asarray(array) for key, array in zip(TRAINING_COLUMNS, arrays, strict=True)}


def training_specs(episodes: int) -> dict[str, ArraySpec]:
    """What a run file holds besides its document: the :data:`TRAINING_COLUMNS`, each at most
    ``episodes`` long."""
    return {
        f"episode.{key}": ArraySpec((up_to(episodes),), kinds="fiub") for key in TRAINING_COLUMNS
    }


def study_results(run_dir: Path, layout: RunLayout) -> tuple[Any, pd.DataFrame]:
    """(the grid, the summaries of its finished runs in run order) of the results directory
    ``run_dir`` of a study of ``layout``; UserError if it is not one, or holds no run."""
    store = ResultStore(run_dir, layout)
    grid = store.config()
    summaries = store.load_tables()[1]
    return grid, summaries.sort_values("run_id", kind="stable").reset_index(drop=True)


def interval_cell(estimate: Interval) -> str:
    """``"0.38 [0.25, 0.50]"``, or ``"n/a"`` when the estimate is undefined (no run reached the
    goal); an undefined interval shows as ``nan``."""
    if np.isnan(estimate.estimate):
        return "n/a"
    return f"{estimate.estimate:.2f} [{estimate.low:.2f}, {estimate.high:.2f}]"


def html_table(records: Sequence[Mapping[str, Any]]) -> str:
    """An HTML table of text cells, one row per record."""
    return pd.DataFrame.from_records(list(records)).to_html(index=False, escape=True, border=0)


def results_csv(results: Sequence[Any]) -> str:
    """Per-run results (instances of one dataclass, e.g.
    :class:`~skidnav.studies.transfer.evaluation.TransferResult`) as CSV, one column per field."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, [field.name for field in dataclasses.fields(results[0])])
    writer.writeheader()
    writer.writerows(dataclasses.asdict(result) for result in results)
    return buffer.getvalue()


def results_table(results: Sequence[Any]) -> str:
    """Per-run results (as :func:`results_csv`) as an HTML table, values to 4 decimals, an
    undefined one (NaN) as ``n/a``."""
    frame = pd.DataFrame([dataclasses.asdict(result) for result in results]).round(4)
    return frame.to_html(index=False, escape=True, border=0, na_rep="n/a")
