"""The driver tables of a real-time config, ``[tcp]``, ``[serial]`` and ``[ros2]``
(docs/realtime.md, "Configuration"): each a frozen dataclass validated on construction and
built from its table by :func:`~skidnav.files.configtables.build_dataclass` (unknown keys,
types, ranges), and the rule that keeps link secrets out of config files.

A link secret is read from the file a line driver's ``secret_file`` names, or from the
environment variable ``SKIDNAV_LINK_SECRET`` (:mod:`skidnav.realtime.link.auth`), never from
the config itself: a ``secret`` key anywhere in a config is refused (:func:`refuse_inline_secrets`),
so a secret in the wrong place or under a misspelt key ends the run before any link opens,
never leaving it plain.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from skidnav.checks import check_integer
from skidnav.errors import ConfigError, shown
from skidnav.realtime.link.auth import SECRET_ENV
from skidnav.realtime.link.ros2_config import Ros2Config

INLINE_SECRET_KEY = "secret"
"""The key refused in every table of a config: a secret does not belong in a config file."""


@dataclass(frozen=True)
class TcpSettings:
    """A robot over TCP (``--driver tcp``, the ``[tcp]`` table).

    Attributes:
        host: the robot's address.
        port: its TCP port, in [1, 65535].
        secret_file: the file holding the link secret (docs/protocol.md, "Authentication"),
            absolute or relative to the working directory; None: the secret of
            ``SKIDNAV_LINK_SECRET`` if that is set, else no authentication (loopback robots).
        lockstep: the robot runs one control period per command (docs/protocol.md, "Lockstep").
    """

    host: str = "127.0.0.1"
    port: int = 5757
    secret_file: str | None = None
    lockstep: bool = False

    def __post_init__(self) -> None:
        _check_name("host", self.host)
        check_integer("port", self.port, 1, 65535)
        _check_link(self.secret_file, self.lockstep)


@dataclass(frozen=True)
class SerialSettings:
    """A robot over a serial line (``--driver serial``, the ``[serial]`` table).

    Attributes:
        url: the port: a device or any pyserial URL (``/dev/ttyUSB0``, ``rfc2217://…``).
        baudrate: its speed [bit/s], an integer >= 1.
        secret_file, lockstep: as :class:`TcpSettings`.
    """

    url: str = "/dev/ttyUSB0"
    baudrate: int = 115200
    secret_file: str | None = None
    lockstep: bool = False

    def __post_init__(self) -> None:
        _check_name("url", self.url)
        check_integer("baudrate", self.baudrate, 1)
        _check_link(self.secret_file, self.lockstep)


DRIVER_SETTINGS: dict[str, type[Any]] = {
    "tcp": TcpSettings,
    "serial": SerialSettings,
    "ros2": Ros2Config,
}
"""Each driver table → the dataclass of its settings."""


def _check_name(name: str, value: object) -> None:
    if not (isinstance(value, str) and value.strip()):
        raise ValueError(f"expected {name} to be a non-empty string, got {shown(value)}")


def _check_link(secret_file: object, lockstep: object) -> None:
    if secret_file is not None:
        _check_name("secret_file", secret_file)
    if not isinstance(lockstep, bool):
        raise ValueError(f"expected lockstep to be true or false, got {shown(lockstep)}")


def refuse_inline_secrets(data: Mapping[str, Any], where: str = "") -> None:
    """UserError naming the table of the first :data:`INLINE_SECRET_KEY` key anywhere in the
    parsed config ``data`` (its presets and their tables included), the value never shown.

    >>> refuse_inline_secrets({"presets": {"lab": {"tcp": {"secret": "s"}}}})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    skidnav.errors.ConfigError: key 'secret': a link secret ... in [presets.lab.tcp] (put it ...
    """
    for key, value in data.items():
        if key == INLINE_SECRET_KEY:
            raise ConfigError(
                f"key {key!r}: a link secret does not belong in a config file",
                (f"[{where}]" if where else "top level",),
                "put it in a file only you can read and name that with secret_file in [tcp] or "
                f"[serial], or set {SECRET_ENV}; see docs/protocol.md",
            )
        if isinstance(value, Mapping):
            refuse_inline_secrets(value, f"{where}.{key}" if where else str(key))
