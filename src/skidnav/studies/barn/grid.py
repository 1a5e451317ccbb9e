"""The config of a BARN study: agents × BARN worlds × floors × seeds, run by the benchmark's
rules (``kind = "barn"``, :mod:`skidnav.studies.kind`; docs/barn.md, "Running the benchmark").

A config is a TOML file (``configs/barn-zero-shot.toml``)::

    kind = "barn"

    [barn]
    name = "barn-zero-shot"        # the results directory's default name (default: the file's)
    description = "…"              # shown in the report
    root_seed = 2020               # the one root seed, >= 0
    seeds = 1                      # runs per (agent, world, floor), 1 … 1000
    protocol = "zero-shot"         # or "learning"
    episodes = 1                   # learning: training episodes per world, each then scored
    worlds = { start = 0, stop = 300, step = 1 }   # or a list: [0, 60, 120]
    floors = ["nominal"]           # slip presets, e.g. "ice-physics" (BARN on ice)
    dynamics = "kinematic"         # or "mujoco" (the physics extra)
    lidar_rays = 271               # rays of the laser over its 270° field of view
    discrete_action_duration = 0.1 # seconds a discrete agent's action lasts (0.1, 0.2, …)

    [[agents]]                     # one table per agent: name, label, params = { … }
    name = "goal-tracker"

:class:`BarnGrid` is that config, validated on construction, and the runner's grid
(:class:`~skidnav.experiments.runs.Grid`): its maps are the worlds (labels ``world-N``,
:func:`world_label`), its presets the floors. Every agent meets the same world streams of a
(world, floor, seed) (common random numbers), so the agents' scores pair by world.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from skidnav.checks import check_integer, check_names, check_number
from skidnav.errors import shown
from skidnav.experiments.config import MapSpec
from skidnav.experiments.store import RunLayout
from skidnav.files.configtables import check_keys
from skidnav.files.saved import ArraySpec, up_to
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.sim.features import MAX_LIDAR_RAYS
from skidnav.studies.agent_grid import AgentSeedGrid, check_choice
from skidnav.world.barn import N_WORLDS, TIME_LIMIT

KIND = "barn"
"""The ``kind`` of a BARN config (and its ``[barn]`` table)."""
PROTOCOLS = ("zero-shot", "learning")
"""zero-shot: one scored run of a new agent per world; learning: ``episodes`` training episodes
per world, each followed by one scored run."""
DYNAMICS = ("kinematic", "mujoco")
"""The env's dynamics (``mujoco``: the physics extra)."""
MAX_EPISODES = 1000
"""Most training episodes per world."""
QUINTILE_SIZE = N_WORLDS // 5
"""Worlds per difficulty quintile: BARN numbers its worlds from open to cluttered, so world n is
in quintile n // 60 (0 the easiest, 4 the hardest)."""
CONTROL_PERIOD = 0.1
"""Seconds per action [s], the benchmark's 10 Hz."""
MAX_DISCRETE_ACTION_DURATION = 10.0
"""Longest action of a discrete agent [s]: a tenth of the benchmark's time limit."""
MAX_ACTIONS = 2 * round(TIME_LIMIT / CONTROL_PERIOD)
"""Most actions of a scored run [actions]: up to 100 s before the robot leaves its start, and
the 100 s of the run (:mod:`skidnav.studies.barn.rules`)."""
RANGE_KEYS = ("start", "stop", "step")
"""Keys of the range form of ``worlds`` (Python's ``range``: ``stop`` excluded)."""
EPISODE_COLUMNS = (
    "world", "quintile", "success", "collision", "timeout", "time", "metric", "optimal_time",
    "clock_start", "scored_actions", "training_actions", "driving_seconds", "wall_time",
)  # fmt: skip
"""One row per scored run (the results' episode table; ``map`` is ``world-N``, ``preset`` the
floor): the world's number and difficulty quintile; the outcome (success, collision, timeout,
each 0/1); AT, the benchmark's time [s] (:mod:`skidnav.studies.barn.rules`); the BARN metric;
OT [s]; when the benchmark's clock started [s after the reset]; the scored run's actions; the
actions of the training episode before it (0 for zero-shot); the seconds of driving in
training so far [s]; the wall time of that training episode [s]."""


