"""Learning off the control path: a worker thread feeds each real step to an agent that plans on
copies of what it learned (``mppi-kinematic`` on the robot, :mod:`.mppi_loop`;
docs/robot-learning.md).

The control path never waits for learning. Each control period it reads :attr:`BackgroundLearner.
view` (one attribute read: the newest published copy of the dynamics and the cost map) and
hands the step it just drove to :meth:`BackgroundLearner.submit` (a queue put). The worker
thread takes the steps in order and, holding :attr:`BackgroundLearner.lock`, lets the agent
learn from each (``agent.observe``: the kinematic log into the model, refitted on its schedule,
the path, collision and laser readings into the map, the cost map and its lattice recomputed
when they changed); whenever the model was refitted or the cost map recomputed, it publishes a
fresh copy (``agent.planning_view()``) by replacing :attr:`view`, which the control path picks up
at its next period. The compiled kernels release the GIL (:func:`skidnav._jit.jit`), and the
worker runs at a lower scheduling priority where the system allows it (Linux: a niceness of
:data:`WORKER_NICENESS` for its thread), so a refit or a recompute does not delay a period.

Between episodes (the wheels stopped) :meth:`BackgroundLearner.drain` waits until every step
submitted has been learned, so the checkpoint holds all of them. A step that makes the agent
raise stops the worker and calls ``on_failure`` with the reason (the loop trips its safety
monitor: the robot stops and the run ends).
"""

from __future__ import annotations

import logging
import os
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

from skidnav.errors import first_line

log = logging.getLogger(__name__)

WORKER_NICENESS = 10
"""Niceness added to the worker thread (Linux): the control path, the driver's reader and the
watchdog win the CPU when it is short."""


class Step(NamedTuple):
    """One real step as ``agent.observe`` takes it."""

    observation: Any
    action: Any
    reward: float
    next_observation: Any
    terminated: bool
    truncated: bool
    info: dict[str, Any]


@dataclass
class LearnerStats:
    """What the worker did.

    Attributes:
        steps: steps learned. refits: model refits. recomputes: cost-map recomputations.
        published: views published. seconds: time spent learning [s wall].
        longest: the longest single step [s wall]. backlog: the most steps waiting at once.
    """

    steps: int = 0
    refits: int = 0
    recomputes: int = 0
    published: int = 0
    seconds: float = 0.0
    longest: float = 0.0
    backlog: int = 0


class BackgroundLearner:
    """Feeds submitted steps to ``agent`` in a worker thread (module doc).

    Args:
        agent: an agent with ``observe``, ``planning_view()``, ``model.refits`` and
            ``evidence.reweighs`` (:class:`~skidnav.agents.mpc.agent.MPPIKinematicAgent`).
        record: ``record(event, fields)`` for the run log: a ``"learned"`` record each time a
            view is published.
        on_failure: called once with a one-line reason if the agent raises.
    """

    def __init__(
        self,
        agent: Any,
        record: Callable[[str, dict[str, object]], None],
        on_failure: Callable[[str], None],
    ) -> None:
        self.agent = agent
        self.record, self.on_failure = record, on_failure
        self.lock = threading.Lock()
        """Held while the agent learns; hold it to read or save the agent."""
        self.view = agent.planning_view()
        """The newest published copy of what the planner reads."""
        self.stats = LearnerStats()
        self.failed: str | None = None
        self._queue: queue.Queue[Step | None] = queue.Queue()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        """Start the worker thread."""
        self._thread = threading.Thread(target=self._work, name="background-learner", daemon=True)
        self._thread.start()

    def submit(self, step: Step) -> None:
        """Queue ``step`` to be learned (never blocks; ignored once the worker failed)."""
        if self.failed is None:
            self._queue.put(step)
            self.stats.backlog = max(self.stats.backlog, self._queue.qsize())

    def drain(self) -> None:
        """Wait until every step submitted has been learned (or the worker failed)."""
        self._queue.join()

    def close(self) -> None:
        """Learn what is queued, then end the worker thread."""
        if self._thread is not None:
            self._queue.put(None)
            self._thread.join()
            self._thread = None

    def _work(self) -> None:
        _lower_priority()
        while True:
            step = self._queue.get()
            try:
                if step is None:
                    return
                if self.failed is None:
                    self._learn(step)
            finally:
                self._queue.task_done()

    def _learn(self, step: Step) -> None:
        agent, stats = self.agent, self.stats
        started = time.monotonic()
        try:
            with self.lock:
                refits, recomputes = agent.model.refits, agent.evidence.reweighs
                agent.observe(*step)
                refitted = agent.model.refits > refits
                recomputed = agent.evidence.reweighs > recomputes
                if refitted or recomputed:
                    self.view = agent.planning_view()
        except Exception as error:  # whatever the agent does wrong, the robot must stop
            self.failed = f"policy failed: learning: {first_line(error, 160)}"
            log.error("%s", self.failed)
            log.debug("the learner's failure", exc_info=True)
            self.on_failure(self.failed)
            return
        seconds = time.monotonic() - started
        stats.steps += 1
        stats.refits += int(refitted)
        stats.recomputes += agent.evidence.reweighs - recomputes
        stats.seconds += seconds
        stats.longest = max(stats.longest, seconds)
        if refitted or recomputed:
            stats.published += 1
            self.record(
                "learned",
                {"refit": refitted, "refits": agent.model.refits, "seconds": seconds,
                 "cost_map_recomputes": agent.evidence.reweighs},
            )  # fmt: skip


def _lower_priority() -> None:
    """Raise the calling thread's niceness by :data:`WORKER_NICENESS` where the system allows
    it (Linux threads have their own; elsewhere nothing happens)."""
    try:
        thread = threading.get_native_id()
        current = os.getpriority(os.PRIO_PROCESS, thread)
        os.setpriority(os.PRIO_PROCESS, thread, current + WORKER_NICENESS)
    except (AttributeError, OSError):
        log.debug("the learner runs at the control path's priority")
