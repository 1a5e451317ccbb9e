"""Assembling a real-time run from its settings (:class:`RobotRunSettings`, what ``skidnav robot
run`` asks for): config, map, agent or continuous policy, driver, loop, signals.

Files written in the output directory (docs/realtime.md): ``run.jsonl`` (every command, pose,
transition, safety event), ``checkpoints/`` (per episode), ``summary.json``, and for the ``sim``
driver the server's own command log ``sim-server.jsonl``. :func:`new_agent` and :func:`drive` are
shared with the hardware-in-the-loop study (studies/hardware/study.py), whose runs are real-time
runs too.
"""

from __future__ import annotations

import inspect
import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import Any

import numpy as np

from skidnav.agents.mpc.agent import AGENT_NAME as MPPI_AGENT
from skidnav.agents.mpc.agent import MPPIKinematicAgent
from skidnav.agents.mpc.loading import load_mppi_agent
from skidnav.envs.step_info import step_info
from skidnav.errors import UserError, first_line, shown
from skidnav.files.outputs import make_output_dir
from skidnav.realtime.agent_file import RunWorld, SavedPilot, check_loaded, open_agent_file
from skidnav.realtime.arena import arena_map, seed_streams
from skidnav.realtime.config import RealtimeConfig, load_config, with_overrides
from skidnav.realtime.control.checkpoint import Checkpoints
from skidnav.realtime.control.episodes import EpisodeLoop
from skidnav.realtime.control.loop import RealtimeLoop
from skidnav.realtime.control.mppi_agent import new_mppi_agent, warm_up_mppi
from skidnav.realtime.control.mppi_loop import MPPILoop
from skidnav.realtime.control.policy_loop import PolicyLoop
from skidnav.realtime.control.run_folder import (
    RunOutcome,
    check_run_folder,
    mark_run_folder,
    summarize,
)
from skidnav.realtime.control.transition import compile_scoring
from skidnav.realtime.drivers import DRIVERS, link_secret, make_driver, require_driver_extras
from skidnav.realtime.policies import check_policy, select_policy
from skidnav.robot.kinematics import N_ACTIONS
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from skidnav.world.grid import GridMap


@dataclass(frozen=True)
class RobotRunSettings:
    """What a real-time run is asked for (``skidnav robot run``, docs/realtime.md), validated on
    construction: exactly one pilot (``agent``, ``policy``, ``policy_file`` or ``agent_file``).

    Attributes:
        out: the output directory (run log, checkpoints, summary).
        driver: the robot link, one of :data:`~skidnav.realtime.drivers.DRIVERS`.
        agent: a tabular agent that learns online, by registry name; None with a policy.
        policy: a named continuous policy (frozen: it does not learn), or None.
        policy_file: a saved continuous policy (its JSON file), or None.
        agent_file: a saved agent of any family (:mod:`skidnav.realtime.agent_file`): a
            tabular agent or ``mppi-kinematic`` keeps learning, the others act frozen; or None.
        config: the real-time TOML config (None: the defaults).
        preset: a ``[presets.NAME]`` table of the config to apply, or None.
        episodes: episodes to run, overriding ``[run] episodes`` (None: the config's).
        time_scale: robot seconds per wall second, overriding ``[run] time_scale`` (None: the
            config's).
        reset: ``"auto"`` or ``"manual"``, overriding ``[run] reset`` (None: the config's).
        resume: continue from the newest checkpoint in ``out``.
    """

    out: Path
    driver: str = "sim"
    agent: str | None = None
    policy: str | None = None
    policy_file: Path | None = None
    agent_file: Path | None = None
    config: Path | None = None
    preset: str | None = None
    episodes: int | None = None
    time_scale: float | None = None
    reset: str | None = None
    resume: bool = False

    def __post_init__(self) -> None:
        pilots = [
            p for p in (self.agent, self.policy, self.policy_file, self.agent_file) if p is not None
        ]
        if len(pilots) != 1:
            raise ValueError(
                "expected exactly one of agent, policy, policy_file and agent_file, got "
                f"{len(pilots)}"
            )
        if self.driver not in DRIVERS:
            raise ValueError(
                f"expected driver one of {', '.join(DRIVERS)}, got {shown(self.driver)}"
            )


