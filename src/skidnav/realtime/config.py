"""Configuration of a real-time run, read from TOML (configs/realtime.toml, docs/realtime.md).

Tables: ``[run]`` (:class:`RunSettings`), ``[sim]`` (:class:`SimSettings`), ``[tcp]``,
``[serial]``, ``[ros2]`` (driver options, :mod:`skidnav.realtime.driver_settings`),
``[agents.NAME]`` (the agent's hyperparameters), ``[policies.NAME]`` (a named continuous
policy's settings, realtime/policies.py) and ``[presets.NAME]`` (tables merged over the others
when the preset is chosen). Every table of ``[run]``, ``[sim]`` and the drivers is checked as
a whole when the config is read (:func:`~skidnav.files.configtables.build_dataclass`: unknown
keys, types, ranges), whichever driver runs, and a ``secret`` key anywhere is refused
(:func:`~skidnav.realtime.driver_settings.refuse_inline_secrets`). The sim server's own options
(:class:`ServerOptions`, from ``skidnav robot sim-server``) are here too.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from skidnav.errors import ConfigError, UserError, shown, within
from skidnav.files.configtables import build_dataclass, check_keys, resolve_path, table
from skidnav.files.saved import parse_toml, read_config_text
from skidnav.physics.materials import MATERIALS
from skidnav.realtime.driver_settings import (
    DRIVER_SETTINGS,
    SerialSettings,
    TcpSettings,
    refuse_inline_secrets,
)
from skidnav.realtime.link.auth import require_secret
from skidnav.realtime.link.protocol import MAX_LINE_BYTES
from skidnav.realtime.link.ros2_config import Ros2Config
from skidnav.realtime.reference_robot.rules import MAX_LEASE_LIMIT
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.world.grid import MAP_KINDS

DRIVER_TABLES = tuple(DRIVER_SETTINGS)
"""The tables of driver options."""
TOP_TABLES = ("run", "sim", *DRIVER_TABLES, "agents", "policies", "study")
"""The tables of a config besides ``[presets]`` (``[study]``:
:mod:`skidnav.studies.hardware.study`)."""
FAULTS = ("silence", "garbage", "oversized", "escape", "hangup", "future")
"""Faults the sim server can inject for tests (realtime/robot_server/server.py)."""


@dataclass(frozen=True)
class RunSettings:
    """How the loop runs, validated on construction.

    Attributes:
        episodes: episodes to run (aborted ones count).
        max_actions: actions per episode before truncation.
        time_scale: robot seconds per wall second; must match the sim server's (1 for a real robot).
        period: control period [s robot time]; one action is ``substeps`` periods.
        substeps: control periods per action.
        reset: ``"auto"`` (drive back to the start) or ``"manual"`` (wait for the operator).
        seed: root seed (map, sim server, agent).
        map: map kind (free, obstacles, maze) or map file.
        pose_timeout_periods: control periods without a new pose before the safety trip.
        pose_timeout_min: floor of that timeout [s wall] (high time scales on a busy machine).
        arena_margin: tolerated excursion outside the arena [m].
        reconnect_timeout: how long to retry the link after a fault [s wall]; 0 ends the run.
        homing_tolerance: homing ends within this distance of the start [m] (under half a cell).
        settle_periods: first periods of each action left out of the kinematic log (the wheels
            are still reaching the new command), and periods waited after the closing stop
            before the end pose is read (at least 1); raise it with the link's latency.
        homing_timeout: longest homing [s robot time].
        keep_checkpoints: episode checkpoints kept on disk (the newest ones).
        command_latency: how long after a command leaves the robot's wheels take it [s robot
            time], ≥ 0: each kinematic log row pairs the motion of a period with the commands
            in effect during it, the one before for this long and the new one for the rest
            (their time-weighted mean). 0 (the default) pairs it with the new one alone; with a
            pilot that changes its command every period (``mppi-kinematic``) and a link of 50 ms,
            that halved the speeds its model learned (docs/robot-learning.md).
    """

    episodes: int = 20
    max_actions: int = 100
    time_scale: float = 1.0
    period: float = 0.1
    substeps: int = 10
    reset: str = "auto"
    seed: int = 0
    map: str = "free"
    pose_timeout_periods: int = 5
    pose_timeout_min: float = 0.1
    arena_margin: float = 0.03
    reconnect_timeout: float = 5.0
    homing_tolerance: float = 0.008
    homing_timeout: float = 120.0
    settle_periods: int = 1
    keep_checkpoints: int = 3
    command_latency: float = 0.0

    def __post_init__(self) -> None:
        for name in ("episodes", "max_actions", "substeps", "pose_timeout_periods"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise ValueError(f"expected {name} to be an integer >= 1, got {shown(value)}")
        for name in ("time_scale", "period", "homing_tolerance", "homing_timeout"):
            if not getattr(self, name) > 0:
                raise ValueError(f"expected {name} > 0, got {shown(getattr(self, name))}")
        for name in ("arena_margin", "reconnect_timeout", "pose_timeout_min", "command_latency"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"expected {name} >= 0, got {shown(getattr(self, name))}")
        settle = self.settle_periods
        if not (isinstance(settle, int) and 0 <= settle < self.substeps):
            raise ValueError(f"expected settle_periods in [0, substeps), got {shown(settle)}")
        if self.reset not in ("auto", "manual"):
            raise ValueError(f"expected reset 'auto' or 'manual', got {shown(self.reset)}")
        if not (isinstance(self.keep_checkpoints, int) and self.keep_checkpoints >= 1):
            raise ValueError(f"expected keep_checkpoints >= 1, got {shown(self.keep_checkpoints)}")

    @property
    def period_wall(self) -> float:
        """Control period in wall seconds."""
        return self.period / self.time_scale

    @property
    def pose_timeout(self) -> float:
        """Longest wait for a new pose before the safety trip [s wall]."""
        return max(self.pose_timeout_periods * self.period_wall, self.pose_timeout_min)


@dataclass(frozen=True)
class SimSettings:
    """The simulated robot server the ``sim`` driver starts (options of ``robot sim-server``).

    Attributes:
        slip: slip preset. drift: relative drift amplitude. drift_period: [s].
        latency: command latency [s]. pose_noise: σ of x, y [m]. drop: pose drop probability.
        link_timeout: the server stops the wheels after this quiet time [s wall].
        idle_timeout: the server drops a client after this quiet time [s wall].
        physics: what moves the robot, ``"kinematic"`` (the ICR model) or ``"mujoco"``.
        floor: mujoco only: one floor material everywhere (``""``: the slip preset's).
        lockstep: the server runs one control period per command and the loop waits for each
            (no wall clock: as fast as the physics goes; docs/realtime.md, "Lockstep").
    """

    slip: str = "rough"
    drift: float = 0.0
    drift_period: float = 600.0
    latency: float = 0.0
    pose_noise: float = 0.0
    drop: float = 0.0
    link_timeout: float = 0.5
    idle_timeout: float = 2.0
    physics: str = "kinematic"
    floor: str = ""
    lockstep: bool = False

    def __post_init__(self) -> None:
        if self.physics not in ("kinematic", "mujoco"):
            raise ValueError(f"expected physics 'kinematic' or 'mujoco', got {shown(self.physics)}")
        if self.floor and (self.physics != "mujoco" or self.floor not in MATERIALS):
            raise ValueError(
                f"expected floor one of {', '.join(MATERIALS)} with physics 'mujoco', "
                f"got {shown(self.floor)}"
            )
        if not isinstance(self.lockstep, bool):
            raise ValueError(f"expected lockstep true or false, got {shown(self.lockstep)}")
        if self.slip not in SLIP_PRESETS:
            raise ValueError(
                f"expected slip one of {', '.join(SLIP_PRESETS)}, got {shown(self.slip)}"
            )
        for name in ("drift", "latency", "pose_noise", "drop"):
            if not 0 <= getattr(self, name) < math.inf:
                raise ValueError(f"expected a finite {name} >= 0, got {shown(getattr(self, name))}")
        if not (0 < self.drift_period < math.inf and self.link_timeout > 0 and self.drop < 1):
            raise ValueError("expected a finite drift_period > 0, link_timeout > 0 and drop < 1")
        if not self.idle_timeout >= self.link_timeout:
            raise ValueError(
                f"expected idle_timeout >= link_timeout, got {shown(self.idle_timeout)}"
            )

    def server_arguments(self) -> list[str]:
        """The matching ``skidnav robot sim-server`` options."""
        return [
            "--slip",
            self.slip,
            "--drift",
            str(self.drift),
            "--drift-period",
            str(self.drift_period),
            "--latency",
            str(self.latency),
            "--pose-noise",
            str(self.pose_noise),
            "--drop",
            str(self.drop),
            "--link-timeout",
            str(self.link_timeout),
            "--idle-timeout",
            str(self.idle_timeout),
            "--physics",
            self.physics,
            *(["--floor", self.floor] if self.floor else []),
            *(["--lockstep"] if self.lockstep else []),
        ]


@dataclass(frozen=True)
class ServerOptions:
    """Timing and behaviour of the server, validated on construction.

    Attributes:
        time_scale: robot seconds per wall second (> 0); 10 runs ten times faster than real time.
        link_timeout: wall seconds without a valid message from the client before the wheels
            stop.
        idle_timeout: wall seconds without a valid message before the client is dropped
            (≥ ``link_timeout``).
        send_limit: bytes queued for a client that does not read before it is dropped.
        faults: the faults successive SIGUSR1s inject, in order (each one of :data:`FAULTS`).
        name: robot name sent in ``hello``.
        max_lease: longest a command holds the wheels after it arrived [s wall], whatever its
            ``ttl``: in (0, :data:`MAX_LEASE_LIMIT`]; the default is five periods of a 0.1 s
            robot in real time, the host's own ``ttl`` at time scale 1.
        secret: the link secret (docs/protocol.md, "Authentication"); None: no
            authentication, which only a loopback server may do.
    """

    time_scale: float = 1.0
    link_timeout: float = 0.5
    idle_timeout: float = 2.0
    send_limit: int = 64 * 1024
    faults: tuple[str, ...] = ()
    name: str = "skidnav-sim"
    max_lease: float = 0.5
    secret: bytes | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if not 0 < self.time_scale < math.inf:
            raise ValueError(f"expected a finite time_scale > 0, got {self.time_scale}")
        if not 0 < self.link_timeout < math.inf:
            raise ValueError(f"expected a finite link_timeout > 0 s, got {self.link_timeout}")
        if not self.link_timeout <= self.idle_timeout < math.inf:
            raise ValueError(
                f"expected a finite idle_timeout >= link_timeout ({self.link_timeout} s), "
                f"got {self.idle_timeout}"
            )
        if not 0 < self.max_lease <= MAX_LEASE_LIMIT:
            raise ValueError(
                f"expected max_lease in (0, {MAX_LEASE_LIMIT}] s, got {shown(self.max_lease)}"
            )
        if self.secret is not None:
            require_secret(self.secret)
        if not self.send_limit >= MAX_LINE_BYTES:
            raise ValueError(f"expected send_limit >= {MAX_LINE_BYTES}, got {self.send_limit}")
        for fault in self.faults:
            if fault not in FAULTS:
                raise ValueError(f"expected faults among {', '.join(FAULTS)}, got {fault!r}")


@dataclass(frozen=True)
class RealtimeConfig:
    """Everything a real-time run needs besides the command line: its ``[run]``, ``[sim]``,
    driver (``[tcp]``, ``[serial]``, ``[ros2]``), ``[agents.NAME]`` and ``[policies.NAME]``
    tables."""

    run: RunSettings = field(default_factory=RunSettings)
    sim: SimSettings = field(default_factory=SimSettings)
    tcp: TcpSettings = field(default_factory=TcpSettings)
    serial: SerialSettings = field(default_factory=SerialSettings)
    ros2: Ros2Config = field(default_factory=Ros2Config)
    agents: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    policies: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)


def _merge(base: dict[str, Any], override: Mapping[str, Any]) -> dict[str, Any]:
    """Recursive merge of TOML tables (override wins)."""
    merged = dict(base)
    for key, value in override.items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), Mapping):
            merged[key] = _merge(dict(merged[key]), value)
        else:
            merged[key] = value
    return merged


def config_from_mapping(data: Mapping[str, Any], preset: str | None = None) -> RealtimeConfig:
    """A config from parsed TOML, with ``[presets.NAME]`` merged over it if ``preset`` is given;
    UserError ``"[TABLE]: …"`` (``"preset 'NAME': [TABLE]: …"`` for the tables merged) for an
    unknown key, a value of the wrong type or out of range, or a ``secret`` key anywhere
    (presets included)."""
    refuse_inline_secrets(data)
    tables = {key: value for key, value in data.items() if key != "presets"}
    if preset is None:
        return _build(tables)
    presets = table(data.get("presets", {}), "[presets]")
    if preset not in presets:
        names = ", ".join(shown(name) for name in presets)
        known = f"expected one of {names}" if names else "no [presets] table"
        raise ConfigError(f"unknown preset {shown(preset)}", (), known)
    try:
        return _build(_merge(tables, table(presets[preset], f"[presets.{preset}]")))
    except UserError as error:
        raise within(error, f"preset {preset!r}") from None


def _build(tables: dict[str, Any]) -> RealtimeConfig:
    """The config of the tables of a file (or of its tables and a preset's, merged)."""
    check_keys(tables, TOP_TABLES, "top level")
    agents = table(tables.get("agents", {}), "[agents]")
    policies = table(tables.get("policies", {}), "[policies]")
    return RealtimeConfig(
        run=build_dataclass(RunSettings, tables.get("run", {}), "[run]"),
        sim=build_dataclass(SimSettings, tables.get("sim", {}), "[sim]"),
        tcp=build_dataclass(TcpSettings, tables.get("tcp", {}), "[tcp]"),
        serial=build_dataclass(SerialSettings, tables.get("serial", {}), "[serial]"),
        ros2=build_dataclass(Ros2Config, _with_tuples(tables.get("ros2", {})), "[ros2]"),
        agents={name: dict(table(value, f"[agents.{name}]")) for name, value in agents.items()},
        policies={
            name: dict(table(value, f"[policies.{name}]")) for name, value in policies.items()
        },
    )


def _with_tuples(value: Any) -> Any:
    """A table with its arrays as tuples (a dataclass's tuple fields); anything else as is."""
    if not isinstance(value, dict):
        return value
    return {key: tuple(item) if isinstance(item, list) else item for key, item in value.items()}


def read_tables(path: Path) -> dict[str, Any]:
    """The TOML tables of a config file (read by :func:`~skidnav.files.saved.read_config_text`:
    at most :data:`~skidnav.files.saved.MAX_CONFIG_BYTES`, a device or a pipe ends at that limit;
    nested at most :data:`~skidnav.files.saved.MAX_JSON_DEPTH` levels), with every map file path
    made absolute (:func:`resolve_map_paths`); UserError (one line naming the file) if unreadable
    or malformed."""
    return resolve_map_paths(parse_toml(read_config_text(path), path), path.parent)


def resolve_map_paths(data: dict[str, Any], folder: Path) -> dict[str, Any]:
    """``data`` (parsed TOML tables, changed in place) with every map file path (``[run] map``
    and ``[presets.NAME.run] map``, when not a map kind) made absolute, a relative one against
    ``folder``, the config file's (:func:`~skidnav.files.configtables.resolve_path`)."""
    presets = data.get("presets", {})
    runs = [data.get("run")]
    if isinstance(presets, dict):
        runs += [p.get("run") for p in presets.values() if isinstance(p, dict)]
    for run in runs:
        if not isinstance(run, dict):
            continue
        spec = run.get("map")
        if isinstance(spec, str) and spec not in MAP_KINDS:
            run["map"] = str(resolve_path(spec, folder))
    return data


def load_config(path: Path | None, preset: str | None = None) -> RealtimeConfig:
    """Read a TOML config (defaults without a path), every preset checked, ``preset`` applied;
    UserError if unreadable or invalid, one line naming the file and the table
    (``"my.toml: [tcp]: unknown key 'secret_fle' …"``)."""
    if path is None:
        return config_from_mapping({}, preset)
    tables = read_tables(path)
    try:
        for other in table(tables.get("presets", {}), "[presets]"):
            if other != preset:
                config_from_mapping(tables, other)  # every preset is checked, not only this one
        return config_from_mapping(tables, preset)
    except UserError as error:
        raise within(error, str(path)) from None


def with_overrides(config: RealtimeConfig, **run_fields: Any) -> RealtimeConfig:
    """A copy with the given :class:`RunSettings` fields replaced (None values ignored)."""
    changes = {key: value for key, value in run_fields.items() if value is not None}
    if not changes:
        return config
    try:
        run = dataclasses.replace(config.run, **changes)
    except (ValueError, TypeError) as error:
        raise UserError(str(error)) from None
    return dataclasses.replace(config, run=run)
