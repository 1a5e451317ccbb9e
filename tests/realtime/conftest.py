"""Fixtures of the real-time tests (helpers in realtime_helpers.py)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from tests.realtime.realtime_helpers import ServerProcess, ServerThread


@pytest.fixture
def server_thread() -> Iterator[ServerThread]:
    """A sim server on a free loopback port in a background thread (time scale 10)."""
    with ServerThread() as server:
        yield server


@pytest.fixture
def server_process(tmp_path: Path) -> Iterator[Callable[..., ServerProcess]]:
    """Factory of sim server subprocesses, all stopped at teardown."""
    started: list[ServerProcess] = []

    def start(*arguments: str, port: int = 0, log: str = "server.jsonl") -> ServerProcess:
        server = ServerProcess(tmp_path / log, *arguments, port=port)
        started.append(server)
        return server

    yield start
    for server in started:
        server.stop()