def online_agent_class(name: str) -> type[Any]:
    """The class of agent ``name`` if it learns online on the robot (the tabular family, whose
    agents the real-time loop trains step by step, and ``mppi-kinematic``, which learns off the
    control path: :mod:`.mppi_loop`); UserError in one line naming those agents otherwise, or
    for an unknown name."""
    from skidnav.agents.catalog import entry, family

    described = entry(name)
    if described.family.name != "tabular" and name != MPPI_AGENT:
        online = ", ".join((*family("tabular").agents, MPPI_AGENT))
        raise UserError(
            f"agent {name!r} ({described.family.name} family) does not learn online on the "
            f"robot: expected one of {online} (a saved wheel-speed policy runs with "
            "--policy-file)"
        )
    return described.agent_class


def agent_context(name: str, robot: RobotParams, grid: Discretization) -> dict[str, Any]:
    """Extra constructor arguments of agent ``name``: the model-based agents take the robot
    geometry and discretization (``robot``, ``discretization``) for their kinematic model."""
    parameters = inspect.signature(online_agent_class(name).__init__).parameters
    context: dict[str, Any] = {}
    if "robot" in parameters:
        context["robot"] = robot
    if "discretization" in parameters:
        context["discretization"] = grid
    return context


def _make_or_resume_agent(
    name: str,
    settings: RobotRunSettings,
    config: RealtimeConfig,
    context: dict[str, Any],
    world: RunWorld,
    saved: SavedPilot | None = None,
) -> tuple[Any, int, dict[str, Any] | None]:
    """(agent ``name``, first episode, loop state to restore or None): from the newest
    checkpoint when resuming, else the ``saved`` agent (``--agent-file``, checked against the
    run's ``world``) or a new one."""
    from skidnav.agents.tabular.registry import load_agent

    if settings.resume:
        latest = Checkpoints(settings.out / "checkpoints").latest()
        if latest is None:
            raise UserError(f"{settings.out}: no checkpoint to resume from")
        episode, directory, state = latest
        if "policy" in state:
            raise UserError(
                f"{directory}: checkpoint holds policy {shown(state['policy'])}, not agent {name!r}"
            )
        agent = load_agent(directory / "agent", **context)
        if agent.name != name:
            raise UserError(f"{directory}: checkpoint holds agent {agent.name!r}, not {name!r}")
        return agent, episode + 1, state
    if saved is not None:
        agent = load_agent(saved.json_path.with_suffix(""), **context)
        check_loaded(agent, saved.json_path, world)
        return agent, 0, None
    agent = new_agent(name, config, context, world.grid, seed_streams(config.run.seed)["agent"])
    return agent, 0, None


def new_agent(
    name: str,
    config: RealtimeConfig,
    context: dict[str, Any],
    grid: Discretization,
    rng: np.random.Generator,
) -> Any:
    """A new agent ``name`` with the hyperparameters of ``[agents.NAME]``, drawing from the
    generator ``rng``, over ``grid``'s states and the robot's actions; UserError (one line) for
    hyperparameters this robot cannot serve, such as ``kinematic_model = "true"`` (a real or
    served robot has no true kinematic model)."""
    from skidnav.agents.tabular.registry import make_agent

    table = config.agents.get(name)
    try:
        return make_agent(name, grid.n_states, N_ACTIONS, table, rng, **context)
    except ValueError as error:
        raise UserError(f"agent {name!r}: {first_line(error)}") from None


def warm_up_agent(
    name: str, config: RealtimeConfig, context: dict[str, Any], n_states: int
) -> None:
    """Compile (numba) every kernel of agent ``name`` before the robot moves: a throwaway agent
    acts, learns from one dummy step and ends an episode. Compilation holds the GIL, which would
    starve the driver's reader thread and trip the pose watchdog mid-episode."""
    from skidnav.agents.tabular.registry import make_agent

    agent = make_agent(
        name, n_states, N_ACTIONS, config.agents.get(name), np.random.default_rng(0), **context
    )
    info = step_info((0.0, 0.0, 0.0), (0, 0, 0), False, (0.0, 0.0), 0, np.zeros((0, 6)))
    for terminated in (False, True):
        action = agent.act(0)
        agent.observe(0, action, -1.0, 1, terminated, False, info)
    agent.greedy_action(0)
    agent.end_episode()


