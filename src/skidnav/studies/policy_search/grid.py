"""The config of a CMA-ES policy-search study: slip presets × seeds, one search per run.

A config is a TOML file (``configs/policy-search.toml``)::

    kind = "policy-search"
    name = "policy-search"     # the results directory's default name (runs/NAME)
    presets = ["thesis"]       # slip presets: one search per preset and seed
    seeds = 1                  # searches per preset
    root_seed = 0              # every search's seed stream derives from it

    [search]                   # SearchConfig (docs/agents/cmaes.md) but slip and seed
    map_kind = "obstacles"
    world_seed = 0
    generations = 50
    ...

:class:`PolicySearchGrid` is that config, validated on construction, and the runner's grid
(:class:`~skidnav.experiments.runs.Grid`): one agent (``cmaes``), one map (``map_kind`` drawn
from ``world_seed``, the same world for every run), the presets, the seeds. Run (preset p, seed
s) is the search of :func:`run_search_config`: the ``[search]`` settings on slip preset p, its
root seed drawn from the run's own stream (:func:`skidnav.seeding.seed_int` of the runner's
run stream of ``root_seed``, :mod:`skidnav.experiments.runs`), so each run has its own seeds,
the same on every backend and after a resume.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from skidnav.agents.policies.search.config import MAX_SEED, SearchConfig
from skidnav.agents.policies.search.curve import COUNTS, GenerationRecord
from skidnav.checks import check_integer
from skidnav.errors import ConfigError, shown, within
from skidnav.experiments.config import AgentSpec, MapSpec
from skidnav.experiments.store import RunLayout
from skidnav.files.configtables import check_keys, table, toml_value
from skidnav.files.saved import ArraySpec
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.seeding import SeedKey, seed_int

KIND = "policy-search"
"""The ``kind`` of a policy-search config."""
AGENT = "cmaes"
"""The agent label of every run."""
RUN_FIELDS = ("slip", "seed")
"""The :class:`SearchConfig` fields each run sets: its preset and its root seed."""
SEARCH_KEYS = tuple(f.name for f in dataclasses.fields(SearchConfig) if f.name not in RUN_FIELDS)
"""The keys of ``[search]``."""
CONFIG_KEYS = ("kind", "name", "presets", "seeds", "root_seed", "search")
"""The top-level keys of a config."""
MAX_SEEDS = 1000
EPISODE_COLUMNS = GenerationRecord._fields
"""The learning curve, one row per generation 0 .. G (the results' episode table)."""
_FLOAT_FIELDS = tuple(
    f.name for f in dataclasses.fields(SearchConfig) if isinstance(f.default, float)
)


@dataclass(frozen=True)
class PolicySearchGrid:
    """A policy-search study (module doc); validated on construction.

    Attributes:
        search: the settings of every search; its ``slip`` (the first preset) and ``seed`` (0)
            are replaced per run (:func:`run_search_config`).
        presets: distinct slip presets (:data:`skidnav.robot.slip.SLIP_PRESETS`).
        seeds: searches per preset, in [1, :data:`MAX_SEEDS`].
        root_seed: the root of every run's stream, an integer in [0, 2⁶³ − 1].
        name: the results directory's default name.
    """

    search: SearchConfig = field(default_factory=SearchConfig)
    presets: tuple[str, ...] = ("thesis",)
    seeds: int = 1
    root_seed: int = 0
    name: str = KIND

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name):
            raise ValueError(f"expected name to be a non-empty string, got {shown(self.name)}")
        presets = self.presets
        known = isinstance(presets, tuple) and all(p in SLIP_PRESETS for p in presets)
        if not (known and presets and len(set(presets)) == len(presets)):
            raise ValueError(
                f"expected presets to be distinct slip presets among {', '.join(SLIP_PRESETS)}, "
                f"got {shown(list(presets) if isinstance(presets, tuple) else presets)}"
            )
        check_integer("seeds", self.seeds, 1, MAX_SEEDS)
        check_integer("root_seed", self.root_seed, 0, MAX_SEED)
        floats: dict[str, Any] = {n: float(getattr(self.search, n)) for n in _FLOAT_FIELDS}
        canonical = dataclasses.replace(self.search, slip=presets[0], seed=0, **floats)
        object.__setattr__(self, "search", canonical)  # 1 and 1.0 are one config

    @property
    def agents(self) -> tuple[AgentSpec, ...]:
        """The one agent, :data:`AGENT`."""
        return (AgentSpec(AGENT, AGENT),)

    @property
    def maps(self) -> tuple[MapSpec, ...]:
        """The one map kind (drawn from ``search.world_seed``)."""
        return (MapSpec(self.search.map_kind, kind=self.search.map_kind),)

    @property
    def n_runs(self) -> int:
        """Presets × seeds."""
        return len(self.presets) * self.seeds

    def fingerprint(self) -> str:
        """SHA-256 of the canonical JSON of :func:`grid_to_dict`."""
        text = json.dumps(grid_to_dict(self), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()


def run_search_config(grid: PolicySearchGrid, preset: str, run_seed: SeedKey) -> SearchConfig:
    """The search of the run on ``preset`` with the run stream ``run_seed``: ``grid.search``
    on that slip preset, its root seed :func:`~skidnav.seeding.seed_int` of the stream."""
    return dataclasses.replace(grid.search, slip=preset, seed=seed_int(run_seed.sequence()))


def grid_to_dict(grid: PolicySearchGrid) -> dict[str, Any]:
    """The grid as a JSON-ready dict (read back by :func:`grid_from_dict`)."""
    search = {key: value for key, value in grid.search.to_dict().items() if key in SEARCH_KEYS}
    return {
        "name": grid.name,
        "presets": list(grid.presets),
        "seeds": grid.seeds,
        "root_seed": grid.root_seed,
        "search": search,
    }


def grid_from_dict(values: dict[str, Any]) -> PolicySearchGrid:
    """The grid of :func:`grid_to_dict` (KeyError, TypeError or ValueError if invalid)."""
    presets = tuple(values["presets"])
    search = SearchConfig.from_mapping({**values["search"], "slip": presets[0], "seed": 0})
    return PolicySearchGrid(search, presets, values["seeds"], values["root_seed"], values["name"])


def grid_from_document(document: Mapping[str, Any], path: Path | str) -> PolicySearchGrid:
    """The grid of a parsed TOML ``document`` read from ``path``.

    Raises:
        UserError: ``path: …`` in one line: an unknown key (``slip`` or ``seed`` in
            ``[search]`` named as set per run), a value out of its bounds.
    """
    check_keys(document, CONFIG_KEYS, str(path))
    where = f"{path}: [search]"
    settings = dict(table(document.get("search", {}), where))
    for key in RUN_FIELDS:
        if key in settings:
            problem = f"key {key!r} is set per run"
            raise ConfigError(problem, (where,), "list presets, give root_seed")
    check_keys(settings, SEARCH_KEYS, where)
    presets = document.get("presets", PolicySearchGrid.presets)
    if isinstance(presets, list):
        presets = tuple(presets)
    try:
        search = SearchConfig(**settings)  # its slip and seed: set per run
    except (TypeError, ValueError) as error:
        raise within(error, where) from None
    top = {key: document[key] for key in ("name", "seeds", "root_seed") if key in document}
    try:
        return PolicySearchGrid(search, presets, **top)
    except (TypeError, ValueError) as error:
        raise within(error, str(path)) from None


def grid_toml(grid: PolicySearchGrid) -> str:
    """The grid as the TOML text of a config file (:func:`grid_from_document` reads it back
    equal)."""
    values = grid_to_dict(grid)
    lines = [f"kind = {toml_value(KIND)}"]
    lines += [f"{key} = {toml_value(values[key])}" for key in ("name", "presets", "seeds")]
    lines += [f"root_seed = {toml_value(grid.root_seed)}", "", "[search]"]
    lines += [f"{key} = {toml_value(value)}" for key, value in values["search"].items()]
    return "\n".join(lines) + "\n"


def run_file_specs(grid: PolicySearchGrid) -> dict[str, ArraySpec]:
    """What a run file holds besides its document: the learning curve (one row per generation
    0 .. G, :data:`EPISODE_COLUMNS`) and the final mean policy's ``parameters`` (n,) with the
    observation bounds ``observation_low`` and ``observation_high`` (7 + k,), float64."""
    rows = grid.search.generations + 1
    specs = {
        f"episode.{key}": ArraySpec((rows,), "<i8" if key in COUNTS else "<f8")
        for key in EPISODE_COLUMNS
    }
    specs["array.parameters"] = ArraySpec((grid.search.n_parameters,), "<f8")
    for key in ("observation_low", "observation_high"):
        specs[f"array.{key}"] = ArraySpec((7 + grid.search.lidar_rays,), "<f8")
    return specs


LAYOUT = RunLayout(KIND, EPISODE_COLUMNS, grid_to_dict, grid_from_dict, run_file_specs)
"""The results directory of a policy-search study."""
