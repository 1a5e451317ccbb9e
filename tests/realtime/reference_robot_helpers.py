"""The reference robot for the real-time tests: in a thread of the test (its state at hand) or
as ``python -m skidnav.realtime.reference_robot`` (a subprocess), and a bridge of two
pseudo-terminals, so that pyserial opens a serial port on both ends."""

from __future__ import annotations

import contextlib
import os
import select
import subprocess
import sys
import threading
import time
import tty
from typing import Any

from skidnav.realtime.reference_robot.loop import run
from skidnav.realtime.reference_robot.simulated_base import SimulatedBase
from skidnav.realtime.reference_robot.tcp import TcpTransport
from tests.realtime.realtime_helpers import cli_env


class RobotThread:
    """The reference robot on a free loopback port in a background thread, driving a
    :class:`SimulatedBase` (:attr:`base`); ``options`` go to :func:`run`. :meth:`freeze`
    stalls its loop as a frozen process would be (its clock runs on); :attr:`events` collects
    what it reports."""

    def __init__(self, **options: Any) -> None:
        self.base = SimulatedBase()
        self.transport = TcpTransport("127.0.0.1", 0)
        self.port = self.transport.port
        self.events: list[tuple[float, str, dict[str, Any]]] = []
        self._done = threading.Event()
        self._thaw = threading.Event()
        self._thaw.set()
        options.setdefault("period", 0.02)
        self.thread = threading.Thread(
            target=run,
            args=(self.transport, self.base, time.monotonic, self._running),
            kwargs={"on_event": self._event, **options},
        )

    def _event(self, event: str, fields: dict[str, Any]) -> None:
        self.events.append((time.monotonic(), event, fields))

    def _running(self) -> bool:
        self._thaw.wait()
        return not self._done.is_set()

    def freeze(self, seconds: float) -> tuple[float, float]:
        """Stall the robot's loop for ``seconds``; the monotonic times of the freeze and thaw."""
        self._thaw.clear()
        frozen = time.monotonic()
        time.sleep(seconds)
        thawed = time.monotonic()
        self._thaw.set()
        return frozen, thawed

    def kinds(self, after: float = 0.0) -> list[str]:
        return [event for when, event, _ in self.events if when >= after]

    def __enter__(self) -> RobotThread:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._done.set()
        self._thaw.set()
        self.thread.join(timeout=5)
        self.transport.close()


class RobotProcess:
    """``python -m skidnav.realtime.reference_robot`` with ``arguments`` (``--verbose``: its
    events on standard error, read back by :meth:`events`)."""

    def __init__(self, *arguments: str) -> None:
        command = [sys.executable, "-m", "skidnav.realtime.reference_robot", "--verbose"]
        self.process = subprocess.Popen(
            [*command, *arguments], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
            env=cli_env(),
        )  # fmt: skip
        assert self.process.stdout is not None
        self.banner = self.process.stdout.readline().strip()
        assert self.banner.startswith(("listening on ", "serving ")), self.banner
        self.port = int(self.banner.rsplit(":", 1)[1]) if "listening" in self.banner else 0

    def stop(self) -> tuple[int, str]:
        """End it with SIGTERM; its exit code and standard error."""
        if self.process.poll() is None:
            self.process.terminate()
        _, err = self.process.communicate(timeout=10)
        return self.process.returncode, err


class PtyBridge:
    """Two pseudo-terminals whose masters a thread copies between: pyserial opens
    :attr:`robot_end` on one side and :attr:`host_end` on the other, as two ends of a cable."""

    def __init__(self) -> None:
        self._fds = [os.openpty(), os.openpty()]
        for _, slave in self._fds:
            tty.setraw(slave)  # no echo, no line editing, from the start
        (robot_master, robot_slave), (host_master, host_slave) = self._fds
        self.robot_end, self.host_end = os.ttyname(robot_slave), os.ttyname(host_slave)
        self._pairs = {robot_master: host_master, host_master: robot_master}
        self._done = threading.Event()
        self.thread = threading.Thread(target=self._copy)

    def _copy(self) -> None:
        while not self._done.is_set():
            ready, _, _ = select.select(list(self._pairs), [], [], 0.01)
            for fd in ready:
                try:
                    data = os.read(fd, 4096)
                except OSError:  # no one holds that end open yet
                    time.sleep(0.01)
                    continue
                os.write(self._pairs[fd], data)

    def __enter__(self) -> PtyBridge:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._done.set()
        self.thread.join(timeout=5)
        for pair in self._fds:
            for fd in pair:
                with contextlib.suppress(OSError):
                    os.close(fd)
