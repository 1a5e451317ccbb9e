"""What continuity buys: one episode of any policy recorded as a trace, and the trace's metrics.

The thesis's future work asks for continuous wheel speeds because its four discrete actions make
trajectories that jerk between full-speed commands. This module measures that on any policy:
:func:`record_rollout` runs one episode of a policy (a callable observation → action; adapters
:func:`tabular_policy` for a tabular agent's greedy action, :func:`wheel_speed_policy` for a
:class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy` on ``action="continuous"``) and
returns a :class:`Trace`; :func:`trace_metrics` turns a trace into the numbers below;
:func:`aggregate` and :func:`comparison_table` average them over many traces with bootstrap
intervals (:mod:`skidnav.statistics.intervals`). Definitions, T being the number of actions of the
trace, Δt its
control period [s], p_t = (x_t, y_t, ψ_t) its poses (t = 0 … T) and ω_t = (ω_L,t, ω_R,t) its
commanded wheel speeds (t = 0 … T − 1); docs/continuity.md says why each one.

1. **success**: 1 if the episode terminated (the goal was reached), else 0.
2. **time to goal** [s]: T · Δt for a success; NaN for a failure (so means are over successes).
3. **path length** [m]: Σ_t ‖(x_t+1, y_t+1) − (x_t, y_t)‖, straight segments between the
   recorded poses (:func:`skidnav.experiments.metrics.path_length`).
4. **wheel change** [rad/s]: mean |Δω| = 1 / (2 (T − 1)) · Σ_t=1…T−1 (|ω_L,t − ω_L,t−1| +
   |ω_R,t − ω_R,t−1|), the mean over both wheels and the T − 1 transitions between consecutive
   control periods; NaN for T < 2.
5. **heading reversals per metre** [1/m]: the heading rate of period t is
   r_t = wrap(ψ_t+1 − ψ_t) / Δt [rad/s] (wrap to [−π, π]: exact while a period turns less than
   π); rates with |r_t| < ``reversal_threshold`` (default :data:`REVERSAL_THRESHOLD`) count as
   straight and are left out; a reversal is a sign change between consecutive remaining rates;
   their count over the path length. NaN for a path of length 0.
6. **energy** [rad²/s]: Σ_t (ω_L,t² + ω_R,t²) · Δt of the commands (a proxy: motor power grows
   with the square of the wheel speed).
7. **collisions**: actions that ran into a wall (``info["collision"]``).

>>> trace = Trace(
...     poses=np.array([[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0.3, 0.4, 0.0]]),
...     commands=np.array([[1.7, 1.7], [-1.7, 1.7]]),
...     control_period=1.0, rewards=np.array([-1.0, 10.0]), collisions=np.zeros(2, bool),
...     terminated=True, truncated=False)
>>> m = trace_metrics(trace)
>>> m.success, m.time_to_goal, round(m.path_length, 12), m.wheel_change, round(m.energy, 12)
(1.0, 2.0, 0.7, 1.7, 11.56)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any, NamedTuple

import gymnasium
import numpy as np
import pandas as pd

from skidnav.agents.greedy import Greedy, as_state, start_rollout
from skidnav.agents.wheel_policy import WheelSpeedPolicy
from skidnav.experiments.metrics import path_length
from skidnav.statistics.intervals import Interval, bootstrap_interval

Policy = Callable[[Any], Any]
"""A deterministic policy: the env's observation → an action of the env's action space."""

REVERSAL_THRESHOLD = 0.05
"""Heading rates [rad/s] below this in magnitude count as straight for heading reversals: about
4 × the largest drift of a forward action on the ``slippery`` preset (0.014 rad/s) and a twelfth
of a full-speed turn (≈ 0.6 rad/s)."""


class Trace(NamedTuple):
    """One recorded episode (T actions).

    Attributes:
        poses: float64 (T + 1, 3), (x [m], y [m], heading [rad]) after reset and after each
            action (``info["pose"]``).
        commands: float64 (T, 2), the commanded wheel speeds (ω_L, ω_R) [rad/s] of each action
            (``env.unwrapped.wheel_commands``: clipped to the box, before slip).
        control_period: Δt, the duration of one action [s].
        rewards: float64 (T,).
        collisions: bool (T,), True where the action ran into a wall.
        terminated: the goal was reached.
        truncated: the episode was cut by the time limit (the env's or ``max_steps``).
    """

    poses: np.ndarray
    commands: np.ndarray
    control_period: float
    rewards: np.ndarray
    collisions: np.ndarray
    terminated: bool
    truncated: bool

    @property
    def n_actions(self) -> int:
        """T, the number of actions."""
        return len(self.commands)


class TraceMetrics(NamedTuple):
    """The metrics of one trace (module doc, items 1–7)."""

    success: float
    time_to_goal: float
    """[s], NaN unless the goal was reached."""
    path_length: float
    """[m]."""
    wheel_change: float
    """Mean |Δω| [rad/s], NaN for fewer than 2 actions."""
    reversals_per_metre: float
    """[1/m], NaN for a path of length 0."""
    energy: float
    """[rad²/s]."""
    collisions: float


METRIC_UNITS = {
    "success": "",
    "time_to_goal": "s",
    "path_length": "m",
    "wheel_change": "rad/s",
    "reversals_per_metre": "1/m",
    "energy": "rad²/s",
    "collisions": "",
}
"""Unit of each field of :class:`TraceMetrics`."""


class GreedyPolicy:
    """The greedy policy of an agent as a :data:`Policy`: its ``greedy_action`` in the
    observation's state (:func:`~skidnav.agents.greedy.as_state`), an int for Discrete actions,
    float64 wheel speeds (2,) [rad/s] for Box ones. An agent whose greedy policy keeps a state
    within a rollout (:class:`~skidnav.agents.greedy.RolloutState`, ``mppi-kinematic``'s
    frozen planner) forgets it when :func:`record_rollout` starts one."""

    def __init__(self, agent: Greedy) -> None:
        self.agent = agent

    def __call__(self, observation: Any) -> Any:
        action = self.agent.greedy_action(as_state(observation))
        return int(action) if np.ndim(action) == 0 else np.asarray(action, dtype=np.float64)

    def start_greedy_rollout(self) -> None:
        """A rollout starts (:func:`~skidnav.agents.greedy.start_rollout` of the agent)."""
        start_rollout(self.agent)


def tabular_policy(agent: Greedy) -> Policy:
    """The greedy policy of a tabular agent, or of any agent with ``greedy_action``
    (:class:`GreedyPolicy`)."""
    return GreedyPolicy(agent)


def wheel_speed_policy(policy: WheelSpeedPolicy, env: gymnasium.Env[Any, Any]) -> Policy:
    """``policy``'s wheel speeds as the action (float64 (2,) [rad/s]: float32 would round them)
    of ``env``; ValueError unless ``env`` takes continuous actions and observes the features
    with the policy's ``lidar_rays`` and ``lidar_range``."""
    nav = env.unwrapped
    wanted = ("continuous", "features", policy.lidar_rays, float(policy.lidar_range))
    features = getattr(nav, "features", None)
    got = (
        getattr(nav, "action_kind", None),
        getattr(nav, "observation_kind", None),
        getattr(features, "lidar_rays", None),
        getattr(features, "lidar_range", None),
    )
    if got != wanted:
        raise ValueError(
            "expected an env with (action, observation, lidar_rays, lidar_range) = "
            f"{wanted}, got {got}"
        )

    return WheelSpeeds(policy)


class WheelSpeeds:
    """A :class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy` as a :data:`Policy`
    (:func:`wheel_speed_policy`); a policy with a state of its own within a rollout forgets it
    when :func:`record_rollout` starts one."""

    def __init__(self, policy: WheelSpeedPolicy) -> None:
        self.policy = policy

    def __call__(self, observation: Any) -> np.ndarray:
        return np.asarray(self.policy.wheel_speeds(observation), dtype=np.float64)

    def start_greedy_rollout(self) -> None:
        """A rollout starts (:func:`~skidnav.agents.greedy.start_rollout` of the policy)."""
        start_rollout(self.policy)


def _step_limit(env: gymnasium.Env[Any, Any], max_steps: int | None) -> int:
    """``max_steps``, else the env's time limit; ValueError if neither exists or it is < 1."""
    limit = max_steps
    if limit is None and env.spec is not None:
        limit = env.spec.max_episode_steps
    if limit is None or limit < 1:
        raise ValueError(f"expected max_steps >= 1 for an env without a time limit, got {limit}")
    return int(limit)


def record_rollout(
    env: gymnasium.Env[Any, Any],
    policy: Policy,
    *,
    seed: int | None = None,
    max_steps: int | None = None,
) -> Trace:
    """Run one episode of ``policy`` from ``env.reset(seed=seed)`` and record it.

    The episode ends when the env terminates or truncates, or after ``max_steps`` actions
    (default: the env's time limit, ``env.spec.max_episode_steps``; ValueError if it has none),
    which counts as truncated. Nothing is learned; the policy is called once per action, after
    it forgot any state of its own (:func:`~skidnav.agents.greedy.start_rollout`).
    """
    limit = _step_limit(env, max_steps)
    nav: Any = env.unwrapped  # a SkidSteerNavEnv, or any env with its wheel_commands and robot
    observation, info = env.reset(seed=seed)
    start_rollout(policy)
    poses, commands, rewards, collisions = [info["pose"]], [], [], []
    terminated = truncated = False
    while not (terminated or truncated):
        action = policy(observation)
        commands.append(nav.wheel_commands(action))
        observation, reward, terminated, truncated, info = env.step(action)
        poses.append(info["pose"])
        rewards.append(float(reward))
        collisions.append(bool(info.get("collision", False)))
        truncated = bool(truncated) or (len(rewards) >= limit and not terminated)
    return Trace(
        poses=np.asarray(poses, dtype=np.float64).reshape(-1, 3),
        commands=np.asarray(commands, dtype=np.float64).reshape(-1, 2),
        control_period=float(nav.robot.action_duration),
        rewards=np.asarray(rewards, dtype=np.float64),
        collisions=np.asarray(collisions, dtype=np.bool_),
        terminated=bool(terminated),
        truncated=bool(truncated),
    )


def check_trace(trace: Trace) -> None:
    """ValueError unless the trace's arrays have consistent shapes (poses (T + 1, 3) with T ≥ 0,
    commands (T, 2), rewards and collisions (T,)) and its control period is finite and > 0."""
    n = len(trace.poses) - 1  # the poses count the actions: the other arrays must agree
    shapes = {
        "poses": (np.shape(trace.poses), (max(n, 0) + 1, 3)),
        "commands": (np.shape(trace.commands), (n, 2)),
        "rewards": (np.shape(trace.rewards), (n,)),
        "collisions": (np.shape(trace.collisions), (n,)),
    }
    for name, (got, wanted) in shapes.items():
        if got != wanted:
            raise ValueError(f"expected {name} of shape {wanted}, got {got}")
    if not (math.isfinite(trace.control_period) and trace.control_period > 0):
        raise ValueError(f"expected a control period > 0 s, got {trace.control_period!r}")


def wheel_change(commands: np.ndarray) -> float:
    """Mean |Δω| [rad/s] over both wheels and the T − 1 transitions of ``commands`` (T, 2)
    [rad/s] (module doc, item 4); NaN for T < 2.

    >>> wheel_change(np.array([[1.7, 1.7], [-1.7, 1.7], [1.7, 1.7]]))
    1.7
    """
    commands = np.asarray(commands, dtype=np.float64)
    if len(commands) < 2:
        return math.nan
    return float(np.abs(np.diff(commands, axis=0)).mean())


def heading_rates(poses: np.ndarray, control_period: float) -> np.ndarray:
    """Heading rate [rad/s] of each control period, wrap(ψ_t+1 − ψ_t) / Δt, shape (T,), of
    ``poses`` (T + 1, 3) [m, m, rad]; ``control_period`` Δt [s]."""
    turn = np.diff(np.asarray(poses, dtype=np.float64)[:, 2])
    return np.asarray(np.arctan2(np.sin(turn), np.cos(turn)) / control_period)


def heading_reversals(rates: np.ndarray, threshold: float = REVERSAL_THRESHOLD) -> int:
    """Sign changes between consecutive heading ``rates`` [rad/s] whose magnitude is at least
    ``threshold`` [rad/s] (smaller ones are left out: straight driving separates no turns).

    >>> heading_reversals(np.array([0.6, 0.0, 0.6, -0.6, 0.01, 0.6]))
    2
    """
    rates = np.asarray(rates, dtype=np.float64)
    signs = np.sign(rates[np.abs(rates) >= threshold])
    return int(np.count_nonzero(signs[1:] != signs[:-1]))


def energy(commands: np.ndarray, control_period: float) -> float:
    """Σ_t (ω_L,t² + ω_R,t²) · Δt [rad²/s] of ``commands`` (T, 2) [rad/s] held for
    ``control_period`` Δt [s] each."""
    return float(np.square(np.asarray(commands, dtype=np.float64)).sum() * control_period)


def trace_metrics(trace: Trace, *, reversal_threshold: float = REVERSAL_THRESHOLD) -> TraceMetrics:
    """The metrics of one trace (module doc); ValueError for an inconsistent trace."""
    check_trace(trace)
    length = path_length(trace.poses)
    reversals = heading_reversals(
        heading_rates(trace.poses, trace.control_period), reversal_threshold
    )
    return TraceMetrics(
        success=1.0 if trace.terminated else 0.0,
        time_to_goal=trace.n_actions * trace.control_period if trace.terminated else math.nan,
        path_length=length,
        wheel_change=wheel_change(trace.commands),
        reversals_per_metre=reversals / length if length > 0 else math.nan,
        energy=energy(trace.commands, trace.control_period),
        collisions=float(np.count_nonzero(trace.collisions)),
    )


def metric_rows(
    traces: Sequence[Trace], *, reversal_threshold: float = REVERSAL_THRESHOLD
) -> np.ndarray:
    """The metrics of each trace, float64 (n_traces, 7), columns in :class:`TraceMetrics`
    order."""
    rows = [trace_metrics(trace, reversal_threshold=reversal_threshold) for trace in traces]
    return np.array(rows, dtype=np.float64).reshape(-1, len(TraceMetrics._fields))


def aggregate(
    traces: Sequence[Trace],
    rng: np.random.Generator,
    *,
    confidence: float = 0.95,
    reversal_threshold: float = REVERSAL_THRESHOLD,
) -> dict[str, Interval]:
    """Mean of each metric over ``traces`` with its percentile-bootstrap interval
    (:func:`~skidnav.statistics.intervals.bootstrap_interval`, traces resampled, resamples drawn
    from ``rng``).
    A metric's NaN values are left out (time to goal: the mean over successes)."""
    rows = metric_rows(traces, reversal_threshold=reversal_threshold)
    return _intervals(rows, rng, confidence)


def _intervals(
    rows: np.ndarray, rng: np.random.Generator, confidence: float
) -> dict[str, Interval]:
    return {
        name: bootstrap_interval(rows[:, column], rng, confidence=confidence)
        for column, name in enumerate(TraceMetrics._fields)
    }


def comparison_table(
    traces: Mapping[str, Sequence[Trace]],
    rng: np.random.Generator,
    *,
    confidence: float = 0.95,
    reversal_threshold: float = REVERSAL_THRESHOLD,
) -> pd.DataFrame:
    """One row per policy (the keys of ``traces``, in order) and metric: columns ``policy``,
    ``metric``, ``unit``, ``n`` (traces where the metric is defined), ``mean``, ``low``,
    ``high`` (:func:`aggregate`; the policies' resamples drawn from ``rng`` in turn)."""
    rows = []
    for policy, policy_traces in traces.items():
        values = metric_rows(policy_traces, reversal_threshold=reversal_threshold)
        intervals = _intervals(values, rng, confidence)
        for column, (name, interval) in enumerate(intervals.items()):
            rows.append(
                {
                    "policy": policy, "metric": name, "unit": METRIC_UNITS[name],
                    "n": int(np.isfinite(values[:, column]).sum()),
                    "mean": interval.estimate, "low": interval.low, "high": interval.high,
                }
            )  # fmt: skip
    return pd.DataFrame(rows, columns=["policy", "metric", "unit", "n", "mean", "low", "high"])
