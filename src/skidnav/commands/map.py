"""``skidnav world map generate|show``: make a seeded map file, or show one as text or a PNG."""

from __future__ import annotations

import argparse

import numpy as np

from skidnav.commands.parsing import path_argument
from skidnav.errors import UserError
from skidnav.files.outputs import check_output_file
from skidnav.world.discretization import Discretization
from skidnav.world.grid import MAP_KINDS, MAX_SIZE, generate_map
from skidnav.world.mapfile import format_map, load_map, save_map


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``map`` with its ``generate`` and ``show`` subcommands."""
    parser = subparsers.add_parser("map", help="generate or show arena maps")
    actions = parser.add_subparsers(dest="map_command", required=True)
    generate = actions.add_parser("generate", help="write a seeded map file")
    generate.add_argument("--kind", choices=MAP_KINDS, default="obstacles")
    generate.add_argument("--seed", type=int, default=0, help="map seed")
    generate.add_argument("--size", type=int, nargs=2, default=(25, 25), metavar=("NX", "NY"))
    generate.add_argument("--out", type=path_argument, help="map file to write (default: print it)")
    generate.set_defaults(func=_generate)
    show = actions.add_parser("show", help="print a map file as text, or draw it as a PNG")
    show.add_argument("file", type=path_argument)
    show.add_argument("--png", type=path_argument, help="write a picture instead of printing text")
    show.set_defaults(func=_show)


def _generate(args: argparse.Namespace) -> int:
    if min(args.size) < 5:
        raise UserError(
            f"expected --size of at least 5 × 5 cells, got {args.size[0]} × {args.size[1]}"
        )
    if max(args.size) > MAX_SIZE:
        raise UserError(
            f"expected --size of at most {MAX_SIZE} × {MAX_SIZE} cells (the map file limit), "
            f"got {args.size[0]} × {args.size[1]}"
        )
    if args.out is not None:
        check_output_file(args.out)
    try:
        grid = generate_map(args.kind, np.random.default_rng(args.seed), tuple(args.size))
    except ValueError as error:
        raise UserError(str(error)) from None
    if args.out is None:
        print(format_map(grid), end="")
    else:
        try:
            save_map(grid, args.out)
        except OSError as error:
            raise UserError(
                f"{args.out}: cannot write the map ({error.strerror or error})"
            ) from None
        print(f"wrote {args.out} ({args.kind}, start {grid.start}, goal {grid.goal})")
    return 0


def _show(args: argparse.Namespace) -> int:
    if args.png is not None:
        check_output_file(args.png, "--png")
    grid = load_map(args.file)
    if args.png is None:
        print(format_map(grid), end="")
        return 0
    from skidnav.robot.slip import make_slip_field
    from skidnav.world.rendering import rgb_frame, save_frame, with_legend

    disc = Discretization(n_x=grid.shape[0], n_y=grid.shape[1])
    start = disc.cell_centre(*grid.start)
    slip = make_slip_field("thesis", np.random.default_rng(0))
    frame = rgb_frame(grid, disc, slip, np.array([*start, 0.0]), [])
    save_frame(with_legend(frame), args.png)
    print(f"wrote {args.png}")
    return 0
