"""The sim server's transport: the byte channels it serves (a connected socket, a pty, a serial
device) and its TCP listener, which serves loopback only unless the link is authenticated."""

from __future__ import annotations

import contextlib
import ipaddress
import os
import socket
from typing import Protocol

from skidnav.errors import UserError
from skidnav.realtime.link import protocol as pr
from skidnav.realtime.link.auth import SECRET_ENV

BACKLOG = 1024
"""Pending TCP connections the kernel queues for the server (listen backlog; the kernel may cap
it lower, e.g. at ``net.core.somaxconn`` on Linux). Connections beyond it are dropped and retried
by the client a second or more later."""


class Channel(Protocol):
    """A connected, non-blocking byte stream the server can select on."""

    def fileno(self) -> int: ...
    def read(self) -> bytes:
        """Bytes that arrived; b"" at end of stream; BlockingIOError if none yet."""
        ...

    def write(self, data: bytes) -> int:
        """Write what fits now; returns the bytes taken (0 if none); OSError if broken."""
        ...

    def close(self) -> None: ...


class FdChannel:
    """A file descriptor — a pty master, a serial device, a connected socket's — as a
    :class:`Channel`, made non-blocking; closing the channel closes the descriptor."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        os.set_blocking(fd, False)

    def fileno(self) -> int:
        return self.fd

    def read(self) -> bytes:
        return os.read(self.fd, 4096)

    def write(self, data: bytes) -> int:
        try:
            return os.write(self.fd, data)
        except BlockingIOError:
            return 0

    def close(self) -> None:
        os.close(self.fd)


def refuse_busy(sock: socket.socket) -> None:
    """Tell a second client ``busy`` (one non-blocking send, errors ignored) and close it."""
    busy = pr.encode(pr.Error(seq=0, code="busy", message="another client is connected"))
    with contextlib.suppress(OSError):
        sock.setblocking(False)
        sock.send(busy)
    sock.close()


def bind_listener(host: str, port: int, *, authenticated: bool = False) -> socket.socket:
    """A listening TCP socket on (host, port) with a backlog of :data:`BACKLOG`; port 0 picks
    a free one. OSError if it cannot bind, OverflowError for a port beyond 65535; UserError for
    an address beyond loopback unless the server is ``authenticated`` (has a link secret):
    whoever reaches an open port first would drive the robot."""
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        listener.bind((host, port))
        address = listener.getsockname()[0]
        if not (authenticated or ipaddress.ip_address(address).is_loopback):
            raise UserError(
                f"refusing to serve the robot link on {address} without a secret "
                f"(give --secret-file or set {SECRET_ENV}; docs/protocol.md)"
            )
        listener.listen(BACKLOG)
    except (OSError, OverflowError, UserError):
        listener.close()
        raise
    return listener
