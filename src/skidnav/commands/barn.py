"""``skidnav world barn import``: convert the BARN benchmark's worlds and reference paths to map
files (:mod:`skidnav.world.barn_import`)."""

from __future__ import annotations

import argparse

from skidnav.commands.parsing import path_argument
from skidnav.errors import UserError
from skidnav.world.barn import N_WORLDS


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``barn`` with its ``import`` subcommand."""
    parser = subparsers.add_parser("barn", help="the BARN benchmark's worlds")
    actions = parser.add_subparsers(dest="barn_command", required=True)
    convert = actions.add_parser(
        "import", help="convert BARN .world and path_N.npy files to skidnav map files"
    )
    convert.add_argument(
        "source",
        type=path_argument,
        help="the BARN directory, or a checkout of Daffan/the-barn-challenge",
    )
    convert.add_argument(
        "out", type=path_argument, help="a directory, or a .zip archive, to write to"
    )
    convert.add_argument(
        "--world", type=int, action="append", help=f"world number (default: all {N_WORLDS})"
    )
    convert.set_defaults(func=_import)


def _import(args: argparse.Namespace) -> int:
    from skidnav.world.barn_import import import_worlds

    indices = args.world or list(range(N_WORLDS))
    bad = [index for index in indices if not 0 <= index < N_WORLDS]
    if bad:
        raise UserError(f"expected --world in [0, {N_WORLDS - 1}], got {bad[0]}")
    try:
        written = import_worlds(args.source, args.out, indices)
    except OSError as error:
        raise UserError(f"{args.out}: cannot write ({error.strerror or error})") from None
    print(f"wrote {written} BARN world{'s' if written != 1 else ''} to {args.out}")
    return 0
