"""A serial port, through pyserial, as the reference robot's
:class:`~.interfaces.Transport`, on CPython with pyserial. On a board, the same four methods
wrap ``machine.UART`` (docs/reference-robot.md).

A serial line has no connections: it is always attached, a host that opens the port again
starts over with a new ``hello`` (``connectionless``), and a host "dropped" for idleness simply
has to send ``hello`` again.
"""

import select

from .interfaces import Transport


class SerialTransport(Transport):
    """The serial device ``url`` (``/dev/ttyUSB0``, ``/dev/pts/3``…) at ``baudrate`` [bit/s],
    opened raw and non-blocking. OSError (pyserial's SerialException) if it cannot be
    opened; ImportError without pyserial."""

    connectionless = True

    def __init__(self, url: str, baudrate: int = 115200) -> None:
        import serial  # pyserial: only this adapter needs it

        self.port = serial.serial_for_url(url, baudrate=baudrate, timeout=0, write_timeout=0)

    def attach(self) -> bool:
        return True

    def read(self) -> bytes | None:
        waiting = self.port.in_waiting
        return bytes(self.port.read(waiting)) if waiting else b""

    def write(self, data: bytes) -> int:
        """What the port takes now: nothing until it is writable (pyserial's own non-blocking
        write would spin until it is)."""
        _, writable, _ = select.select([], [self.port.fileno()], [], 0)
        return int(self.port.write(data) or 0) if writable else 0

    def hang_up(self) -> None:
        """Nothing to close: the host's next ``hello`` starts a new session."""

    def wait(self, timeout: float) -> None:
        select.select([self.port.fileno()], [], [], timeout)

    def close(self) -> None:
        self.port.close()
