"""The sim-to-sim transfer study's config and grid (docs/physics.md, "The sim-to-sim gap")::

    kind = "transfer"

    [transfer]
    seeds = 10               # runs per agent: seeds 0 … 9, each its own world
    episodes = 300           # training episodes on the kinematic simulator
    max_steps = 300          # actions per episode, training and evaluation
    map_kind = "obstacles"   # free | obstacles | maze
    slip = "slippery"        # slip preset (skidnav.robot.slip.SLIP_PRESETS)
    floor = ""               # one material everywhere on the MuJoCo robot ("": the preset's)
    rollouts = 5             # greedy rollouts per dynamics

    [[agents]]
    name = "dyna-full"
    params = { planning_steps = 100 }

Every key of ``[transfer]`` is optional (the values above are the defaults, ``name`` the config
file's name); the agents are the tabular ones (:mod:`skidnav.agents.tabular.registry`). The runs
are agents × seeds, agent-major; run ``seed``'s world, agent, episodes and evaluation come from
``SeedSequence(seed)`` (:func:`~skidnav.studies.transfer.evaluation.transfer_run`), so every agent
meets the same world for a seed; the runner's ``metadata.json`` lists its own streams, which these
runs do not use.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from skidnav.experiments.config import MapSpec
from skidnav.experiments.store import RunLayout
from skidnav.files.saved import ArraySpec
from skidnav.physics.materials import MATERIALS
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.studies.agent_grid import (
    TRAINING_COLUMNS,
    AgentSeedGrid,
    check_choice,
    check_count,
    training_specs,
)
from skidnav.world.grid import MAP_KINDS

KIND = "transfer"
"""The config's ``kind`` (and its settings' table)."""
MAX_EPISODES = 100_000
"""Most training episodes per run."""
FLOORS = ("", *sorted(MATERIALS))
"""``floor`` values: the preset's materials (``""``), or one material everywhere."""


@dataclass(frozen=True)
class TransferGrid(AgentSeedGrid):
    """A transfer study, validated on construction (module doc; the fields are the keys of
    ``[transfer]``).

    Attributes:
        episodes: training episodes per run. max_steps: actions per episode.
        map_kind, slip: each seed's world. floor: one material everywhere on the MuJoCo robot
            (``""``: the slip preset's materials, :mod:`skidnav.physics.materials`).
        rollouts: greedy rollouts per dynamics (the same reset seeds on both).
    """

    seeds: int = 10
    episodes: int = 300
    max_steps: int = 300
    map_kind: str = "obstacles"
    slip: str = "slippery"
    floor: str = ""
    rollouts: int = 5

    def __post_init__(self) -> None:
        super().__post_init__()
        check_count("episodes", self.episodes, 1, MAX_EPISODES)
        check_count("max_steps", self.max_steps, 1, 100_000)
        check_count("rollouts", self.rollouts, 1, 100)
        check_choice("map_kind", self.map_kind, MAP_KINDS)
        check_choice("slip", self.slip, SLIP_PRESETS)
        check_choice("floor", self.floor, FLOORS)

    @property
    def maps(self) -> tuple[MapSpec, ...]:
        """The map kind every seed's world is generated as."""
        return (MapSpec(self.map_kind, kind=self.map_kind),)

    @property
    def presets(self) -> tuple[str, ...]:
        """The slip preset of every world."""
        return (self.slip,)

    @property
    def env_options(self) -> dict[str, Any]:
        """The env options of :func:`~skidnav.studies.transfer.evaluation.transfer_run`."""
        return {"map_kind": self.map_kind, "slip": self.slip, "floor": self.floor or None}


def _file_specs(grid: TransferGrid) -> dict[str, ArraySpec]:
    return training_specs(grid.episodes)


LAYOUT = RunLayout(
    KIND, TRAINING_COLUMNS, TransferGrid.to_dict, TransferGrid.from_dict, _file_specs
)
"""A transfer study's results directory: one run file per (agent, seed) with its training
episodes on the kinematic simulator (:data:`~skidnav.studies.agent_grid.TRAINING_COLUMNS`) and its
:class:`~skidnav.studies.transfer.evaluation.TransferResult` as its summary."""
