"""Being told of each training episode as it ends, and stopping training early.

Every family's loop records its episodes in one place
(:class:`~skidnav.agents.training.LogRows`), so a callback is heard there, whatever the family:
:func:`listening` makes ``callback`` the listener of the trainings started inside it (a context
variable: nothing else is passed through the trainers), and each recorded episode calls it with
an :class:`EpisodeInfo`. Returning ``False`` or raising :class:`StopTraining` stops the training
after that episode (as Stable-Baselines3's ``BaseCallback._on_step`` returning ``False`` stops
``learn``); the loop then returns the log of the episodes run. A callback that never stops
changes nothing: it draws no random number and the log is the same.

The compiled tabular trainer hears of each episode too: it returns to Python between episodes
(the ε decay and the greedy evaluation), so the call costs one Python call per episode.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable, Iterator
from contextvars import ContextVar
from typing import NamedTuple


class StopTraining(Exception):
    """Raised by a training callback to stop the training after the episode it was told of."""


class EpisodeInfo(NamedTuple):
    """What a training callback is told after each episode."""

    episode: int
    """The episode's number in this training, from 1 (as ``convergence_episode`` counts)."""
    length: int
    """Actions taken."""
    total: float
    """Its return: the undiscounted sum of rewards."""
    success: bool
    """True if it reached the goal (terminated) rather than being cut."""
    wall_time: float
    """Seconds of computing in the episode, greedy evaluation excluded [s]."""
    elapsed: float
    """Seconds since the training started, evaluations included [s]."""
    driving: float
    """Simulated seconds the robot drove in the episode (its length × the env's control
    period) [s]; NaN for an env without a control period."""


EpisodeCallback = Callable[[EpisodeInfo], object]
"""A training callback: ``False`` (or raising :class:`StopTraining`) stops; anything else
(``None``, ``True``) goes on."""


class Listener:
    """The callback of the trainings under way, with the clock and control period it reports."""

    def __init__(self, callback: EpisodeCallback, seconds_per_action: float) -> None:
        self.callback, self.seconds_per_action = callback, seconds_per_action
        self.start = time.perf_counter()

    def tell(
        self, episode: int, length: int, total: float, success: bool, wall_time: float
    ) -> bool:
        """Tell the callback of an episode; True if it asks to stop."""
        info = EpisodeInfo(
            episode, int(length), float(total), bool(success), float(wall_time),
            time.perf_counter() - self.start, int(length) * self.seconds_per_action,
        )  # fmt: skip
        try:
            return self.callback(info) is False
        except StopTraining:
            return True


_LISTENER: ContextVar[Listener | None] = ContextVar("skidnav_training_listener", default=None)


def current_listener() -> Listener | None:
    """The listener of the trainings started now (None outside :func:`listening`)."""
    return _LISTENER.get()


@contextlib.contextmanager
def listening(
    callback: EpisodeCallback, seconds_per_action: float = math.nan
) -> Iterator[Listener]:
    """Within the block, every training started calls ``callback`` after each episode
    (``seconds_per_action`` [s]: the env's control period, for :attr:`EpisodeInfo.driving`)."""
    listener = Listener(callback, seconds_per_action)
    token = _LISTENER.set(listener)
    try:
        yield listener
    finally:
        _LISTENER.reset(token)
