"""``skidnav robot``: the real-time platform (docs/realtime.md).

``skidnav robot sim-server`` runs the simulated robot server; ``skidnav robot run`` runs an agent
(or a frozen continuous policy) in real time against a robot driver; ``skidnav robot study``
runs agents × presets × seeds against the sim server through the experiment runner and
tabulates success: a shortcut that writes the study's config of its flags (``kind =
"robot-study"``, saved as ``OUT/config.toml``; ``skidnav run`` runs and resumes it alike) and
runs it (:mod:`skidnav.studies.hardware.study`).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
from pathlib import Path
from types import FrameType
from typing import IO, Any

from skidnav.commands.parsing import comma_integers, path_argument, positive_number
from skidnav.commands.verbs import HELP
from skidnav.errors import UserError
from skidnav.files.outputs import check_output_dir


def port_number(text: str) -> int:
    """A TCP port for argparse: an integer in [0, 65535] (0: pick a free one)."""
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a port number, got {text!r}") from None
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"expected a port in [0, 65535], got {port}")
    return port


def add_parser(subparsers: Any) -> None:
    """Add ``robot`` with its ``sim-server``, ``run`` and ``study`` subcommands."""
    robot = subparsers.add_parser("robot", help=HELP["robot"])
    commands = robot.add_subparsers(dest="robot_command", required=True)
    _add_sim_server(commands)
    _add_run(commands)
    _add_study(commands)


def _add_sim_server(commands: Any) -> None:
    from skidnav.robot.slip import SLIP_PRESETS

    server = commands.add_parser("sim-server", help="simulated robot speaking the line protocol")
    server.add_argument(
        "--port", type=port_number, required=True, help="TCP port (0: pick a free one)"
    )
    server.add_argument("--host", default="127.0.0.1", help="bind address (default 127.0.0.1)")
    server.add_argument("--time-scale", type=float, default=1.0, help="robot s per wall s")
    server.add_argument(
        "--slip",
        choices=SLIP_PRESETS,
        default="rough",
        metavar="PRESET",
        help=f"slip preset: {', '.join(SLIP_PRESETS)} (default %(default)s)",
    )
    server.add_argument("--drift", type=float, default=0.0, help="relative slip drift amplitude")
    server.add_argument(
        "--drift-period", type=positive_number, default=600.0, help="drift period [s]"
    )
    server.add_argument("--latency", type=float, default=0.0, help="command latency [s]")
    server.add_argument("--pose-noise", type=float, default=0.0, help="pose noise σ [m]")
    server.add_argument("--drop", type=float, default=0.0, help="pose drop probability")
    server.add_argument("--map", default="free", help="free, obstacles, maze or a map file")
    server.add_argument(
        "--integrator",
        choices=("euler", "exact"),
        default="euler",
        help="pose integration of each 0.1 s sub-step, as the simulator's (default euler)",
    )
    server.add_argument(
        "--physics",
        choices=("kinematic", "mujoco"),
        default="kinematic",
        help="what moves the robot: the ICR model, or the MuJoCo robot (default kinematic)",
    )
    server.add_argument(
        "--floor", help="mujoco: one floor material everywhere (default: the slip preset's)"
    )
    server.add_argument(
        "--lockstep",
        action="store_true",
        help="no wall clock: each command advances the robot one period (docs/protocol.md)",
    )
    server.add_argument("--seed", type=int, default=0, help="root seed (map, slip, noise)")
    server.add_argument("--log", type=path_argument, help="JSON-lines log of received commands")
    server.add_argument("--link-timeout", type=float, default=0.5, help="quiet link stop [s]")
    server.add_argument(
        "--max-lease",
        type=float,
        default=0.5,
        help="longest a command holds the wheels after it arrived, whatever its ttl [s] (≤ 5)",
    )
    server.add_argument(
        "--secret-file",
        type=path_argument,
        help="file holding the link secret (or set SKIDNAV_LINK_SECRET); needed beyond loopback",
    )
    server.add_argument(
        "--idle-timeout", type=float, default=2.0, help="drop a client quiet this long [s]"
    )
    server.add_argument(
        "--exit-with-stdin",
        action="store_true",
        help="exit when standard input ends (the parent's pipe: the server never outlives it)",
    )
    server.add_argument(
        "--fault", default="", help="comma-separated faults injected by successive SIGUSR1s"
    )
    server.set_defaults(func=_run_sim_server)


def _run_sim_server(args: argparse.Namespace) -> int:
    from skidnav.realtime.control.records import EventLog
    from skidnav.realtime.robot_server.lockstep import LockstepServer
    from skidnav.realtime.robot_server.server import SimServer
    from skidnav.realtime.robot_server.transport import bind_listener

    robot, options = _sim_robot(args)
    server_class = LockstepServer if args.lockstep else SimServer
    authenticated = options.secret is not None
    with contextlib.ExitStack() as stack:
        try:
            listener = stack.enter_context(
                bind_listener(args.host, args.port, authenticated=authenticated)
            )
        except OSError as error:
            raise UserError(f"cannot listen on {args.host}:{args.port}: {error}") from None
        stream = stack.enter_context(_open_log(args.log)) if args.log else None
        watch = sys.stdin.fileno() if args.exit_with_stdin else None
        server = server_class(robot, options, EventLog(stream), watch_fd=watch)

        def on_signal(signum: int, frame: FrameType | None) -> None:
            if signum == signal.SIGUSR1:
                server.inject()
            else:
                server.request_shutdown()

        for signum in (signal.SIGUSR1, signal.SIGTERM, signal.SIGINT):
            signal.signal(signum, on_signal)
        host, port = listener.getsockname()[:2]
        server.events.write("listening", host=host, port=port, pid=os.getpid())
        print(f"listening on {host}:{port}", flush=True)
        server.serve_tcp(listener)
    return 0


def _sim_robot(args: argparse.Namespace) -> tuple[Any, Any]:
    """The simulated robot of the ``sim-server`` arguments (compiled, warmed up) and the
    server's options; UserError on a bad value."""
    from skidnav.physics.backend import PhysicsUnavailable
    from skidnav.realtime.config import ServerOptions
    from skidnav.realtime.link.auth import load_secret
    from skidnav.realtime.robot_server.simulated_robot import SimRobotConfig, build_robot, warm_up
    from skidnav.robot.params import RobotParams

    try:
        config = SimRobotConfig(latency=args.latency, pose_noise=args.pose_noise, drop=args.drop)
        options = ServerOptions(
            time_scale=args.time_scale,
            link_timeout=args.link_timeout,
            idle_timeout=args.idle_timeout,
            faults=tuple(fault for fault in args.fault.split(",") if fault),
            max_lease=args.max_lease,
            secret=load_secret(args.secret_file),
        )
    except ValueError as error:
        raise UserError(str(error)) from None
    try:
        robot = build_robot(
            slip=args.slip, drift=args.drift, drift_period=args.drift_period, map_spec=args.map,
            seed=args.seed, config=config, robot=RobotParams(integrator=args.integrator),
            physics=args.physics, floor=args.floor,
        )  # fmt: skip
    except PhysicsUnavailable as error:
        raise UserError(f"--physics mujoco: {error}") from None
    warm_up(robot)
    return robot, options


