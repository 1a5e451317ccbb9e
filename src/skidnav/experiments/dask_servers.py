"""The local Dask cluster of the ``dask`` backend: TLS between every part, no HTTP server.

Imported only when a local cluster starts (it imports ``distributed``, the ``distributed``
extra), by :func:`skidnav.experiments.dask_backend.dask_client`, and by the cluster's worker
processes, which import :class:`QuietWorker` by name.

* **TLS with credentials that exist only for this cluster.** ``Security.temporary()`` makes a
  self-signed key and certificate in memory; the scheduler, the nannies, the workers and the
  runner's client all hold it and require it of each other (``tls://``, certificates verified
  both ways). A process without that certificate, another local user's among them, cannot
  complete a handshake with any port of the cluster, so it can neither submit work nor call a
  worker's or nanny's ``run`` handler. The nannies hand the credentials to the worker processes
  they spawn (pickled through multiprocessing's pipe, never written to a shared file).
* **No HTTP server.** Dask's scheduler and workers start an HTTP server even without a
  dashboard (``dashboard_address=None`` only drops the dashboard's pages: the scheduler still
  serves ``/health``, ``/metrics`` and its JSON routes on port 8787, each worker on a random port,
  unauthenticated). :class:`QuietScheduler` and :class:`QuietWorker` start none, so the cluster
  listens only on its comm ports: the scheduler's and one per nanny in the runner's process, one
  per worker process.
"""

from __future__ import annotations

import logging
from typing import Any

import distributed

untyped: Any = distributed  # Security.temporary and SpecCluster have no type hints

LOCAL_HOST = "127.0.0.1"
"""The only interface the local cluster listens on."""


class QuietScheduler(distributed.Scheduler):
    """A Dask scheduler without an HTTP server (dashboard, ``/health``, metrics)."""

    def start_http_server(self, *args: Any, **kwargs: Any) -> None:
        """Start nothing: the runner uses only the scheduler's comm port."""


class QuietWorker(distributed.Worker):
    """A Dask worker without an HTTP server (``/health``, metrics)."""

    def start_http_server(self, *args: Any, **kwargs: Any) -> None:
        """Start nothing: the scheduler and the client use only the worker's comm port."""


def local_cluster(jobs: int) -> Any:
    """A started ``distributed.SpecCluster`` of ``jobs`` single-threaded worker processes (each
    under a nanny) and a scheduler in this process, all on :data:`LOCAL_HOST` over ``tls://``
    with fresh temporary credentials, none serving HTTP. As ``LocalCluster(n_workers=jobs,
    threads_per_worker=1)`` would, each worker may use ``1/jobs`` of the machine's memory.
    Connect to it with ``distributed.Client(cluster)``, which takes its credentials."""
    security = untyped.Security.temporary()
    common = {
        "host": LOCAL_HOST,
        "protocol": "tls://",
        "security": security,
        "dashboard": False,
        "dashboard_address": None,
    }
    scheduler = {"cls": QuietScheduler, "options": {**common, "port": 0}}
    worker = {
        "cls": distributed.Nanny,
        "options": {
            **common,
            "worker_class": QuietWorker,
            "nthreads": 1,
            "memory_limit": 1.0 / jobs,  # a fraction of the machine's memory
            "silence_logs": logging.WARNING,
        },
    }
    return untyped.SpecCluster(
        scheduler=scheduler,
        workers={index: worker for index in range(jobs)},
        worker=worker,
        security=security,
        silence_logs=logging.WARNING,
    )
