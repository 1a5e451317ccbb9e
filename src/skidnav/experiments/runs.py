"""The expanded grid of runs and their random streams.

Seeding (:mod:`skidnav.seeding`, architecture.md "Randomness"): the root ``SeedSequence(root_seed)``
has the children of :data:`~skidnav.seeding.ROOT_ROLES`, among them a *world* root and a *run* root.

* ``run root.spawn(n_runs)[index]`` is the stream of the run at position ``index`` of the grid
  (agent-major, then map, preset, seed): it drives the agent and the episodes.
* ``world root.spawn(n_worlds)[w]`` with ``w`` the position of (map, preset, seed) drives the map
  generation and the slip field. Every agent therefore meets the *same* map and floor for a given
  seed (common random numbers), which makes the agent comparisons paired.

Both depend only on positions in the grid, so a run has the same streams on every backend, in
any order, and after a resume.

A grid is anything with the attributes of :class:`Grid`: an
:class:`~skidnav.experiments.config.ExperimentConfig` (``skidnav run``), or a study's grid (e.g.
the hardware-in-the-loop study's :class:`skidnav.studies.hardware.grid.StudyGrid`,
:mod:`skidnav.studies.kind`), whose runs the same runner executes with a trial function of its
own.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Generic, Protocol, TypeVar

from skidnav.errors import UserError
from skidnav.experiments.config import AgentSpec, MapSpec
from skidnav.seeding import ROOT_ROLES, SeedKey, child_sequences


class Grid(Protocol):
    """What :func:`expand_runs` and the runner need of an experiment: agents × maps × presets ×
    seeds from one root seed, and a fingerprint naming all of it (a results directory holds the
    runs of one fingerprint)."""

    @property
    def name(self) -> str: ...
    @property
    def agents(self) -> tuple[AgentSpec, ...]: ...
    @property
    def maps(self) -> tuple[MapSpec, ...]: ...
    @property
    def presets(self) -> tuple[str, ...]: ...
    @property
    def seeds(self) -> int: ...
    @property
    def root_seed(self) -> int: ...
    @property
    def n_runs(self) -> int: ...
    def fingerprint(self) -> str: ...


GridT = TypeVar("GridT", bound=Grid)


@dataclass(frozen=True)
class RunSpec(Generic[GridT]):
    """Everything one run needs; picklable, so it can travel to a process or Dask worker.

    Attributes:
        index: position in the expanded grid (agent-major, then map, preset, seed).
        agent, map, preset, seed: the grid coordinates (``seed`` is the seed index 0..seeds−1).
        world_seed: stream of the map and slip field (shared by all agents).
        run_seed: stream of the agent and the episodes.
        config: the whole grid (for an experiment: episodes, max steps, drift, env options …).
    """

    index: int
    agent: AgentSpec
    map: MapSpec
    preset: str
    seed: int
    world_seed: SeedKey
    run_seed: SeedKey
    config: GridT

    @property
    def run_id(self) -> str:
        """Stable file-name-safe id, e.g. ``run-000042``."""
        return f"run-{self.index:06d}"

    @property
    def coordinates(self) -> dict[str, Any]:
        """The run's place in the grid, as the results tables name it: agent (label),
        algorithm (agent name), map (label), preset, seed (index)."""
        return {
            "agent": self.agent.label,
            "algorithm": self.agent.name,
            "map": self.map.label,
            "preset": self.preset,
            "seed": self.seed,
        }


def world_index(config: Grid, map_index: int, preset_index: int, seed: int) -> int:
    """Position of a (map, preset, seed) world among all worlds of the config."""
    return (map_index * len(config.presets) + preset_index) * config.seeds + seed


def expand_runs(config: GridT) -> list[RunSpec[GridT]]:
    """Every run of the grid, in index order.

    >>> from skidnav.experiments.config import AgentSpec, MapSpec, ExperimentConfig
    >>> cfg = ExperimentConfig("x", (AgentSpec("q-learning", "Q"),), (MapSpec("free", "free"),),
    ...                        seeds=3, root_seed=7)
    >>> [(r.run_id, r.seed) for r in expand_runs(cfg)]
    [('run-000000', 0), ('run-000001', 1), ('run-000002', 2)]
    """
    roots = child_sequences(config.root_seed, ROOT_ROLES)
    world_root, run_root = roots["world"], roots["run"]
    n_worlds = len(config.maps) * len(config.presets) * config.seeds
    worlds = world_root.spawn(n_worlds)
    run_seeds = run_root.spawn(config.n_runs)
    runs: list[RunSpec[GridT]] = []
    index = 0
    for agent in config.agents:
        for map_index, map_spec in enumerate(config.maps):
            for preset_index, preset in enumerate(config.presets):
                for seed in range(config.seeds):
                    world = worlds[world_index(config, map_index, preset_index, seed)]
                    runs.append(
                        RunSpec(
                            index,
                            agent,
                            map_spec,
                            preset,
                            seed,
                            SeedKey.of(world),
                            SeedKey.of(run_seeds[index]),
                            config,
                        )
                    )
                    index += 1
    return runs


def select_runs(runs: Sequence[RunSpec[GridT]], selection: str) -> list[RunSpec[GridT]]:
    """The runs of ``runs`` (a whole grid, in index order) that ``selection`` names: indices ``N``
    and half-open ranges ``A:B`` (``A`` to ``B`` − 1, either end may be left out), separated by
    commas, e.g. ``"0:60,120:180"`` or ``"7"``. A run keeps its index, and with it its streams,
    so a grid run in parts into one directory (one arm first, the rest later) gives the runs of
    a whole run.

    >>> from skidnav.experiments.config import AgentSpec, MapSpec, ExperimentConfig
    >>> cfg = ExperimentConfig("x", (AgentSpec("q-learning", "Q"),), (MapSpec("free", "free"),),
    ...                        seeds=6, root_seed=7)
    >>> [r.index for r in select_runs(expand_runs(cfg), "4:,1")]
    [1, 4, 5]

    Raises:
        UserError: a part that is not an index or a non-empty range of the grid's indices.
    """
    chosen: set[int] = set()
    for part in selection.split(","):
        chosen.update(_selected_indices(part.strip(), len(runs), selection))
    return [spec for spec in runs if spec.index in chosen]


def _selected_indices(part: str, n_runs: int, selection: str) -> range:
    """The indices of one part of a selection (``N``, ``A:B``, ``A:``, ``:B``)."""
    ends = part.split(":")
    try:
        if len(ends) == 1:
            first = int(ends[0])
            bounds = (first, first + 1)
        elif len(ends) == 2:
            bounds = (int(ends[0]) if ends[0] else 0, int(ends[1]) if ends[1] else n_runs)
        else:
            raise ValueError(part)
    except ValueError:
        raise UserError(
            f"--runs {selection!r}: {part!r} is not a run index N or a range A:B"
        ) from None
    start, stop = bounds
    if start < 0 or stop > n_runs or start >= stop:
        raise UserError(
            f"--runs {selection!r}: {part!r} is not a non-empty range of the grid's run "
            f"indices 0 to {n_runs - 1}"
        )
    return range(start, stop)
