"""What a learning step is given: one real step as an :class:`Experience`, the agent's counters.

Every agent owns one compiled learning step, registered for the NamedTuple class of its arrays with
:func:`learning_step` in the agent's module, and called through :func:`learn` once per real step by
the step-by-step loop (:meth:`skidnav.agents.tabular.agent.TabularAgent.observe`) and by the fused
trainer (:mod:`skidnav.agents.tabular.fused_loop`) alike::

    kernel(arrays, settings, counters, experience, rng) -> None

``arrays`` and ``settings`` are the agent's own NamedTuples (what it learns into, its scalars);
``counters`` is its int64 array of :data:`N_COUNTERS` (the caller has already counted the step in
``counters[STEPS]``; the kernel adds its model-based updates to ``counters[PLANNING_UPDATES]``);
``rng`` is the agent's generator.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, NamedTuple, TypeVar

import numpy as np

from skidnav._jit import dispatch_on_type

STEPS, PLANNING_UPDATES = range(2)
N_COUNTERS = 2
"""Columns of an agent's int64 ``counters``: real steps observed, planning updates made."""

NO_LOG = -1
"""``Experience.n_logged`` of an env that gives no kinematic log (not the same as an empty one)."""


class Experience(NamedTuple):
    """One real step (s, a, r, s′) and what the env measured during it.

    ``pose`` is float64 (3,), the pose after the step (x [m], y [m], heading [rad]), all −1 when
    the env gives none; ``log`` is float64 (n, 6), the kinematic samples of the step's sub-steps
    (:func:`skidnav.sim.navigation.transition`), of which the first ``n_logged`` rows count
    (:data:`NO_LOG`: the env keeps no log).
    """

    state: int
    action: int
    reward: float
    next_state: int
    terminated: bool
    collided: bool
    pose: np.ndarray
    log: np.ndarray
    n_logged: int


LEARNING_STEPS: dict[type, Any] = {}
"""NamedTuple class of an agent's arrays → its compiled learning step."""

K = TypeVar("K")


def learning_step(arrays_class: type) -> Callable[[K], K]:
    """Register the decorated compiled kernel as the learning step of agents whose
    ``learning_arrays()`` are an ``arrays_class``."""

    def register(kernel: K) -> K:
        LEARNING_STEPS[arrays_class] = kernel
        return kernel

    return register


@dispatch_on_type(LEARNING_STEPS)
def learn(
    arrays: Any, settings: Any, counters: np.ndarray, step: Experience, rng: np.random.Generator
) -> None:
    """One learning step: the kernel registered for ``type(arrays)``, from Python or compiled
    code alike."""
    LEARNING_STEPS[type(arrays)](arrays, settings, counters, step, rng)


NO_POSE = np.full(3, -1.0)
"""``Experience.pose`` of an env that gives none (read, never written, by the kernels)."""
NO_LOG_ROWS = np.zeros((0, 6))
"""``Experience.log`` of an env that keeps no kinematic log."""


def experience_from_info(
    state: int,
    action: int,
    reward: float,
    next_state: int,
    terminated: bool,
    info: Mapping[str, Any] | None,
) -> Experience:
    """The :class:`Experience` of a Gymnasium step, from the env's ``info`` by its documented keys
    (``"pose"``, ``"collision"``, ``"kinematic_log"``, see :mod:`skidnav.envs.navigation`); an
    env without them (e.g. a grid maze) gives no pose, no collision and no log."""
    info = info or {}
    pose = np.array(info["pose"], dtype=np.float64) if "pose" in info else NO_POSE
    log = info.get("kinematic_log")
    if log is None:
        rows, n_logged = NO_LOG_ROWS, NO_LOG
    else:
        rows = np.ascontiguousarray(log, dtype=np.float64).reshape(-1, 6)
        n_logged = rows.shape[0]
    return Experience(
        int(state), int(action), float(reward), int(next_state), bool(terminated),
        bool(info.get("collision", False)), pose, rows, n_logged,
    )  # fmt: skip
