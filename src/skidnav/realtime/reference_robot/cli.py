"""``python -m skidnav.realtime.reference_robot``: the reference robot on CPython, driving
:class:`~.simulated_base.SimulatedBase`, over TCP (``--tcp HOST:PORT``, loopback unless a
secret is given) or a serial port (``--serial DEVICE``, pyserial). Prints ``listening on
HOST:PORT`` or ``serving DEVICE`` once it serves; with ``--verbose`` every connection, drop
and rule note goes to standard error as one JSON line. Bad arguments end in one line and exit
code 2; SIGINT and SIGTERM end it with the wheels stopped (exit code 0).
"""

from __future__ import annotations

import argparse
import ipaddress
import json
import math
import signal
import sys
import time
from collections.abc import Sequence
from types import FrameType
from typing import Any, NoReturn

from skidnav.arguments import StrictParser, positive_number
from skidnav.errors import UserError
from skidnav.realtime.reference_robot.interfaces import Transport
from skidnav.realtime.reference_robot.loop import run
from skidnav.realtime.reference_robot.rules import MAX_LEASE_LIMIT
from skidnav.realtime.reference_robot.secret_file import load_secret
from skidnav.realtime.reference_robot.simulated_base import SimulatedBase
from skidnav.realtime.reference_robot.tcp import TcpTransport

PROG = "reference-robot"


class _Parser(StrictParser):
    """Errors in one line, ``reference-robot: error: …``, exit code 2; no abbreviation of an
    option taken (``--secret X`` is not ``--secret-file X``), and the words after an unknown
    option not printed (:func:`~skidnav.errors.unknown_arguments`)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{PROG}: error: {message}\n")


def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def _address(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit() or int(port) > 65535:
        raise argparse.ArgumentTypeError(
            f"expected HOST:PORT with a port in [0, 65535], got {text!r}"
        )
    return host, int(port)


def parser() -> argparse.ArgumentParser:
    """The command line (see module doc)."""
    parse = _Parser(prog=PROG, description="The reference robot end of skidnav's line protocol.")
    where = parse.add_mutually_exclusive_group(required=True)
    where.add_argument(
        "--tcp", type=_address, metavar="HOST:PORT", help="listen on TCP (port 0: a free one)"
    )
    where.add_argument("--serial", metavar="DEVICE", help="serve a serial port (pyserial)")
    parse.add_argument("--baudrate", type=int, default=115200, help="serial speed [bit/s]")
    parse.add_argument("--secret-file", help="the link secret (else $SKIDNAV_LINK_SECRET)")
    parse.add_argument("--period", type=positive_number, default=0.1, help="control period [s]")
    parse.add_argument("--name", default="skidnav-reference", help="name sent in hello")
    parse.add_argument("--max-lease", type=positive_number, default=0.5, help="longest lease [s]")
    parse.add_argument("--link-timeout", type=positive_number, default=0.5, help="wheels stop [s]")
    parse.add_argument("--idle-timeout", type=positive_number, default=2.0, help="host dropped [s]")
    parse.add_argument(
        "--pose", type=_finite, nargs=3, default=(0.3, 0.25, 0.0), metavar=("X", "Y", "HEADING"),
        help="start pose of the simulated base [m, m, rad]",
    )  # fmt: skip
    parse.add_argument("--verbose", action="store_true", help="events as JSON lines on stderr")
    return parse


def _check(arguments: argparse.Namespace, secret: bytes | None) -> None:
    """The checks across arguments; UserError in one line."""
    if arguments.max_lease > MAX_LEASE_LIMIT:
        raise UserError(
            f"expected --max-lease in (0, {MAX_LEASE_LIMIT}] s, got {arguments.max_lease}"
        )
    if arguments.idle_timeout < arguments.link_timeout:
        raise UserError("expected --idle-timeout >= --link-timeout")
    if arguments.tcp is not None and secret is None:
        host = arguments.tcp[0]
        try:
            loopback = ipaddress.ip_address(host).is_loopback
        except ValueError:
            loopback = host == "localhost"
        if not loopback:
            raise UserError(
                f"refusing to serve the robot link on {host} without a secret "
                "(give --secret-file or set SKIDNAV_LINK_SECRET; docs/protocol.md)"
            )


def _transport(arguments: argparse.Namespace) -> tuple[Transport, str]:
    """The transport asked for and what to print once it serves; UserError if it cannot open."""
    try:
        if arguments.tcp is not None:
            tcp = TcpTransport(*arguments.tcp)
            return tcp, f"listening on {arguments.tcp[0]}:{tcp.port}"
        from skidnav.realtime.reference_robot.serial_port import SerialTransport

        return SerialTransport(arguments.serial, arguments.baudrate), f"serving {arguments.serial}"
    except ImportError:
        raise UserError("--serial needs pyserial: pip install 'skidnav[serial]'") from None
    except (OSError, OverflowError, ValueError) as error:  # pyserial's errors are OSErrors
        where = arguments.serial or "{}:{}".format(*arguments.tcp)
        raise UserError(f"cannot open {where}: {error}") from None


def _log_event(event: str, fields: dict[str, Any]) -> None:
    record = {"mono": time.monotonic(), "event": event, **fields}
    sys.stderr.write(json.dumps(record) + "\n")
    sys.stderr.flush()


def serve(arguments: argparse.Namespace) -> None:
    """Run the reference robot as ``arguments`` ask until SIGINT or SIGTERM."""
    secret = load_secret(arguments.secret_file)
    _check(arguments, secret)
    transport, banner = _transport(arguments)
    ending: list[int] = []

    def end(signum: int, frame: FrameType | None) -> None:
        ending.append(signum)

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, end)
    print(banner, flush=True)
    x, y, heading = arguments.pose
    try:
        run(
            transport, SimulatedBase(x, y, heading), time.monotonic, lambda: not ending,
            period=arguments.period, name=arguments.name, secret=secret,
            max_lease=arguments.max_lease, link_timeout=arguments.link_timeout,
            idle_timeout=arguments.idle_timeout,
            on_event=_log_event if arguments.verbose else None,
        )  # fmt: skip
    finally:
        transport.close()


def main(argv: Sequence[str] | None = None) -> int:
    """The command; returns its exit code (2 for a bad argument, in one line)."""
    arguments = parser().parse_args(argv)
    try:
        serve(arguments)
    except UserError as error:
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 2
    return 0
