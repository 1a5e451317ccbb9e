"""Registration of skidnav's environments the moment Gymnasium is imported, so that
``import skidnav`` does not import Gymnasium (and NumPy) itself: ``skidnav --help`` and
``skidnav --version`` answer without them, and ``gymnasium.make("skidnav/SkidSteerNav-v0")``
works after ``import skidnav`` whichever of the two was imported first.

The hook is a finder first on ``sys.meta_path`` that, asked for ``gymnasium``, steps aside, finds
its spec as Python would, and runs :func:`~skidnav.envs.registration.register_envs` right after
the module has executed (PEP 451's ``exec_module``). Nothing else is imported or changed.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import importlib.util
import sys
from collections.abc import Sequence
from types import ModuleType

GYMNASIUM = "gymnasium"
REGISTRATION = "skidnav.envs.registration"


def _register() -> None:
    registration = sys.modules.get(REGISTRATION)
    if registration is not None and not hasattr(registration, "register_envs"):
        return  # it is importing Gymnasium now: it registers once loaded (its last line)
    from skidnav.envs.registration import register_envs

    register_envs()


class RegisterOnImport(importlib.abc.MetaPathFinder):
    """A one-shot finder that registers skidnav's environments once Gymnasium is imported."""

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        """Gymnasium's own spec, its loader made to register skidnav's envs after executing
        the module; None (not ours) for any other module."""
        if fullname != GYMNASIUM:
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(GYMNASIUM)
        if spec is None or spec.loader is None:
            return spec
        execute = spec.loader.exec_module

        def exec_module(module: ModuleType) -> None:
            execute(module)
            _register()

        spec.loader.exec_module = exec_module  # type: ignore[method-assign]  # this spec's only
        return spec


def register_on_import() -> None:
    """Register skidnav's environments now if Gymnasium is imported, else as soon as it is."""
    if GYMNASIUM in sys.modules:
        _register()
    elif not any(isinstance(finder, RegisterOnImport) for finder in sys.meta_path):
        sys.meta_path.insert(0, RegisterOnImport())
