"""The Dask backend's links, on real clusters: the runner's local cluster admits only its own
client (TLS with credentials of its own) and serves no HTTP; a remote ``tls://`` scheduler is
reached with the credentials of Dask's config, and a bad config is one line, exit code 2."""

from __future__ import annotations

import asyncio
import http.client
import os
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pandas as pd
import psutil
import pytest

from skidnav.cli import main
from skidnav.experiments import dask_backend
from skidnav.experiments.configfile import parse_config
from skidnav.experiments.runner import run_experiment
from skidnav.experiments.store import TrialResult
from tests.experiments.exp_support import TINY_TOML, cli_command, cli_env, comparable

distributed = pytest.importorskip("distributed")
dask = pytest.importorskip("dask")


def _listening(pid: int) -> set[tuple[int, str, int]]:
    """(pid, address, port) of every listening TCP socket of ``pid`` and its descendants."""
    parent = psutil.Process(pid)
    found = set()
    for process in [parent, *parent.children(recursive=True)]:
        with_sockets = process.net_connections(kind="inet")
        found |= {
            (process.pid, c.laddr.ip, c.laddr.port)
            for c in with_sockets
            if c.status == psutil.CONN_LISTEN
        }
    return found


def _answers_http(port: int) -> bool:
    """True when ``GET /health`` on 127.0.0.1:``port`` gets any HTTP response."""
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=5)
    try:
        connection.request("GET", "/health")
        connection.getresponse()
    except (OSError, http.client.HTTPException):
        return False
    finally:
        connection.close()
    return True


ATTEMPT_S = 10.0
"""Longest wait for one call on the cluster (a call that hangs counts as refused)."""


async def _rpc_run(address: str, security: Any, marker: Path) -> None:
    """Ask the worker or nanny at ``address`` to run ``marker.touch()`` (its ``run`` handler)."""
    arguments = security.get_connection_args("client") if security is not None else {}
    remote = distributed.core.rpc(address, connection_args=arguments, timeout=5)
    try:
        await remote.run(function=distributed.protocol.pickle.dumps(marker.touch))
    finally:
        await remote.close_rpc()


async def _client_run(address: str, security: Any, marker: Path) -> None:
    """Connect a client to the scheduler at ``address`` and run ``marker.touch()`` on every
    worker."""
    async with distributed.Client(
        address, security=security, asynchronous=True, timeout="2s"
    ) as client:
        await client.run(marker.touch)


def _stranger_ran(port: int, security: Any, marker: Path) -> list[str]:
    """What a process with other credentials than the cluster's (or none: ``tcp://``) managed
    on ``port``: a client's run and a direct ``run`` call, each told to touch ``marker``."""
    address = f"{'tcp' if security is None else 'tls'}://127.0.0.1:{port}"
    done = []
    for name, call in (("client", _client_run), ("run handler", _rpc_run)):
        try:
            asyncio.run(asyncio.wait_for(call(address, security, marker), ATTEMPT_S))
            done.append(f"{name} on {address}")
        except Exception:  # any refusal will do
            pass
    return done


def _probe(ports: set[int], tmp: Path) -> dict[str, Any]:
    """Try every port of the running cluster as a stranger and as the runner's own client."""
    own = distributed.default_client()  # the runner's client, in this process
    strangers = [None, distributed.Security.temporary()]  # no credentials; other credentials
    stranger_runs = [
        done
        for port in sorted(ports)
        for security in strangers
        for done in _stranger_ran(port, security, tmp / "stranger-was-here")
    ]
    own.run((tmp / "own-client").touch)
    workers = own.scheduler_info()["workers"]
    for index, address in enumerate([*workers, *(w["nanny"] for w in workers.values())]):
        call = _rpc_run(address, own.security, tmp / f"own-{index}")
        asyncio.run(asyncio.wait_for(call, ATTEMPT_S))
    return {
        "http": [port for port in sorted(ports) if _answers_http(port)],
        "stranger runs": stranger_runs,
        "scheduler": own.scheduler.address,
    }


def test_local_cluster_admits_only_its_own_client_and_serves_no_http(
    serial_results: Path, tmp_path: Path
) -> None:
    before = _listening(os.getpid())
    seen: dict[str, Any] = {}

    def probe_once(result: TrialResult) -> None:  # mid-sweep, in the runner's process
        if not seen:
            opened = _listening(os.getpid()) - before
            seen["opened"] = opened
            seen.update(_probe({port for _, _, port in opened}, tmp_path))

    out = tmp_path / "out"
    outcome = run_experiment(
        parse_config(TINY_TOML), out, backend="dask", jobs=2, on_run=probe_once
    )
    assert outcome.executed == 8
    pd.testing.assert_frame_equal(comparable(out), comparable(serial_results))
    assert seen["scheduler"].startswith("tls://127.0.0.1:")
    # the scheduler and two nannies here, one comm port in each worker process: nothing else
    opened = seen["opened"]
    assert {address for _, address, _ in opened} == {"127.0.0.1"}
    assert sum(pid == os.getpid() for pid, _, _ in opened) == 3
    assert len(opened) == 5 and len({pid for pid, _, _ in opened}) == 3
    assert seen["http"] == []
    assert seen["stranger runs"] == []
    assert not (tmp_path / "stranger-was-here").exists()
    # the same calls with the cluster's credentials do run: the refusals above are the TLS's
    assert (tmp_path / "own-client").exists()
    assert len(list(tmp_path.glob("own-*"))) == 1 + 4


