"""Experiment configs: frozen, validated dataclasses loaded from TOML.

An experiment is the grid agents × maps × slip presets × seeds (docs/experiments.md). The TOML
layout is::

    [experiment]
    name = "quick"
    episodes = 60            # training episodes per run
    max_steps = 300          # action limit per episode (truncation)
    seeds = 5                # seeds per (agent, map, preset)
    root_seed = 2020         # the one root seed of the whole experiment
    presets = ["thesis"]     # slip presets (skidnav.robot.slip.SLIP_PRESETS)
    drift_amplitude = 0.0    # relative slip drift amplitude (0: stationary)

    [env]                    # optional keyword arguments of the environment
    [[maps]]                 # kind = "free" | "obstacles" | "maze", or file = "maps/a.txt"
    [[agents]]               # name, label, params = {...}, sweep = {key = [values]}

Every field is documented on :class:`ExperimentConfig`; docs/experiments.md has the full schema.
Configs are never mutated: :func:`config_to_dict` and :func:`config_from_dict` round-trip them
through JSON, which is how the resolved config is saved next to the results.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from dataclasses import dataclass
from typing import Any

from skidnav.errors import shown
from skidnav.experiments.limits import check_range, check_setting
from skidnav.robot.slip import MAX_DRIFT_AMPLITUDE, MAX_DRIFT_PERIOD, SLIP_PRESETS
from skidnav.world.grid import MAP_KINDS

#: Values a hyperparameter or option may take: TOML scalars, or tuples of them (TOML arrays).
Scalar = bool | int | float | str | tuple[bool | int | float | str, ...]
Params = tuple[tuple[str, Scalar], ...]
_SCALARS = (bool, int, float, str)

DEFAULT_ENV_ID = "skidnav/SkidSteerNav-v0"

MAX_BOOTSTRAP = 1_000_000
"""Most bootstrap resamples per interval."""
MAX_STATE_LEVELS = 1000
"""Most position levels (n_x, n_y) and heading bins of a state grid."""
MAX_GRID_STATES = 5_000_000
"""Most states of a state grid (an agent's ``discretization`` or an optimum grid): its oracle
holds (n_states, 4, samples) int32 outcomes."""
MAX_TOTAL_EPISODES = 1_000_000_000
"""Most episodes of a whole experiment (runs × episodes): beyond it the work is absurd for any
machine this runs on, and the config is refused before a run starts."""


def _check_params(name: str, params: Params) -> None:
    for key, value in params:
        if not isinstance(key, str) or not key:
            raise ValueError(f"expected {name} keys to be non-empty strings, got {shown(key)}")
        items = value if isinstance(value, tuple) else (value,)
        if not all(isinstance(item, _SCALARS) for item in items):
            raise ValueError(
                f"expected {name}.{key} to be a number, string or bool, got {shown(value)}"
            )


Levels = tuple[int, ...]
"""A state grid (n_x, n_y, n_headings), or () for the environment's own."""


def check_levels(name: str, levels: Levels) -> None:
    """ValueError unless ``levels`` is () or three integers (n_x, n_y, n_headings), the sides in
    [3, :data:`MAX_STATE_LEVELS`], the bins in [1, :data:`MAX_STATE_LEVELS`], at most
    :data:`MAX_GRID_STATES` states in all."""
    if levels == ():
        return
    ok = (
        isinstance(levels, tuple)
        and len(levels) == 3
        and all(isinstance(v, int) and not isinstance(v, bool) for v in levels)
        and all(3 <= v <= MAX_STATE_LEVELS for v in levels[:2])
        and 1 <= levels[2] <= MAX_STATE_LEVELS
    )
    if not ok:
        raise ValueError(
            f"expected {name} to be [n_x, n_y, n_headings] (sides 3 … {MAX_STATE_LEVELS}, "
            f"bins 1 … {MAX_STATE_LEVELS}), got {shown(levels)}"
        )
    if math.prod(levels) > MAX_GRID_STATES:
        raise ValueError(
            f"expected {name} of at most {MAX_GRID_STATES:,} states, got {math.prod(levels):,}"
        )


def freeze_params(mapping: dict[str, Any] | Params | None) -> Params:
    """A mapping of scalar options as a sorted tuple of (key, value) pairs (hashable, ordered)."""
    if mapping is None:
        return ()
    items = mapping.items() if isinstance(mapping, dict) else mapping
    return tuple(
        sorted(
            (str(key), tuple(value) if isinstance(value, list) else value) for key, value in items
        )
    )


@dataclass(frozen=True)
class AgentSpec:
    """One agent variant of the grid.

    Attributes:
        name: algorithm name understood by ``skidnav.agents.make_agent``.
        label: unique display name (default: the name, plus swept values).
        params: hyperparameters passed to the agent, as sorted (key, value) pairs.
        discretization: the state grid (n_x, n_y, n_headings) a tabular agent learns over, a
            refinement of the map's cells (:func:`skidnav.world.grid.refine_map`); () for the
            map's own cells and the environment's heading bins (docs/discretization-gap.md).
    """

    name: str
    label: str
    params: Params = ()
    discretization: Levels = ()

    def __post_init__(self) -> None:
        if not self.name:
            raise ValueError(f"expected a non-empty agent name, got {shown(self.name)}")
        if not self.label:
            raise ValueError(f"expected a non-empty agent label, got {shown(self.label)}")
        _check_params(f"agent {shown(self.label)} params", self.params)
        check_levels(f"agent {shown(self.label)} discretization", self.discretization)

    def params_dict(self) -> dict[str, Scalar]:
        """The hyperparameters as a fresh dict."""
        return dict(self.params)


@dataclass(frozen=True)
class MapSpec:
    """One map of the grid: a generated kind or a map file.

    Attributes:
        label: unique display name.
        kind: generated map kind (one of :data:`MAP_KINDS`) or ``""`` for a file.
        file: absolute path of a map file, or ``""`` for a generated kind.
        options: extra keyword arguments of the map generator, as (key, value) pairs.
    """

    label: str
    kind: str = ""
    file: str = ""
    options: Params = ()

    def __post_init__(self) -> None:
        if bool(self.kind) == bool(self.file):
            raise ValueError("expected exactly one of kind or file in a map")
        if self.kind and self.kind not in MAP_KINDS:
            raise ValueError(
                f"expected map kind one of {', '.join(MAP_KINDS)}, got {shown(self.kind)}"
            )
        if self.file and self.options:
            raise ValueError("expected no options for a map file")
        if not self.label:
            raise ValueError("expected a non-empty map label")
        _check_params(f"map {shown(self.label)} options", self.options)


CONVERGENCE_OBJECTIVES = {"actions": "greedy_length", "cost": "greedy_cost"}
"""What convergence is measured in → the per-episode column compared with the oracle."""


@dataclass(frozen=True)
class ExperimentConfig:
    """A whole experiment, validated on construction.

    Attributes:
        name: experiment name (used in the report title).
        agents: agent variants, unique labels.
        maps: maps, unique labels.
        presets: slip presets, unique, from ``skidnav.robot.slip.SLIP_PRESETS``.
        seeds: seeds per (agent, map, preset) cell, ≥ 1 (≥ 30 for headline claims).
        episodes: training episodes per run, ≥ 2.
        max_steps: action limit per episode (truncation), ≥ 1; ``None`` keeps the env default.
        root_seed: the one root seed; every run's streams are spawned from it.
        drift_amplitude: relative slip drift amplitude A ≥ 0 (``SlipField``; 0: stationary).
        drift_period: slip drift period [s] > 0.
        convergence_tolerance: relative band above the oracle's expected length L* within which
            an evaluation passes, in (0, 1) (default 0.10 = 10 %;
            :mod:`skidnav.experiments.metrics`).
        convergence_window: W, the evaluations from the convergence episode on that must
            already hold a share ``convergence_level`` of passes (the least evidence), in
            [1, 10,000] (default 10).
        convergence_level: p, the share of passing evaluations that must hold from the
            convergence episode to every later episode, in (0, 1] (default 0.9).
        convergence_objective: what an evaluation is measured in against the oracle: "actions"
            (mean length against L*, default) or "cost" (mean cost, minus the reward without the
            goal bonus, against C*: the objective of the agents' reward, which differs from the
            actions where the floor's slip variance or collisions weigh).
        eval_rollouts: greedy rollouts per evaluation, R, each from its own fixed evaluation
            seed, in [1, 100] (default 5).
        oracle_samples: sampled poses per state (each tries every action) of the oracle's
            transition model, in [1, 1,000] (default 64;
            :mod:`skidnav.experiments.reference.oracle`).
        baseline: label of the agent every other agent is compared to (default: the first
            agent named ``q-learning``, else the first agent).
        headline: label of the agent the verdict leads with, not the baseline (default: the
            first agent named ``dyna-full``, the thesis's, else the first agent after the
            baseline; :mod:`skidnav.experiments.report.verdict`).
        bootstrap_samples: bootstrap resamples for every interval, ≥ 100.
        confidence: confidence level of every interval, in [0.5, 0.999].
        greedy_eval: evaluate the greedy policy after each episode (needed for the primary
            convergence definition).
        save_agents: keep each run's trained agent, saved by its family's own ``save`` beside
            its run file (``runs/<run_id>/agent.npz`` + ``agent.json``, with ``world.json`` and
            ``map.txt``: the world it was trained for), for ``skidnav robot run --agent-file``
            (docs/robot-learning.md). Default false.
        optimum_grids: state grids (n_x, n_y, n_headings), coarse to fine, at which the continuous
            optimum of every world is computed (:mod:`skidnav.experiments.reference.optimum`; the
            last is the reference, the one before it checks its convergence); () for none.
        optimum_samples: sampled poses per state and action of the optimum's model, in [1, 1000]
            (default 8).
        optimum_rollouts: rollouts of the optimum's policy that measure its path length [m],
            in [1, 10,000] (default 100).
        env_id: Gymnasium id of the environment.
        env_options: extra keyword arguments of the environment, as (key, value) pairs.
        description: free text shown in the report.
    """

    name: str
    agents: tuple[AgentSpec, ...]
    maps: tuple[MapSpec, ...]
    presets: tuple[str, ...] = ("thesis",)
    seeds: int = 30
    episodes: int = 100
    max_steps: int | None = None
    root_seed: int = 0
    drift_amplitude: float = 0.0
    drift_period: float = 600.0
    convergence_tolerance: float = 0.10
    convergence_window: int = 10
    convergence_level: float = 0.9
    convergence_objective: str = "actions"
    eval_rollouts: int = 5
    oracle_samples: int = 64
    baseline: str = ""
    headline: str = ""
    bootstrap_samples: int = 2000
    confidence: float = 0.95
    greedy_eval: bool = True
    save_agents: bool = False
    optimum_grids: tuple[Levels, ...] = ()
    optimum_samples: int = 8
    optimum_rollouts: int = 100
    env_id: str = DEFAULT_ENV_ID
    env_options: Params = ()
    description: str = ""

    def __post_init__(self) -> None:
        if not self.name:
            raise ValueError("expected a non-empty experiment name")
        self._check_members()
        self._check_numbers()
        if not self.baseline:
            names = [agent.label for agent in self.agents if agent.name == "q-learning"]
            object.__setattr__(self, "baseline", (names or [self.agents[0].label])[0])
        if self.baseline not in self.agent_labels:
            raise ValueError(f"expected baseline to be an agent label, got {shown(self.baseline)}")
        if self.headline and self.headline not in set(self.agent_labels) - {self.baseline}:
            raise ValueError(
                f"expected headline to be an agent label other than the baseline, got "
                f"{shown(self.headline)}"
            )
        _check_params("env", self.env_options)
        self._check_true_kinematics()

    def _check_true_kinematics(self) -> None:
        """ValueError if an agent asks for the true kinematic model on the physics robot, which
        has none (``kinematic_model = "true"`` with ``[env] dynamics = "mujoco"``)."""
        if dict(self.env_options).get("dynamics") != "mujoco":
            return
        for agent in self.agents:
            if agent.params_dict().get("kinematic_model") == "true":
                raise ValueError(
                    f"expected agent {shown(agent.label)} kinematic_model 'learned' or 'prior' "
                    "with [env] dynamics 'mujoco' (the physics robot has no true kinematic "
                    "model), got 'true'"
                )

    def _check_members(self) -> None:
        if not self.agents:
            raise ValueError("expected at least one agent")
        if not self.maps:
            raise ValueError("expected at least one map")
        if not self.presets:
            raise ValueError("expected at least one slip preset")
        for preset in self.presets:
            if preset not in SLIP_PRESETS:
                raise ValueError(
                    f"expected presets from {', '.join(SLIP_PRESETS)}, got {shown(preset)}"
                )
        for what, labels in (
            ("agent labels", self.agent_labels),
            ("map labels", [m.label for m in self.maps]),
            ("presets", list(self.presets)),
        ):
            if len(set(labels)) != len(labels):
                raise ValueError(f"expected unique {what}, got {labels}")

    def _check_numbers(self) -> None:
        check_setting("seeds", self.seeds)
        check_setting("episodes", self.episodes, low=2)
        if self.max_steps is not None:
            check_setting("max_steps", self.max_steps)
        check_setting("root_seed", self.root_seed)
        check_range(
            "drift_amplitude", self.drift_amplitude, 0.0, MAX_DRIFT_AMPLITUDE, integer=False
        )
        check_range("drift_period", self.drift_period, 1e-9, MAX_DRIFT_PERIOD, integer=False)
        check_setting("convergence_tolerance", self.convergence_tolerance)
        check_setting("convergence_window", self.convergence_window)
        check_setting("convergence_level", self.convergence_level)
        if self.convergence_objective not in CONVERGENCE_OBJECTIVES:
            raise ValueError(
                f"expected convergence_objective in {sorted(CONVERGENCE_OBJECTIVES)}, "
                f"got {shown(self.convergence_objective)}"
            )
        check_setting("eval_rollouts", self.eval_rollouts)
        check_range("oracle_samples", self.oracle_samples, 1, 1_000, integer=True)
        check_range("bootstrap_samples", self.bootstrap_samples, 100, MAX_BOOTSTRAP, integer=True)
        check_range("confidence", self.confidence, 0.5, 0.999, integer=False)
        for levels in self.optimum_grids:
            check_levels("each of optimum_grids", levels)
        check_range("optimum_samples", self.optimum_samples, 1, 1_000, integer=True)
        check_range("optimum_rollouts", self.optimum_rollouts, 1, 10_000, integer=True)
        for name in ("greedy_eval", "save_agents"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(
                    f"expected {name} to be true or false, got {shown(getattr(self, name))}"
                )
        episodes = self.n_runs * self.episodes
        if episodes > MAX_TOTAL_EPISODES:
            raise ValueError(
                f"expected at most {MAX_TOTAL_EPISODES:,} episodes in all (runs × episodes), "
                f"got {episodes:,}"
            )

    @property
    def agent_labels(self) -> list[str]:
        """Agent labels in config order."""
        return [agent.label for agent in self.agents]

    @property
    def n_runs(self) -> int:
        """Number of runs in the expanded grid."""
        return len(self.agents) * len(self.maps) * len(self.presets) * self.seeds

    def fingerprint(self) -> str:
        """SHA-256 of the canonical JSON of the resolved config (identifies a results dir)."""
        text = json.dumps(config_to_dict(self), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()


def config_to_dict(config: ExperimentConfig) -> dict[str, Any]:
    """The resolved config as a JSON-ready dict (inverse of :func:`config_from_dict`). The
    optimum settings, ``headline``, ``save_agents`` and an agent's discretization appear only
    when set, so a config without them keeps the dict, and the fingerprint, it had before they
    existed (a resume that turns ``save_agents`` on is another config: the runs done lack their
    agents)."""
    data = _base_dict(config)
    optional = {
        "headline": config.headline,
        "optimum_grids": [list(levels) for levels in config.optimum_grids],
        "optimum_samples": config.optimum_samples,
        "optimum_rollouts": config.optimum_rollouts,
        "save_agents": config.save_agents,
    }
    defaults = {field.name: field.default for field in dataclasses.fields(config)}
    data.update({k: v for k, v in optional.items() if getattr(config, k) != defaults[k]})
    for agent, saved in zip(config.agents, data["agents"], strict=True):
        if agent.discretization:
            saved["discretization"] = list(agent.discretization)
    return data


def _base_dict(config: ExperimentConfig) -> dict[str, Any]:
    return {
        "name": config.name,
        "description": config.description,
        "env_id": config.env_id,
        "env_options": dict(config.env_options),
        "episodes": config.episodes,
        "max_steps": config.max_steps,
        "seeds": config.seeds,
        "root_seed": config.root_seed,
        "presets": list(config.presets),
        "drift_amplitude": config.drift_amplitude,
        "drift_period": config.drift_period,
        "convergence_tolerance": config.convergence_tolerance,
        "convergence_window": config.convergence_window,
        "convergence_level": config.convergence_level,
        "convergence_objective": config.convergence_objective,
        "eval_rollouts": config.eval_rollouts,
        "oracle_samples": config.oracle_samples,
        "baseline": config.baseline,
        "bootstrap_samples": config.bootstrap_samples,
        "confidence": config.confidence,
        "greedy_eval": config.greedy_eval,
        "agents": [
            {"name": a.name, "label": a.label, "params": dict(a.params)} for a in config.agents
        ],
        "maps": [
            {"label": m.label, "kind": m.kind, "file": m.file, "options": dict(m.options)}
            for m in config.maps
        ],
    }


def config_from_dict(data: dict[str, Any]) -> ExperimentConfig:
    """Rebuild a config saved by :func:`config_to_dict`."""
    values = dict(data)
    agents = tuple(
        AgentSpec(
            a["name"], a["label"], freeze_params(a["params"]),
            tuple(a.get("discretization", ())),
        )
        for a in values.pop("agents")
    )  # fmt: skip
    maps = tuple(
        MapSpec(m["label"], m["kind"], m["file"], freeze_params(m["options"]))
        for m in values.pop("maps")
    )
    values["presets"] = tuple(values["presets"])
    values["optimum_grids"] = tuple(tuple(levels) for levels in values.get("optimum_grids", ()))
    values["env_options"] = freeze_params(values["env_options"])
    return ExperimentConfig(agents=agents, maps=maps, **values)