def quintile(world: int) -> int:
    """The difficulty quintile (0 … 4) of BARN world ``world`` (:data:`QUINTILE_SIZE`).

    >>> quintile(0), quintile(59), quintile(60), quintile(299)
    (0, 0, 1, 4)
    """
    return world // QUINTILE_SIZE


def world_label(world: int) -> str:
    """The map label of BARN world ``world`` in the results (``world-N``)."""
    return f"world-{world}"


def world_number(label: str) -> int:
    """The number of the world labelled ``label`` (:func:`world_label`).

    >>> world_number("world-42")
    42
    """
    return int(label.removeprefix("world-"))


def expand_worlds(value: object) -> tuple[int, ...]:
    """The world numbers of a config's ``worlds``: a list of numbers, or a table ``{ start,
    stop, step }`` read as Python's ``range`` (``start`` 0 and ``step`` 1 by default, ``stop``
    excluded); ValueError unless they are distinct numbers in [0, 299].

    >>> expand_worlds({"start": 0, "stop": 300, "step": 100})
    (0, 100, 200)
    >>> expand_worlds([3, 1])
    (3, 1)
    """
    if isinstance(value, Mapping):
        check_keys(value, RANGE_KEYS, "worlds")
        bounds = {"start": 0, "step": 1, **value}
        if "stop" not in value:
            raise ValueError("expected worlds to have a stop, e.g. { start = 0, stop = 300 }")
        for key in RANGE_KEYS:
            check_integer(f"worlds.{key}", bounds[key], 1 if key == "step" else 0, N_WORLDS)
        value = tuple(range(bounds["start"], bounds["stop"], bounds["step"]))
    if not isinstance(value, list | tuple) or not value:
        raise ValueError(f"expected worlds to be a non-empty list or a range, got {shown(value)}")
    for world in value:
        check_integer("each of worlds", world, 0, N_WORLDS - 1)
    if len(set(value)) != len(value):
        raise ValueError(f"expected distinct worlds, got {shown(list(value))}")
    return tuple(value)