def _credential_files(folder: Path) -> dict[str, str]:
    """A fresh self-signed certificate and key written to files, as Dask's config keys of a
    client (:data:`~skidnav.experiments.dask_backend.CLIENT_TLS`) name them."""
    temporary = distributed.Security.temporary()
    folder.mkdir()
    (folder / "ca.pem").write_text(temporary.tls_ca_file)
    (folder / "key.pem").write_text(temporary.tls_client_key)
    files = {"ca-file": folder / "ca.pem", "cert": folder / "ca.pem", "key": folder / "key.pem"}
    return {dask_backend.CLIENT_TLS[name]: str(path) for name, path in files.items()}


def _environment(settings: dict[str, str]) -> dict[str, str]:
    """Dask config ``settings`` as the environment variables Dask reads them from."""
    return {
        "DASK_" + key.upper().replace(".", "__").replace("-", "_"): value
        for key, value in settings.items()
    }


@pytest.fixture(scope="module")
def tls_cluster(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, dict[str, str]]]:
    """A TLS-only Dask cluster, as an admin would start one, and the client settings for it."""
    settings = _credential_files(tmp_path_factory.mktemp("tls") / "cluster")
    ca, cert, key = settings.values()
    security = distributed.Security(
        tls_ca_file=ca,
        **{f"tls_{role}_{kind}": path for role in ("scheduler", "worker", "client")
           for kind, path in (("cert", cert), ("key", key))},
        require_encryption=True,
    )  # fmt: skip
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        host="127.0.0.1",
        protocol="tls://",
        security=security,
        dashboard_address=None,
    ) as cluster:
        yield cluster.scheduler_address, settings


def test_tls_scheduler_with_the_credentials_of_dask_config(
    tls_cluster: tuple[str, dict[str, str]], serial_results: Path, tmp_path: Path
) -> None:
    address, settings = tls_cluster
    assert address.startswith("tls://")
    config = tmp_path / "tiny.toml"
    config.write_text(TINY_TOML)
    out = tmp_path / "out"
    args = ["run", str(config), "--out", str(out), "--backend", "dask", "--scheduler", address]
    result = subprocess.run(
        cli_command(*args, "--no-progress"),
        env=cli_env() | _environment(settings),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    assert "unauthenticated" not in result.stderr
    pd.testing.assert_frame_equal(comparable(out), comparable(serial_results))


def test_tls_scheduler_refuses_other_credentials(
    tls_cluster: tuple[str, dict[str, str]], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    address, _ = tls_cluster
    monkeypatch.setattr(dask_backend, "DASK_CONNECT_TIMEOUT", "2s")
    out = tmp_path / "out"
    with (
        dask.config.set(_credential_files(tmp_path / "other")),
        pytest.raises(dask_backend.UserError, match=r"^cannot connect to Dask scheduler 'tls://"),
    ):
        run_experiment(parse_config(TINY_TOML), out, backend="dask", scheduler=address)
    assert not out.exists()


def _garbage(folder: Path) -> dict[str, str]:
    (folder / "junk.pem").write_text("not a certificate\n")
    return {key: str(folder / "junk.pem") for key in dask_backend.CLIENT_TLS.values()}


BAD_CONFIGS = {
    "none": (lambda folder: {}, "needs distributed.comm.tls.ca-file in Dask's config"),
    "missing file": (
        lambda folder: {dask_backend.CLIENT_TLS["ca-file"]: str(folder / "nowhere.pem")},
        "Dask config distributed.comm.tls.ca-file: no such file",
    ),
    "not PEM": (_garbage, "Dask TLS config (distributed.comm.tls): "),
}


@pytest.mark.parametrize("case", list(BAD_CONFIGS))
def test_bad_tls_config_is_one_line_and_exit_2(
    case: str, tiny_config_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    make, expected = BAD_CONFIGS[case]
    settings = dict.fromkeys(dask_backend.CLIENT_TLS.values()) | make(tmp_path)
    out = tmp_path / "out"
    args = ["run", str(tiny_config_file), "--out", str(out), "--backend", "dask"]
    with dask.config.set(settings):
        code = main([*args, "--scheduler", "tls://127.0.0.1:9", "--no-progress"])
    error = capsys.readouterr().err
    assert code == 2
    assert error.count("\n") == 1 and error.startswith("skidnav: error: "), error
    assert expected in error
    assert not out.exists()
