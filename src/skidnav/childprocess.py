"""Python child processes that import nothing from the current directory.

``python -m module`` and ``python -c code`` put the current directory first on the child's
``sys.path``, so a ``json.py``, ``numpy.py`` or ``pickle.py`` in the folder skidnav is run from
would be imported in place of the real module, and run. Every Python child skidnav starts
therefore runs in safe-path mode (Python ≥ 3.11: ``-P``, or ``PYTHONSAFEPATH=1`` in its
environment), which leaves that entry out; ``PYTHONPATH`` and the installed packages stay:

* a child skidnav starts itself (the robot's sim server): :func:`python_module_command` in
  :func:`child_environment`;
* the workers of a process pool or of a local Dask cluster (and multiprocessing's resource
  tracker), which ``multiprocessing`` starts as ``python -c …`` with a command line no caller
  can change: :func:`safe_path_children` puts the same settings in this process's environment
  while they start, and they inherit it.

An empty entry of ``PYTHONPATH`` (``PYTHONPATH=/a:``, as ``export PYTHONPATH=/a:$PYTHONPATH``
leaves behind when it was unset) also means the current directory: children get ``PYTHONPATH``
without empty entries. Once started, a spawned worker takes this process's ``sys.path``: a parent
started as ``python -m skidnav.cli`` has the current directory on it (Python's rule for ``-m``,
which also holds for that parent itself); the ``skidnav`` command, or ``python -P -m
skidnav.cli``, has not.

>>> python_module_command("skidnav.cli", "--help")[1:]
['-P', '-m', 'skidnav.cli', '--help']
>>> child_environment({"PYTHONPATH": "/a::/b:", "HOME": "/h"})["PYTHONPATH"].split(":")[1:]
['/a', '/b']
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator, Mapping, MutableMapping
from pathlib import Path

SAFE_PATH_VARIABLE = "PYTHONSAFEPATH"
"""The environment variable of Python's safe-path mode (``-P``)."""
PACKAGE_ROOT = Path(__file__).resolve().parents[1]
"""The folder skidnav is imported from: first on a child's ``PYTHONPATH``, so that it imports
this same skidnav."""


def python_module_command(module: str, *arguments: str) -> list[str]:
    """argv of ``python -P -m module ARGUMENTS`` with this process's interpreter."""
    return [sys.executable, "-P", "-m", module, *arguments]


def child_environment(base: Mapping[str, str] | None = None) -> dict[str, str]:
    """``base`` (default: this process's environment) with safe-path mode on and
    ``PYTHONPATH`` = :data:`PACKAGE_ROOT` followed by ``base``'s non-empty entries."""
    environment = dict(os.environ if base is None else base)
    _make_safe(environment, str(PACKAGE_ROOT))
    return environment


@contextlib.contextmanager
def safe_path_children() -> Iterator[None]:
    """Python processes started in this block (multiprocessing's spawned workers, a local Dask
    cluster's) run in safe-path mode, with ``PYTHONPATH`` without empty entries: both set in
    ``os.environ`` on entry and restored on exit. (A spawned worker imports skidnav from this
    process's ``sys.path``, which it receives.)"""
    saved = {name: os.environ.get(name) for name in (SAFE_PATH_VARIABLE, "PYTHONPATH")}
    _make_safe(os.environ)
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def _make_safe(environment: MutableMapping[str, str], *first: str) -> None:
    """Turn safe-path mode on in ``environment`` and set its ``PYTHONPATH`` to ``first`` and
    its own non-empty entries (none: no ``PYTHONPATH``)."""
    environment[SAFE_PATH_VARIABLE] = "1"
    entries = [*first, *environment.get("PYTHONPATH", "").split(os.pathsep)]
    path = os.pathsep.join(entry for entry in entries if entry)
    if path:
        environment["PYTHONPATH"] = path
    else:
        environment.pop("PYTHONPATH", None)
