"""Registration of skidnav's Gymnasium environments, and the ids a config may name.

An experiment config's ``env_id`` is a registered Gymnasium id (:func:`registered_env_id`):
skidnav's, or any other in Gymnasium's registry. Gymnasium's ``module:Env-v0`` form, which
imports ``module`` for its registrations, is accepted only for a module the user allowed on the
command line (``--env-module MODULE``, :func:`allow_env_modules`), never one a config names: a
config cannot make skidnav import, let alone call, anything (docs/experiments.md).

>>> registered_env_id("skidnav/DynaMaze-v0")
'skidnav/DynaMaze-v0'
>>> registered_env_id("this:Zen-v0")
Traceback (most recent call last):
...
skidnav.errors.UserError: env_id 'this:Zen-v0': module 'this' is not allowed (only the modules \
named with --env-module are imported)
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable
from typing import Any, TypeVar

import gymnasium

from skidnav.errors import UserError, first_line, shown

ENV_ID = "skidnav/SkidSteerNav-v0"
MAX_EPISODE_STEPS = 500
"""Actions per episode of ``skidnav/SkidSteerNav-v0`` before Gymnasium's ``TimeLimit`` truncates
it (``gymnasium.make(ENV_ID, max_episode_steps=N)`` overrides it)."""
MAZE_IDS = {
    "skidnav/DynaMaze-v0": "skidnav.envs.mazes:dyna_maze",
    "skidnav/BlockingMaze-v0": "skidnav.envs.mazes:blocking_maze",
    "skidnav/ShortcutMaze-v0": "skidnav.envs.mazes:shortcut_maze",
}
"""The Sutton & Barto (2018) ch. 8 grid mazes (Examples 8.1–8.3) → their factories. They are
registered without a time limit, as the book runs them (episodes end at the goal)."""


def register_envs() -> None:
    """Register ``skidnav/SkidSteerNav-v0`` (truncated by Gymnasium's ``TimeLimit`` after
    :data:`MAX_EPISODE_STEPS` actions; ``gymnasium.make_vec`` makes its compiled vector env,
    :mod:`skidnav.envs.vector`) and the grid mazes (idempotent)."""
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(
            id=ENV_ID,
            entry_point="skidnav.envs.navigation:SkidSteerNavEnv",
            vector_entry_point="skidnav.envs.vector:make_vector_env",
            max_episode_steps=MAX_EPISODE_STEPS,
        )
    for env_id, entry_point in MAZE_IDS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(id=env_id, entry_point=entry_point, max_episode_steps=None)


CREATOR_SUFFIX = " was raised from the environment creator for "
"""Where Gymnasium's message about an env that refused its arguments starts repeating every
argument (maps and arrays included: dozens of lines)."""


def creation_error(error: BaseException) -> str:
    """The one line of an error ``gymnasium.make`` raised, without Gymnasium's repetition of the
    env's arguments: ``"SkidSteerNavEnv.__init__() got an unexpected keyword argument 'x'"``.

    >>> creation_error(TypeError("f() got an unexpected keyword argument 'x'" + CREATOR_SUFFIX
    ...                          + "skidnav/SkidSteerNav-v0 with kwargs ({'x': 1})"))
    "f() got an unexpected keyword argument 'x'"
    """
    text = str(error).split(CREATOR_SUFFIX, 1)[0]
    return first_line(ValueError(text)) if text else first_line(error)


Result = TypeVar("Result")
_allowed_modules: set[str] = set()
"""The modules :func:`allow_env_modules` imported in this process."""


def allow_env_modules(modules: Iterable[str]) -> None:
    """Import each of ``modules`` (dotted names the user gave with ``--env-module``, never a
    config's) so that it registers its environments, and accept ``module:Env-v0`` ids naming
    it in this process from now on. UserError naming a module that is not a dotted name or
    cannot be imported."""
    for module in modules:
        if not all(part.isidentifier() for part in module.split(".")):
            raise UserError(f"--env-module: expected a dotted module name, got {module!r}")
        try:
            importlib.import_module(module)
        except Exception as error:  # the user's module: not found, or failing as it loads
            raise UserError(f"--env-module {module}: {first_line(error)}") from None
        _allowed_modules.add(module)


def allowed_env_modules() -> tuple[str, ...]:
    """The modules :func:`allow_env_modules` imported in this process, sorted."""
    return tuple(sorted(_allowed_modules))


def with_env_modules(
    modules: Iterable[str], function: Callable[..., Result], *arguments: Any
) -> Result:
    """``function(*arguments)`` after :func:`allow_env_modules` of ``modules``: a worker
    process's trial, as ``functools.partial(with_env_modules, modules, trial)``."""
    allow_env_modules(modules)
    return function(*arguments)


def registered_env_id(env_id: str) -> str:
    """The Gymnasium id to make for a config's ``env_id``: ``env_id`` itself, or for
    ``module:Env-v0`` (``module`` allowed by :func:`allow_env_modules`) ``Env-v0``. Nothing is
    imported. UserError naming ``env_id`` unless that id is registered."""
    module, colon, name = env_id.rpartition(":")
    if colon and module not in _allowed_modules:
        raise UserError(
            f"env_id {shown(env_id)}: module {shown(module)} is not allowed (only the modules "
            "named with --env-module are imported)"
        )
    if name not in gymnasium.registry:
        ids = ", ".join([ENV_ID, *MAZE_IDS])
        raise UserError(
            f"env_id {shown(env_id)} is not a registered environment (skidnav's: {ids}; another "
            "module's with --env-module MODULE)"
        )
    return name


register_envs()  # importing this module imports Gymnasium: the envs are registered with it