@contextmanager
def interrupt_handlers(loop: EpisodeLoop) -> Iterator[None]:
    """SIGINT and SIGTERM trip the safety monitor (and end an operator wait) while inside."""

    def handler(signum: int, frame: FrameType | None) -> None:
        loop.interrupt(f"signal {signal.Signals(signum).name}")
        if loop.waiting_for_operator:
            raise KeyboardInterrupt

    previous = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for signum, old in previous.items():
            signal.signal(signum, old)


def run_robot(
    settings: RobotRunSettings,
    *,
    progress: Callable[[str], None],
    wait_for_operator: Callable[[str], None],
) -> RunOutcome:
    """Run an agent that learns online, or a frozen continuous policy (by name or file), in real
    time as ``settings`` ask. The config, the driver's extras and link secret, and the output
    folder (:func:`~.run_folder.check_run_folder`) are checked before anything slow starts."""
    config = load_config(settings.config, settings.preset)
    config = with_overrides(
        config, episodes=settings.episodes, time_scale=settings.time_scale, reset=settings.reset
    )
    require_driver_extras(settings.driver, config)
    link_secret(settings.driver, config)  # unreadable or short: refused now, never a plain link
    check_run_folder(settings.out, config, settings.resume)
    robot, grid = RobotParams(), Discretization()
    grid_map = arena_map(config.run.map, config.run.seed, grid)
    world = RunWorld(robot, grid, config.run.period * config.run.substeps, grid_map)
    pilot, first_episode, state, policy_name = _pilot(settings, config, world)
    out = make_output_dir(settings.out)  # a refused resume has written nothing
    mark_run_folder(out, config)
    code, loop = drive(
        settings.driver,
        pilot,
        grid_map,
        config,
        out,
        robot=robot,
        grid=grid,
        progress=progress,
        wait_for_operator=wait_for_operator,
        resume=(first_episode, state),
        policy_name=policy_name,
    )
    return summarize(loop, out, code)


def _pilot(
    settings: RobotRunSettings, config: RealtimeConfig, world: RunWorld
) -> tuple[Any, int, dict[str, Any] | None, str | None]:
    """(pilot, first episode, loop state to restore or None, policy label or None) of the run:
    an agent that learns online (by name or ``--agent-file``), warmed up, or a frozen policy
    (by name, ``--policy-file``, or ``--agent-file`` of a family that does not learn here),
    asked once at the start."""
    name, saved = settings.agent, None
    if settings.agent_file is not None:
        saved = open_agent_file(settings.agent_file, world)
        if saved.learns:
            name = saved.name
    if name is None:
        policy_file = saved.json_path if saved is not None else settings.policy_file
        pilot, policy_name = select_policy(settings.policy, policy_file, config, world.robot)
        check_policy(pilot, policy_name, world.grid_map, world.grid, world.action_duration)
        first_episode, state = _resume_policy(settings, policy_name)
        return pilot, first_episode, state, policy_name
    if name == MPPI_AGENT:
        mppi, first_episode, state = _mppi_agent(settings, config, world, saved)
        warm_up_mppi(mppi, world.grid_map)
        return mppi, first_episode, state, None
    context = agent_context(name, world.robot, world.grid)
    agent, first_episode, state = _make_or_resume_agent(
        name, settings, config, context, world, saved
    )
    warm_up_agent(name, config, context, world.grid.n_states)
    return agent, first_episode, state, None


def _mppi_agent(
    settings: RobotRunSettings, config: RealtimeConfig, world: RunWorld, saved: SavedPilot | None
) -> tuple[MPPIKinematicAgent, int, dict[str, Any] | None]:
    """(``mppi-kinematic``, first episode, loop state to restore or None): from the newest
    checkpoint when resuming, else the ``saved`` agent (checked against the run's ``world``) or
    a new one (:func:`~.mppi_agent.new_mppi_agent`)."""
    if settings.resume:
        episode, directory, state = _latest_agent_checkpoint(settings.out, MPPI_AGENT)
        return _load_mppi(directory / "agent.json", world), episode + 1, state
    if saved is not None:
        return _load_mppi(saved.json_path, world), 0, None
    rng = seed_streams(config.run.seed)["agent"]
    table = config.agents.get(MPPI_AGENT, {})
    agent = new_mppi_agent(
        table, world.robot, world.grid, world.action_duration, world.grid_map, rng
    )
    return agent, 0, None