def _open_log(path: Path) -> IO[str]:
    """``path`` opened for appending; UserError naming it if that is impossible."""
    try:
        return path.open("a", encoding="utf-8")
    except OSError as error:
        raise UserError(f"cannot write the log {path}: {error.strerror or error}") from None


def _add_run(commands: Any) -> None:
    run = commands.add_parser("run", help="run an agent in real time")
    run.add_argument(
        "--driver", choices=("sim", "tcp", "serial", "ros2"), default="sim", help="robot link"
    )
    pilot = run.add_mutually_exclusive_group(required=True)
    pilot.add_argument("--agent", help="agent name (q-learning, dyna-q, dyna-kinematic, …)")
    pilot.add_argument(
        "--policy", help="a continuous policy by name (goal-tracker), frozen: it does not learn"
    )
    pilot.add_argument(
        "--policy-file",
        type=path_argument,
        help="a saved continuous policy (its JSON file), loaded by the loader of its format",
    )
    pilot.add_argument(
        "--agent-file",
        type=path_argument,
        help="a saved agent of any family (skidnav run's runs/RUN/agent.json): tabular agents "
        "and mppi-kinematic keep learning, the others act frozen",
    )
    run.add_argument(
        "--config", type=path_argument, help="real-time TOML config (configs/realtime.toml)"
    )
    run.add_argument("--preset", help="a [presets.NAME] table of the config to apply")
    run.add_argument("--episodes", type=int, help="episodes to run (overrides the config)")
    run.add_argument(
        "--time-scale", type=float, help="robot s per wall s (a sim server's; 1 for a real robot)"
    )
    run.add_argument("--reset", choices=("auto", "manual"), help="between episodes")
    run.add_argument(
        "--out", type=path_argument, default=Path("realtime-run"), help="output directory"
    )
    run.add_argument("--resume", action="store_true", help="continue from the last checkpoint")
    run.add_argument("--quiet", action="store_true", help="no live progress line")
    run.set_defaults(func=_run_loop)


