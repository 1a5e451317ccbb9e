"""A TCP listener as the reference robot's :class:`~.interfaces.Transport`, with ``socket`` and
``select`` alone (CPython, and MicroPython on a board with a network: ESP32, Pico W).

It serves one host at a time: a connection that arrives while a host is attached is told
``error`` ``busy`` and closed at once. Every socket is non-blocking; :meth:`TcpTransport.wait`
polls both the listener and the host.
"""

import select
import socket

from .interfaces import BUSY_LINE, Transport


def _would_block(error: OSError) -> bool:
    """True for "try again later" (EAGAIN / EWOULDBLOCK, errno 11 or 35; CPython raises it as
    BlockingIOError, MicroPython as a plain OSError)."""
    return isinstance(error, BlockingIOError) or error.args[0] in (11, 35)


class TcpTransport(Transport):
    """Listens on (``host``, ``port``) — loopback by default; port 0 picks a free one, see
    :attr:`port`. Serving beyond loopback needs a link secret (the command line checks it)."""

    def __init__(self, host: str = "127.0.0.1", port: int = 5757) -> None:
        address = socket.getaddrinfo(host, port, 0, socket.SOCK_STREAM)[0][-1]
        listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            listener.bind(address)
            listener.listen(8)
        except OSError:
            listener.close()
            raise
        listener.setblocking(False)
        self.listener = listener
        self.client: socket.socket | None = None
        self.poller = select.poll()
        self.poller.register(listener, select.POLLIN)

    @property
    def port(self) -> int:
        """The port listened on."""
        return int(self.listener.getsockname()[1])

    def attach(self) -> bool:
        """Accept every pending connection: the first becomes the host if none is attached,
        the others are told ``busy`` and closed."""
        while True:
            try:
                sock, _ = self.listener.accept()
            except OSError:  # none pending (or one aborted before it was accepted)
                return self.client is not None
            if self.client is not None:
                _refuse(sock)
                continue
            sock.setblocking(False)
            if hasattr(socket, "TCP_NODELAY"):  # a line leaves at once
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self.client = sock
            self.poller.register(sock, select.POLLIN)

    def read(self) -> bytes | None:
        if self.client is None:
            return None
        try:
            data = self.client.recv(4096)
        except OSError as error:
            return b"" if _would_block(error) else None
        return data if data else None

    def write(self, data: bytes) -> int:
        if self.client is None:
            raise OSError("no host attached")
        try:
            return int(self.client.send(data))
        except OSError as error:
            if _would_block(error):
                return 0
            raise

    def hang_up(self) -> None:
        client, self.client = self.client, None
        if client is not None:
            self.poller.unregister(client)
            client.close()

    def wait(self, timeout: float) -> None:
        self.poller.poll(int(timeout * 1000))

    def close(self) -> None:
        self.hang_up()
        self.listener.close()


def _refuse(sock: socket.socket) -> None:
    """Tell a second host ``busy`` (one non-blocking send) and close it."""
    try:
        sock.setblocking(False)
        sock.send(BUSY_LINE)
    except OSError:  # it left already, or its buffer is full: it is closed all the same
        sock.close()
        return
    sock.close()
