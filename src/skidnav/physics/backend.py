"""Importing MuJoCo: the optional dependency, and the GL backend of its offscreen renderer.

MuJoCo reads ``MUJOCO_GL`` when it is first imported and, given a backend whose library is
missing, fails to import at all. :func:`load_mujoco` therefore chooses before that first import:
a ``MUJOCO_GL`` the user set is kept; otherwise EGL where ``libEGL`` is found, else OSMesa where
``libOSMesa`` is, else nothing (physics works, offscreen rendering does not:
:func:`offscreen_rendering` says so and the report falls back to the 2-D renderer).
"""

from __future__ import annotations

import ctypes.util
import functools
import importlib
import os
import sys
from types import ModuleType

from skidnav.extras import MissingExtraError, install_hint, missing_message, missing_module

INSTALL_HINT = install_hint("physics")
"""How MuJoCo is installed: ``pip install "skidnav[physics]"``."""


class PhysicsUnavailable(MissingExtraError):
    """MuJoCo is not installed (or does not import); the message is one line (a user error:
    the command line prints it and exits with code 2)."""


def gl_backend() -> str:
    """The ``MUJOCO_GL`` value to use: the user's, else ``egl``, ``osmesa`` or ``""`` (none)."""
    chosen = os.environ.get("MUJOCO_GL", "")
    if chosen:
        return chosen
    if ctypes.util.find_library("EGL"):
        return "egl"
    if ctypes.util.find_library("OSMesa"):
        return "osmesa"
    return ""


_imported_before_choice: list[bool] = []
"""Whether MuJoCo was already imported, without ``MUJOCO_GL``, when skidnav first loaded it
(it then uses its default, a windowed GLFW context, which cannot render here)."""


def choose_gl_backend() -> None:
    """Set ``MUJOCO_GL`` to :func:`gl_backend` unless it is set (before MuJoCo is imported)."""
    if not _imported_before_choice:
        _imported_before_choice.append(
            sys.modules.get("mujoco") is not None and "MUJOCO_GL" not in os.environ
        )
    backend = gl_backend()
    if backend and "MUJOCO_GL" not in os.environ:
        os.environ["MUJOCO_GL"] = backend
        os.environ.setdefault("PYOPENGL_PLATFORM", backend)


@functools.cache
def load_mujoco() -> ModuleType:
    """The ``mujoco`` module, imported once with :func:`gl_backend` chosen.

    Raises:
        PhysicsUnavailable: MuJoCo is not installed or fails to import.
    """
    absent = missing_module("physics")
    if absent is not None:
        raise PhysicsUnavailable(missing_message("physics", "the MuJoCo robot", absent))
    choose_gl_backend()
    try:
        mujoco = importlib.import_module("mujoco")
    except ImportError as error:
        module = error.name or "mujoco"
        raise PhysicsUnavailable(missing_message("physics", "the MuJoCo robot", module)) from None
    except Exception as error:  # a broken GL backend makes the import itself fail
        raise PhysicsUnavailable(
            f"MuJoCo failed to import with MUJOCO_GL={os.environ.get('MUJOCO_GL', '')!r}: {error}"
        ) from None
    return mujoco


def mujoco_available() -> bool:
    """True when :func:`load_mujoco` succeeds."""
    try:
        load_mujoco()
    except PhysicsUnavailable:
        return False
    return True


@functools.cache
def offscreen_rendering() -> str:
    """``""`` when MuJoCo can render offscreen here, else the one-line reason it cannot."""
    try:
        mujoco = load_mujoco()
    except PhysicsUnavailable as error:
        return str(error)
    if not os.environ.get("MUJOCO_GL"):
        return "no GL backend (install libegl1 or libosmesa6, or set MUJOCO_GL)"
    if _imported_before_choice[0]:
        return "MuJoCo was imported before skidnav.physics chose its GL backend (set MUJOCO_GL)"
    try:
        model = mujoco.MjModel.from_xml_string("<mujoco><worldbody/></mujoco>")
        renderer = mujoco.Renderer(model, 8, 8)
        renderer.close()
    except Exception as error:
        return f"MuJoCo cannot render with MUJOCO_GL={os.environ['MUJOCO_GL']}: {error}"
    return ""
