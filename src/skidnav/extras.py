"""The optional parts of skidnav and the one check that they are installed.

``pip install skidnav`` brings the core: the simulator, the env, the tabular and linear agents,
the runner (serial and process backends, Parquet tables) and the report. Each *extra* brings
the packages of one more part (``pip install "skidnav[deep]"``; ``skidnav[all]`` brings every
one). :data:`EXTRAS` names the modules each extra provides, and :func:`require` is the one
check every command, agent or backend that needs an extra calls before it starts any work: it
refuses in one line naming the ``pip install`` that fixes it.

>>> EXTRAS["deep"]
('torch', 'stable_baselines3')
>>> install_hint("deep")
'pip install "skidnav[deep]"'
"""

from __future__ import annotations

import importlib.util
from types import ModuleType

from skidnav.errors import SetupError

EXTRAS: dict[str, tuple[str, ...]] = {
    "physics": ("mujoco",),
    "deep": ("torch", "stable_baselines3"),
    "camera": ("cv2",),
    "ros2": ("roslibpy",),
    "serial": ("serial",),
    "distributed": ("dask", "distributed", "cryptography"),
    "tuning": ("optuna",),
    "search": ("cmaes", "threadpoolctl"),
    "gp": ("sklearn",),
    "docs": ("mkdocs", "material", "mkdocstrings", "mkdocs_jupyter"),
    "logging": ("tensorboard",),
    "video": ("moviepy",),
    "notebook": ("nbmake",),
}
"""Extra (``pyproject.toml``'s ``[project.optional-dependencies]``) → the top-level modules it
provides, the ones skidnav imports."""


class MissingExtraError(SetupError):
    """A part of skidnav was asked for whose extra is not installed (one line, exit code 2)."""


def install_hint(extra: str) -> str:
    """The command that installs ``extra``, e.g. ``pip install "skidnav[camera]"``."""
    return f'pip install "skidnav[{extra}]"'


def missing_module(extra: str) -> str | None:
    """The first module of ``extra`` (a key of :data:`EXTRAS`) that cannot be imported here,
    or None when all can. Nothing is imported: the modules are only looked for."""
    for module in EXTRAS[extra]:
        try:
            found = importlib.util.find_spec(module)
        except (ImportError, ValueError):  # a blocked or broken entry in sys.modules
            found = None
        if found is None:
            return module
    return None


def installed(extra: str) -> bool:
    """True when every module of ``extra`` can be imported."""
    return missing_module(extra) is None


def require(extra: str, what: str) -> None:
    """Return when ``extra`` is installed; otherwise refuse ``what`` (e.g. ``"agent 'dqn'"``,
    ``"--backend dask"``) in one line.

    Raises:
        MissingExtraError: ``<what> needs the <extra> extra (no module '<m>'): pip install
            "skidnav[<extra>]"``.
    """
    module = missing_module(extra)
    if module is not None:
        raise MissingExtraError(missing_message(extra, what, module))


def import_with(extra: str, what: str, module: str) -> ModuleType:
    """The module named ``module`` once :func:`require` has found ``extra`` installed; an import
    that fails all the same (a module of the extra missing) is refused in the same one line.

    Raises:
        MissingExtraError: as :func:`require`.
    """
    require(extra, what)
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as error:
        raise MissingExtraError(missing_message(extra, what, str(error.name))) from None


def missing_message(extra: str, what: str, module: str) -> str:
    """The one line of :func:`require` (also for an import that failed later, naming its
    ``module``).

    >>> print(missing_message("deep", "agent 'dqn'", "torch"))
    agent 'dqn' needs the deep extra (no module 'torch'): pip install "skidnav[deep]"
    """
    return f"{what} needs the {extra} extra (no module {module!r}): {install_hint(extra)}"
