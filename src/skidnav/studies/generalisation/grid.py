"""The generalisation study's config and grid (docs/generalisation.md, "Config")::

    kind = "generalisation"

    [generalisation]
    seeds = 5                # runs per agent (run seeds 0 … 4)
    training_maps = 8
    held_out_maps = 4
    episodes = 1000          # training episodes per run
    max_steps = 300          # actions per episode, training and evaluation
    map_kind = "obstacles"   # free | obstacles | maze
    slip = "thesis"          # slip preset (skidnav.robot.slip.SLIP_PRESETS)
    observation = "features" # features | pose (agents on Box observations)
    rollouts = 5             # evaluation rollouts per map
    eval_epsilon = 0.05      # ε of the second, ε-greedy evaluation
    root_seed = 0            # the worlds and every run's streams (GENERALISATION_ROLES)

    [[agents]]
    name = "linear-q"
    params = { dimensions = [4, 5, 6, 7, 8, 14], tiles = [5] }

Every key of ``[generalisation]`` is optional (the values above are the defaults, ``name`` the
config file's name). The runs are agents × seeds, agent-major; run ``seed`` of every agent has the
streams of :func:`~skidnav.studies.generalisation.evaluation.run_streams` (``root_seed``, ``seed``),
as :mod:`~skidnav.studies.generalisation.evaluation` defines them, not the runner's: the
runner's ``metadata.json`` lists its own streams, which these runs do not use.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from skidnav.errors import shown
from skidnav.experiments.config import MapSpec
from skidnav.experiments.store import RunLayout
from skidnav.files.saved import ArraySpec
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.studies.agent_grid import (
    TRAINING_COLUMNS,
    AgentSeedGrid,
    check_choice,
    check_count,
    training_specs,
)
from skidnav.world.grid import MAP_KINDS

KIND = "generalisation"
"""The config's ``kind`` (and its settings' table)."""
MAX_WORLDS = 1000
"""Most training or held-out worlds."""
MAX_EPISODES = 1_000_000
"""Most training episodes per run."""
OBSERVATIONS = ("features", "pose")
"""The env observations a generalisation study may train on (both ``Box``)."""


@dataclass(frozen=True)
class GeneralisationGrid(AgentSeedGrid):
    """A generalisation study, validated on construction (module doc; the fields are the keys
    of ``[generalisation]``).

    Attributes:
        training_maps, held_out_maps: worlds on each side of the split.
        episodes: training episodes per run. max_steps: actions per episode.
        map_kind, slip, observation: the worlds' env options.
        rollouts: evaluation rollouts per world (the same reset seeds for every run).
        eval_epsilon: ε of the ε-greedy evaluation, in [0, 1].
        root_seed: the split and every run's streams.
    """

    seeds: int = 5
    training_maps: int = 8
    held_out_maps: int = 4
    episodes: int = 1000
    max_steps: int = 300
    map_kind: str = "obstacles"
    slip: str = "thesis"
    observation: str = "features"
    rollouts: int = 5
    eval_epsilon: float = 0.05
    root_seed: int = 0  # a field here; the base's property is fixed at 0

    def __post_init__(self) -> None:
        super().__post_init__()
        check_count("training_maps", self.training_maps, 1, MAX_WORLDS)
        check_count("held_out_maps", self.held_out_maps, 1, MAX_WORLDS)
        check_count("episodes", self.episodes, 1, MAX_EPISODES)
        check_count("max_steps", self.max_steps, 1, 100_000)
        check_count("rollouts", self.rollouts, 1, 100)
        check_count("root_seed", self.root_seed, 0, 2**63 - 1)
        check_choice("map_kind", self.map_kind, MAP_KINDS)
        check_choice("slip", self.slip, SLIP_PRESETS)
        check_choice("observation", self.observation, OBSERVATIONS)
        epsilon = self.eval_epsilon
        number = isinstance(epsilon, int | float) and not isinstance(epsilon, bool)
        if not (number and 0.0 <= epsilon <= 1.0):  # NaN fails too
            raise ValueError(f"expected eval_epsilon in [0, 1], got {shown(epsilon)}")
        object.__setattr__(self, "eval_epsilon", float(epsilon))  # 0 and 0.0: one fingerprint

    @property
    def maps(self) -> tuple[MapSpec, ...]:
        """The map kind every world is generated as (each world its own map)."""
        return (MapSpec(self.map_kind, kind=self.map_kind),)

    @property
    def presets(self) -> tuple[str, ...]:
        """The slip preset of every world."""
        return (self.slip,)

    @property
    def env_options(self) -> dict[str, Any]:
        """The worlds' env options."""
        return {"map_kind": self.map_kind, "slip": self.slip, "observation": self.observation}


def _file_specs(grid: GeneralisationGrid) -> dict[str, ArraySpec]:
    return training_specs(grid.episodes)


LAYOUT = RunLayout(
    KIND, TRAINING_COLUMNS, GeneralisationGrid.to_dict, GeneralisationGrid.from_dict, _file_specs
)
"""A generalisation study's results directory: one run file per (agent, seed) with its training
episodes (:data:`~skidnav.studies.agent_grid.TRAINING_COLUMNS`) and its
:class:`~skidnav.studies.generalisation.evaluation.GeneralisationResult` as its summary."""