def _load_mppi(json_path: Path, world: RunWorld) -> MPPIKinematicAgent:
    agent = load_mppi_agent(json_path)
    check_loaded(agent, json_path, world)
    return agent


def _latest_agent_checkpoint(out: Path, name: str) -> tuple[int, Path, dict[str, Any]]:
    """(episode, directory, loop state) of the newest checkpoint in ``out``, which must hold
    agent ``name`` (UserError otherwise)."""
    latest = Checkpoints(out / "checkpoints").latest()
    if latest is None:
        raise UserError(f"{out}: no checkpoint to resume from")
    episode, directory, state = latest
    if "policy" in state or state.get("agent", name) != name:
        holder = f"policy {shown(state['policy'])}" if "policy" in state else state.get("agent")
        raise UserError(f"{directory}: checkpoint holds {holder}, not agent {name!r}")
    return episode, directory, state


def _resume_policy(settings: RobotRunSettings, label: str) -> tuple[int, dict[str, Any] | None]:
    """(first episode, loop state to restore or None) of a policy's run; when resuming, the
    newest checkpoint, which must be one of the same policy (UserError otherwise)."""
    if not settings.resume:
        return 0, None
    latest = Checkpoints(settings.out / "checkpoints").latest()
    if latest is None:
        raise UserError(f"{settings.out}: no checkpoint to resume from")
    episode, directory, state = latest
    if state.get("policy") != label:
        holder = "an agent" if "policy" not in state else f"policy {shown(state['policy'])}"
        raise UserError(f"{directory}: checkpoint holds {holder}, not policy {label!r}")
    return episode + 1, state


def drive(
    driver_name: str,
    agent: Any,
    grid_map: GridMap,
    config: RealtimeConfig,
    out: Path,
    *,
    robot: RobotParams,
    grid: Discretization,
    progress: Callable[[str], None],
    wait_for_operator: Callable[[str], None] | None = None,
    resume: tuple[int, dict[str, Any] | None] = (0, None),
    policy_name: str | None = None,
) -> tuple[int, EpisodeLoop]:
    """Connect driver ``driver_name`` (a sim server logs to ``out/sim-server.jsonl``), run the loop
    of ``agent`` with its files in ``out`` from episode ``resume[0]`` (loop state ``resume[1]``
    restored first, if any), SIGINT and SIGTERM tripping its safety monitor, and shut the driver
    down, the loop's scoring kernels compiled before connecting; returns (exit code of
    :meth:`EpisodeLoop.run`, the loop). With a ``policy_name``, ``agent`` is a frozen continuous
    policy (:class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy`) run by
    :class:`PolicyLoop`; else a tabular agent run by :class:`RealtimeLoop`.

    Raises:
        UserError: the robot cannot be reached.
    """
    compile_scoring(grid_map, grid, robot)
    driver = make_driver(driver_name, config, server_log=out / "sim-server.jsonl")
    shutdown = getattr(driver, "shutdown", driver.close)
    try:
        driver.connect()
    except ConnectionError as error:
        shutdown()
        raise UserError(f"cannot connect to the robot ({driver_name}): {error}") from None
    try:
        common: dict[str, Any] = {
            "robot": robot,
            "grid": grid,
            "progress": progress,
            "wait_for_operator": wait_for_operator,
        }
        loop: EpisodeLoop
        if isinstance(agent, MPPIKinematicAgent):
            loop = MPPILoop(driver, agent, grid_map, config, out, **common)
        elif policy_name is None:
            loop = RealtimeLoop(driver, agent, grid_map, config, out, **common)
        else:
            loop = PolicyLoop(
                driver, agent, grid_map, config, out, policy_name=policy_name, **common
            )
        first_episode, state = resume
        if state is not None:
            loop.restore(state)
        with interrupt_handlers(loop):
            code = loop.run(first_episode)
    finally:
        shutdown()
    return code, loop