@dataclass(frozen=True)
class BarnGrid(AgentSeedGrid):
    """A BARN config (module doc), validated on construction; lists become tuples.

    Attributes:
        description: shown in the report.
        root_seed: the one root seed (>= 0) of every run's streams.
        protocol: one of :data:`PROTOCOLS`.
        episodes: training episodes per world (learning), 1 … :data:`MAX_EPISODES`; 1 for
            zero-shot (its one scored run).
        worlds: distinct BARN world numbers, 0 … 299 (:func:`expand_worlds`).
        floors: distinct slip presets (:data:`skidnav.robot.slip.SLIP_PRESETS`).
        dynamics: one of :data:`DYNAMICS`.
        lidar_rays: rays k of the laser's 270° field of view, 0 … ``MAX_LIDAR_RAYS``.
        discrete_action_duration: how long an action of a discrete agent lasts [s], a whole
            number of the benchmark's :data:`CONTROL_PERIOD` periods, at most
            :data:`MAX_DISCRETE_ACTION_DURATION` (an agent answering wheel speeds acts every
            period); :attr:`action_periods` of them.
    """

    description: str = ""
    root_seed: int = 0  # a field here, a property of the base grid
    protocol: str = "zero-shot"
    episodes: int = 1
    worlds: tuple[int, ...] = tuple(range(N_WORLDS))
    floors: tuple[str, ...] = ("nominal",)
    dynamics: str = "kinematic"
    lidar_rays: int = 271
    discrete_action_duration: float = CONTROL_PERIOD

    def __post_init__(self) -> None:
        super().__post_init__()
        if not isinstance(self.description, str):
            raise ValueError(f"expected description to be a string, got {shown(self.description)}")
        check_integer("root_seed", self.root_seed, 0)
        check_choice("protocol", self.protocol, PROTOCOLS)
        check_integer("episodes", self.episodes, 1, MAX_EPISODES)
        if self.protocol == "zero-shot" and self.episodes != 1:
            raise ValueError(f"expected episodes = 1 with protocol zero-shot, got {self.episodes}")
        object.__setattr__(self, "worlds", expand_worlds(self.worlds))
        floors = tuple(self.floors) if isinstance(self.floors, list) else self.floors
        check_names("floors", floors, tuple(SLIP_PRESETS))
        object.__setattr__(self, "floors", floors)
        check_choice("dynamics", self.dynamics, DYNAMICS)
        check_integer("lidar_rays", self.lidar_rays, 0, MAX_LIDAR_RAYS)
        duration = check_number(
            "discrete_action_duration", self.discrete_action_duration, CONTROL_PERIOD,
            MAX_DISCRETE_ACTION_DURATION, closed=True,
        )  # fmt: skip
        if abs(round(duration / CONTROL_PERIOD) * CONTROL_PERIOD - duration) > 1e-9:
            raise ValueError(
                f"expected discrete_action_duration to be a whole number of the benchmark's "
                f"{CONTROL_PERIOD} s periods, got {shown(self.discrete_action_duration)}"
            )
        object.__setattr__(self, "discrete_action_duration", duration)

    @property
    def action_periods(self) -> int:
        """The benchmark's periods one action of a discrete agent lasts
        (``discrete_action_duration`` / :data:`CONTROL_PERIOD`)."""
        return round(self.discrete_action_duration / CONTROL_PERIOD)

    @property
    def maps(self) -> tuple[MapSpec, ...]:
        """One entry per world, labelled :func:`world_label` (its map comes from the shipped
        archive, :func:`skidnav.world.barn.load_barn_world`)."""
        return tuple(MapSpec(world_label(world), kind="free") for world in self.worlds)

    @property
    def presets(self) -> tuple[str, ...]:
        """The floors."""
        return self.floors

    @property
    def n_runs(self) -> int:
        """Agents × worlds × floors × seeds."""
        return len(self.agents) * len(self.worlds) * len(self.floors) * self.seeds

    def to_dict(self) -> dict[str, Any]:
        """The grid as a JSON-ready dict (inverse of :meth:`from_dict`)."""
        values = super().to_dict()
        values.update(worlds=list(self.worlds), floors=list(self.floors))
        if self.discrete_action_duration == CONTROL_PERIOD:
            # only when set, so a config without it keeps its dict and fingerprint (its results)
            del values["discrete_action_duration"]
        return values


def run_file_specs(grid: BarnGrid) -> dict[str, ArraySpec]:
    """What a run file holds besides its document: the :data:`EPISODE_COLUMNS`, one value per
    scored run; ``poses`` float32 (n, 3) (x [m], y [m], heading [rad]), the scored runs'
    poses one after the other; ``pose_counts`` int64 (episodes,), how many poses each has."""
    episodes = up_to(grid.episodes)
    specs = {f"episode.{key}": ArraySpec((episodes,), kinds="fiub") for key in EPISODE_COLUMNS}
    specs["array.poses"] = ArraySpec((up_to(grid.episodes * (MAX_ACTIONS + 1)), 3), "<f4")
    specs["array.pose_counts"] = ArraySpec((episodes,), "<i8")
    return specs


LAYOUT = RunLayout(KIND, EPISODE_COLUMNS, BarnGrid.to_dict, BarnGrid.from_dict, run_file_specs)
"""The results directory of a BARN study (:class:`~skidnav.experiments.store.RunLayout`)."""
