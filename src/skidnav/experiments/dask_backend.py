"""The client of the runner's ``dask`` backend: on a private local cluster, or on a remote
scheduler (``--scheduler``), and how each link is secured.

* Without a scheduler: a local cluster of ``jobs`` worker processes on 127.0.0.1 that talks
  only ``tls://`` with credentials made for it and serves no HTTP
  (:mod:`skidnav.experiments.dask_servers`): no other process, of this user or another, can
  run code on it.
* ``--scheduler tls://host:port``: the client presents the certificate named in Dask's own
  configuration, as every Dask client does — ``distributed.comm.tls.ca-file``,
  ``distributed.comm.tls.client.cert`` and ``distributed.comm.tls.client.key`` (a YAML file in
  ``~/.config/dask/`` or ``$DASK_CONFIG``, or the environment variables
  ``DASK_DISTRIBUTED__COMM__TLS__CA_FILE``, ``…__CLIENT__CERT``, ``…__CLIENT__KEY``). A missing or
  unreadable setting is refused in one line before anything is contacted.
* ``--scheduler tcp://host:port`` (or an address without a scheme): allowed, with one warning
  line, since whoever reaches such a scheduler can run code on its workers and read the runs.

Dask is the ``distributed`` extra; its modules are imported here only when a client is made.
"""

from __future__ import annotations

import contextlib
import importlib
import logging
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from skidnav.childprocess import safe_path_children
from skidnav.errors import UserError, first_line

logger = logging.getLogger(__name__)

DASK_CONNECT_TIMEOUT = "15s"
"""How long the Dask client tries to reach ``scheduler``."""
TLS_SCHEMES = ("tls", "wss")
"""Address schemes on which Dask encrypts and authenticates with its TLS credentials."""
CLIENT_TLS = {
    "ca-file": "distributed.comm.tls.ca-file",
    "cert": "distributed.comm.tls.client.cert",
    "key": "distributed.comm.tls.client.key",
}
"""The Dask config keys of a client's TLS credentials (PEM files; the key may sit in the
certificate's file, so ``key`` is optional)."""


def distributed_module() -> Any:
    """The ``distributed`` package, imported when a Dask backend is used (handled as ``Any``:
    its objects cross into code that does not type them)."""
    return importlib.import_module("distributed")


@contextlib.contextmanager
def dask_client(jobs: int, scheduler: str | None) -> Iterator[Any]:
    """A ``distributed.Client`` on ``scheduler`` (secured as the module says), or on a private
    local cluster of ``jobs`` worker processes; closed (with the cluster) on exit.

    Raises:
        UserError: a ``tls://`` scheduler without usable TLS credentials in Dask's config, or a
            scheduler that cannot be reached within :data:`DASK_CONNECT_TIMEOUT`.
    """
    distributed = distributed_module()
    if scheduler is not None:
        security = scheduler_security(scheduler)
        try:
            client = distributed.Client(scheduler, timeout=DASK_CONNECT_TIMEOUT, security=security)
        except (OSError, RuntimeError, TypeError, ValueError) as error:
            message = first_line(error)
            raise UserError(f"cannot connect to Dask scheduler {scheduler!r}: {message}") from None
        with client:
            yield client
        return
    from skidnav.experiments.dask_servers import local_cluster

    with (
        safe_path_children(),
        local_cluster(jobs) as cluster,
        distributed.Client(cluster) as client,
    ):
        yield client


def scheduler_security(scheduler: str) -> Any:
    """The ``distributed.Security`` of a client on ``scheduler``: for a ``tls://`` (or
    ``wss://``) address, the credentials of Dask's config (:data:`CLIENT_TLS`), loaded once
    here so that a bad one is refused before anything is contacted; otherwise None (Dask's
    defaults) after one warning that the link is neither authenticated nor encrypted.

    Raises:
        UserError: a setting of :data:`CLIENT_TLS` missing, naming no file, or not PEM.
    """
    distributed = distributed_module()
    scheme, _ = distributed.comm.parse_address(scheduler)
    if scheme not in TLS_SCHEMES:
        logger.warning(
            "Dask scheduler %s: the link is unauthenticated and unencrypted (whoever reaches "
            "the scheduler can run code on its workers and read the runs); use a tls:// "
            "scheduler",
            scheduler,
        )
        return None
    dask = importlib.import_module("dask")
    for name, key in CLIENT_TLS.items():
        value = dask.config.get(key, None)
        if not value and name != "key":
            raise UserError(
                f"Dask scheduler {scheduler}: a {scheme}:// scheduler needs {key} in Dask's "
                f"config (e.g. DASK_{key.upper().replace('.', '__').replace('-', '_')}=FILE)"
            )
        if value and "\n" not in value and not Path(value).is_file():  # "\n": inline PEM
            raise UserError(f"Dask config {key}: no such file: {value!r}")
    try:
        security = distributed.Security(require_encryption=True)
        security.get_connection_args("client")  # reads and parses the PEM files
    except (OSError, ValueError) as error:
        raise UserError(f"Dask TLS config (distributed.comm.tls): {first_line(error)}") from None
    return security