def _run_loop(args: argparse.Namespace) -> int:
    from skidnav.realtime.control.run import RobotRunSettings, run_robot

    check_output_dir(args.out)
    settings = RobotRunSettings(
        out=args.out, driver=args.driver, agent=args.agent, policy=args.policy,
        policy_file=args.policy_file, agent_file=args.agent_file, config=args.config,
        preset=args.preset, episodes=args.episodes, time_scale=args.time_scale, reset=args.reset,
        resume=args.resume,
    )  # fmt: skip

    def progress(line: str) -> None:
        if not args.quiet:
            print(f"\r{line:<79}", end="", file=sys.stderr, flush=True)

    def wait_for_operator(message: str) -> None:
        print(f"\n{message} — press Enter when ready", file=sys.stderr, flush=True)
        sys.stdin.readline()

    outcome = run_robot(settings, progress=progress, wait_for_operator=wait_for_operator)
    if not args.quiet:
        print(file=sys.stderr)
    print(outcome.summary)
    if outcome.problem is not None:
        print(f"skidnav: error: {outcome.problem}", file=sys.stderr)
    return outcome.code


def _add_study(commands: Any) -> None:
    study = commands.add_parser(
        "study",
        help="hardware-in-the-loop study: agents × presets × seeds on the sim server",
        description='Write the study config of these flags (kind = "robot-study", the '
        "real-time config by its path) to OUT/config.toml and run it as 'skidnav run' does "
        "(serially; resumable on the same --out); then the tables, OUT/study.md.",
    )
    study.add_argument("--config", type=path_argument, required=True, help="configs/realtime.toml")
    study.add_argument("--agents", help="comma-separated agent names ([study] agents)")
    study.add_argument("--presets", help="comma-separated preset names ([study] presets)")
    study.add_argument("--episodes", type=int, help="episodes per run (default: the preset's)")
    study.add_argument("--time-scale", type=float, help="robot s per wall s of the sim server")
    study.add_argument("--seeds", type=int, help="runs per agent × preset ([study] seeds)")
    study.add_argument(
        "--sim-episodes",
        type=comma_integers,
        help="episodes of pre-training in the simulator, one arm per value, e.g. 0,1000 "
        "([study] sim_episodes)",
    )
    study.add_argument("--out", type=path_argument, required=True, help="output directory")
    study.add_argument("--quiet", action="store_true", help="no live progress line")
    study.set_defaults(func=_run_study)


def _run_study(args: argparse.Namespace) -> int:
    from skidnav.studies.hardware.study import load_study, run_study

    overrides = {
        "agents": args.agents,
        "presets": args.presets,
        "episodes": args.episodes,
        "time_scale": args.time_scale,
        "seeds": args.seeds,
        "sim_episodes": args.sim_episodes,
    }
    grid, text = load_study(args.config, overrides)
    check_output_dir(args.out)

    def progress(line: str) -> None:
        if not args.quiet:
            print(f"\r{line:<79}", end="", file=sys.stderr, flush=True)

    def announce(line: str) -> None:
        print(f"\r{line:<79}", file=sys.stderr, flush=True)

    outcome = run_study(grid, args.out, source_text=text, progress=progress, announce=announce)
    done_before = outcome.finished - outcome.executed
    tables_line = f"tables in {args.out / 'study.md'}" if outcome.finished else "no tables yet"
    print(
        f"{outcome.finished} of {outcome.n_runs} runs finished ({outcome.executed} run now, "
        f"{done_before} done before); {tables_line}"
    )
    return outcome.code
