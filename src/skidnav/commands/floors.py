"""``skidnav world floors calibrate``: fit the ICR model to the MuJoCo robot on each floor material
(:mod:`skidnav.physics.calibration`), print the table and optionally write it as JSON;
``skidnav world floors prior``: how far every floor is from the robot's datasheet, the prior of
every kinematic learner (:mod:`skidnav.robot.datasheet`)."""

from __future__ import annotations

import argparse
import json

import numpy as np

from skidnav.commands.parsing import path_argument
from skidnav.errors import UserError
from skidnav.files.atomic import write_user_file
from skidnav.files.outputs import check_output_file
from skidnav.physics.backend import PhysicsUnavailable
from skidnav.physics.materials import MATERIALS
from skidnav.robot.datasheet import Datasheet, PriorGap, floor_gap, material_gap
from skidnav.robot.floors import calibrated_floors
from skidnav.robot.params import RobotParams
from skidnav.robot.presets import ROBOT_PRESETS, robot_preset
from skidnav.robot.slip import SLIP_PRESETS
from skidnav.statistics import formatting

MAX_SEGMENTS = 10_000
"""Most 1-s excitation segments per material."""


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``floors`` with its ``calibrate`` subcommand."""
    parser = subparsers.add_parser("floors", help="floor materials of the physical robot")
    actions = parser.add_subparsers(dest="floors_command", required=True)
    calibrate = actions.add_parser(
        "calibrate", help="fit the ICR model to the MuJoCo robot on each floor material"
    )
    calibrate.add_argument(
        "--material", action="append", choices=sorted(MATERIALS), help="default: every one"
    )
    calibrate.add_argument(
        "--robot", choices=sorted(ROBOT_PRESETS), default="thesis", help="the robot to drive"
    )
    calibrate.add_argument("--seconds", type=int, default=60, help="driving per material [s]")
    calibrate.add_argument("--seed", type=int, default=0, help="excitation and interval seed")
    calibrate.add_argument("--out", type=path_argument, help="JSON file to write the fits to")
    calibrate.set_defaults(func=_calibrate)
    prior = actions.add_parser(
        "prior",
        help="how far each floor's true forward speed, turn rate and ICR are from the datasheet",
    )
    prior.set_defaults(func=_prior)


def prior_gap_rows() -> list[tuple[str, str, PriorGap]]:
    """(floor, where it is, its gap) for every slip preset of the kinematic simulator and every
    calibrated material of the MuJoCo robot, against the thesis robot's datasheet."""
    rows = [(preset, "kinematic simulator", floor_gap(preset)) for preset in SLIP_PRESETS]
    rows += [(m, "MuJoCo robot", material_gap(m)) for m in calibrated_floors()]
    return rows


def prior_gap_table() -> str:
    """:func:`prior_gap_rows` as a Markdown table (the documentation shows it)."""
    sheet = Datasheet.of(RobotParams())
    lines = [
        f"| floor | robot | forward speed, truth / datasheet | turn rate, truth / datasheet | "
        f"x_ICR [mm] (datasheet {sheet.x_icr * 1000:g}) |",
        "|---|---|---|---|---|",
    ]
    for floor, where, gap in prior_gap_rows():
        x_icr = round(gap.x_icr * 1000, 1) + 0.0  # no "-0.0"
        lines.append(f"| `{floor}` | {where} | {gap.forward:.3f} | {gap.turn:.3f} | {x_icr:.1f} |")
    return "\n".join(lines)


def _prior(args: argparse.Namespace) -> int:
    print(prior_gap_table())
    return 0


def _calibrate(args: argparse.Namespace) -> int:
    if not 2 <= args.seconds <= MAX_SEGMENTS:
        raise UserError(f"expected --seconds in [2, {MAX_SEGMENTS}], got {args.seconds}")
    if args.seed < 0:
        raise UserError(f"expected --seed >= 0, got {args.seed}")
    if args.out is not None:
        check_output_file(args.out)
    from skidnav.physics.calibration import calibrate

    materials = args.material or list(MATERIALS)
    try:
        fits = calibrate(
            materials,
            np.random.default_rng(args.seed),
            segments=args.seconds,
            robot=robot_preset(args.robot),
        )
    except PhysicsUnavailable as error:
        raise UserError(str(error)) from None
    print(
        f"{'material':12s} {'r [mm]':>22s} {'c [mm]':>24s} {'x_ICR [mm]':>22s} "
        f"{'v_x noise [mm/s]':>17s} {'yaw noise [rad/s]':>18s} {'eta [rad/s]':>12s}"
    )
    for fit in fits:
        print(
            f"{fit.material:12s} {_mm(fit.wheel_radius, fit.wheel_radius_interval):>22s} "
            f"{_mm(fit.half_track, fit.half_track_interval):>24s} "
            f"{_mm(fit.x_icr, fit.x_icr_interval):>22s} {fit.vx_noise * 1000:17.2f} "
            f"{fit.yaw_noise:18.4f} {fit.eta:12.3f}"
        )
    if args.out is not None:
        document = {
            "robot": args.robot,
            "seed": args.seed,
            "seconds": args.seconds,
            "fits": [f.as_dict() for f in fits],
        }
        write_user_file(args.out, (json.dumps(document, indent=2) + "\n").encode(), "fits")
        print(f"wrote {args.out}")
    return 0


def _mm(value: float, interval: tuple[float, float]) -> str:
    """``value [low, high]`` in millimetres."""
    return formatting.interval(value * 1000, interval[0] * 1000, interval[1] * 1000, 2)
