"""``gymnasium.make_vec("skidnav/SkidSteerNav-v0", num_envs=N, ...)``: N robots in one compiled
step.

The vector env of Gymnasium's API (``gymnasium.vector.VectorEnv``) whose sub-envs are N copies of
:class:`~skidnav.envs.navigation.SkidSteerNavEnv` built from the same arguments — one arena, one
slip field — each with its own pose, slip clock, wheel-speed statistics, random stream and
episode counter. A step moves all of them through :func:`skidnav.sim.vector_step.vector_step`
(one crossing into compiled code), and gives the numbers N single envs of ``gymnasium.make`` give
in a ``SyncVectorEnv`` under the same seeds, step for step (tested):

* **seeds**: ``reset(seed=s)`` seeds sub-env i with s + i (a list gives one seed each), each
  stream drawn as ``gymnasium.make`` would (``gymnasium.utils.seeding.np_random``); a seeded
  reset restarts that sub-env's slip clock and statistics, as the single env's does;
* **autoreset** (``AutoresetMode.NEXT_STEP``, Gymnasium's default): a sub-env whose episode
  ended (goal, or ``max_episode_steps`` actions: the ``TimeLimit`` rule) is reset by the next
  ``step``, which ignores its action and returns its start observation with reward 0 and
  neither flag; ``reset(options={"reset_mask": mask})`` resets only the masked sub-envs;
* **infos**: ``pose`` (N, 3), ``collision`` (N,), ``wheel_speeds`` (N, 2), ``region`` (N,),
  each with its ``_``-prefixed mask (Gymnasium's vector convention); the single env's kinematic
  log is not gathered (it differs in length from step to step, which a ``SyncVectorEnv``
  cannot gather either: :class:`GatheredInfo` keeps a single env's infos to these keys).

Discrete (``Discrete(4)``) and continuous (``action="continuous"``: wheel speeds, clipped to the
box) actions, and every observation kind. What the compiled step does not simulate — the MuJoCo
robot (``dynamics="mujoco"``) or rendering — gets a ``SyncVectorEnv`` of single envs instead
(:class:`GatheredInfo`), with the same API.

>>> import gymnasium, numpy as np, skidnav
>>> envs = gymnasium.make_vec("skidnav/SkidSteerNav-v0", num_envs=3, map_kind="free")
>>> type(envs).__name__, envs.action_space
('SkidSteerNavVectorEnv', MultiDiscrete([4 4 4]))
>>> observations, infos = envs.reset(seed=0)
>>> observations, rewards, terminated, truncated, infos = envs.step(np.array([0, 2, 3]))
>>> rewards.round(3).tolist(), infos["pose"].shape
([-1.0, -1.0, -1.0], (3, 3))
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from skidnav.checks import check_integer
from skidnav.envs.navigation import SkidSteerNavEnv
from skidnav.envs.registration import ENV_ID
from skidnav.errors import shown
from skidnav.robot.kinematics import commanded_wheel_speeds, real_values
from skidnav.sim.vector_step import (
    DISCRETE_OBSERVATION,
    FEATURE_OBSERVATION,
    POSE_OBSERVATION,
    observe_poses,
    vector_step,
)

VECTOR_INFO_KEYS = ("pose", "collision", "wheel_speeds", "region")
"""The step-info keys a vector env gathers (the others vary in shape or are objects)."""
NOISE_ACTIONS = 32
"""Actions' worth of uniforms drawn at once from each sub-env's stream (the same numbers, in the
same order, as one draw per action: Generator.random fills an array from the stream in order)."""
OBSERVATION_CODES = {
    "discrete": DISCRETE_OBSERVATION,
    "pose": POSE_OBSERVATION,
    "features": FEATURE_OBSERVATION,
}
MAX_NUM_ENVS = 2**24
"""Most sub-envs of one vector env, on either path (on the compiled one
:data:`MAX_VECTOR_BYTES` binds first: a robot takes at least 2.8 kB)."""
MAX_VECTOR_BYTES = 4 * 2**30
"""Most memory [bytes] the per-robot state of a compiled vector env may take
(:func:`robot_bytes` × N). The policy search's cap on all of its memory is as large, with a
larger estimate per sub-env, so every search it accepts gets its vector envs."""


def make_vector_env(
    num_envs: int, max_episode_steps: int | None = None, **kwargs: Any
) -> VectorEnv[Any, Any, Any]:
    """The vector entry point of ``skidnav/SkidSteerNav-v0`` (``gymnasium.make_vec``):
    :class:`SkidSteerNavVectorEnv`, or a ``SyncVectorEnv`` of single envs for what it does not
    simulate (``dynamics="mujoco"``, a ``render_mode``). ``max_episode_steps`` as for
    ``gymnasium.make``, on either path: None the registered limit, −1 no limit. ValueError for
    ``num_envs`` outside [1, :data:`MAX_NUM_ENVS`]."""
    check_integer("num_envs", num_envs, 1, MAX_NUM_ENVS)
    if kwargs.get("dynamics", "kinematic") != "kinematic" or kwargs.get("render_mode"):
        single = {"max_episode_steps": max_episode_steps, **kwargs}
        return gymnasium.vector.SyncVectorEnv(
            [lambda: GatheredInfo(gymnasium.make(ENV_ID, **single))] * num_envs
        )
    if max_episode_steps is None:
        max_episode_steps = gymnasium.spec(ENV_ID).max_episode_steps
    limit = None if max_episode_steps == -1 else max_episode_steps
    return SkidSteerNavVectorEnv(num_envs, limit, **kwargs)


def robot_bytes(template: SkidSteerNavEnv) -> int:
    """Memory [bytes] a compiled vector env of ``template``'s sub-envs holds per robot: float64
    arrays of 2 · :data:`NOISE_ACTIONS` uniforms per sub-step of an action, the slip
    statistics, the observation and 16 scalars, and 1 KiB for its random generator."""
    shape = template.observation_space.shape or (1,)
    floats = 2 * NOISE_ACTIONS * template.robot.substeps + template.task.variance_stats.size
    return 8 * (floats + int(np.prod(shape)) + 16) + 1024


class GatheredInfo(gymnasium.Wrapper[Any, Any, Any, Any]):
    """A single env whose infos hold only :data:`VECTOR_INFO_KEYS`, so that a ``SyncVectorEnv``
    can gather them (its kinematic logs differ in length from step to step):
    ``gymnasium.make_vec(..., vectorization_mode="sync", wrappers=[GatheredInfo])``."""

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        observation, info = self.env.reset(**kwargs)
        return observation, {key: info[key] for key in VECTOR_INFO_KEYS}

    def step(self, action: Any) -> tuple[Any, Any, bool, bool, dict[str, Any]]:
        observation, reward, terminated, truncated, info = self.env.step(action)
        return observation, reward, terminated, truncated, {k: info[k] for k in VECTOR_INFO_KEYS}


class SkidSteerNavVectorEnv(VectorEnv[Any, Any, Any]):
    """N navigation robots stepped together (module doc).

    Args:
        num_envs: N in [1, :data:`MAX_NUM_ENVS`], with N × :func:`robot_bytes` at most
            :data:`MAX_VECTOR_BYTES`. max_episode_steps: actions per episode before truncation
            (None: no limit; ``gymnasium.make_vec`` passes the registered 500). kwargs: the
            arguments of :class:`SkidSteerNavEnv` (``dynamics="kinematic"``, no
            ``render_mode``).
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP}  # noqa: RUF012

    def __init__(self, num_envs: int, max_episode_steps: int | None = None, **kwargs: Any):
        check_integer("num_envs", num_envs, 1, MAX_NUM_ENVS)
        if max_episode_steps is not None:
            check_integer("max_episode_steps", max_episode_steps, 1)
        template = SkidSteerNavEnv(**kwargs)
        if template.dynamics != "kinematic" or template.render_mode is not None:
            raise ValueError("the compiled vector env simulates the kinematic robot, unrendered")
        needed = num_envs * robot_bytes(template)
        if needed > MAX_VECTOR_BYTES:
            raise ValueError(
                f"expected a vector env of at most {MAX_VECTOR_BYTES / 2**30:g} GiB, got about "
                f"{needed / 2**30:.3g} GiB for num_envs {num_envs} at "
                f"{template.robot.substeps} sub-steps per action"
            )
        self.template, self.num_envs = template, num_envs
        self.max_episode_steps = max_episode_steps
        self.single_observation_space = template.observation_space
        self.single_action_space = template.action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._kind = OBSERVATION_CODES[template.observation_kind]
        features = template.features
        self._geometry = (*features.arena, *features.goal, features.lidar_range)
        speed = template.robot.wheel_speed
        self._commands_of = np.array([commanded_wheel_speeds(a, speed) for a in range(4)])
        self._allocate(template)
        self._rngs: list[np.random.Generator | None] = [None] * num_envs

    def _allocate(self, template: SkidSteerNavEnv) -> None:
        """The per-robot state arrays (see :func:`vector_step` for shapes)."""
        n, substeps = self.num_envs, template.robot.substeps
        self._start = template.start_pose()
        self._poses = np.tile(self._start, (n, 1))
        self._times = np.zeros(n)
        self._stats = np.zeros((n, *template.task.variance_stats.shape))
        self._noise = np.zeros((n, NOISE_ACTIONS, 2 * substeps))
        self._noise_used = np.full(n, NOISE_ACTIONS, dtype=np.int64)
        self._elapsed = np.zeros(n, dtype=np.int64)
        self._autoreset = np.zeros(n, dtype=np.bool_)
        self._rewards = np.zeros(n)
        self._terminated = np.zeros(n, dtype=np.bool_)
        self._collided = np.zeros(n, dtype=np.bool_)
        self._regions = np.zeros(n, dtype=np.int64)
        self._wheel_speeds = np.zeros((n, 2))
        shape = self.single_observation_space.shape or ()
        self._observations = np.zeros((n, int(np.prod(shape)) if shape else 1))

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Reset every sub-env (or those of ``options["reset_mask"]``), seeding sub-env i with
        ``seed + i`` (or ``seed[i]``); returns the observations and infos of all."""
        mask = self._reset_mask(options)
        seeds = self._seeds(seed)
        for k in np.flatnonzero(mask).tolist():
            if seeds[k] is not None or self._rngs[k] is None:
                self._rngs[k], _ = seeding.np_random(seeds[k])
                self._noise_used[k] = NOISE_ACTIONS  # a new stream: nothing drawn from it yet
            if seeds[k] is not None:
                self._times[k] = 0.0
                self._stats[k] = 0.0
        if seed is not None:
            self._np_random, self._np_random_seed = seeding.np_random(
                seed if isinstance(seed, int) else None
            )
        self._restart(mask)
        self._autoreset[mask] = False
        self._rewards[mask] = 0.0
        return self._outputs()[0], self._infos(mask)

    def _reset_mask(self, options: dict[str, Any] | None) -> np.ndarray:
        """The sub-envs a reset applies to: all, or ``options["reset_mask"]`` bool (N,)."""
        if options is None or "reset_mask" not in options:
            return np.ones(self.num_envs, dtype=np.bool_)
        mask = np.asarray(options["reset_mask"])
        if mask.dtype != np.bool_ or mask.shape != (self.num_envs,):
            raise ValueError(f"expected reset_mask to be bool ({self.num_envs},), got {mask!r}")
        return mask

    def _seeds(self, seed: int | list[int | None] | None) -> list[int | None]:
        """One seed (or None) per sub-env from ``reset``'s ``seed``."""
        if seed is None:
            return [None] * self.num_envs
        if isinstance(seed, int) and not isinstance(seed, bool):
            return [seed + k for k in range(self.num_envs)]
        if isinstance(seed, list | tuple) and len(seed) == self.num_envs:
            return list(seed)
        raise ValueError(f"expected seed to be None, an int or {self.num_envs} seeds, got {seed!r}")

    def _restart(self, mask: np.ndarray) -> None:
        """Put the masked robots at the start, their episodes at step 0, and observe them."""
        self._poses[mask] = self._start
        self._elapsed[mask] = 0
        self._terminated[mask] = False
        self._collided[mask] = False
        self._wheel_speeds[mask] = 0.0
        x, y, _ = self._start.tolist()
        self._regions[mask] = self.template.discretization.region(x, y)
        task = self.template.task
        observe_poses(task, self._poses, mask, self._kind, self._geometry, self._observations)

    def step(self, actions: Any) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """One action per sub-env; sub-envs whose episode ended last step are reset instead."""
        commands = self._commands(actions)
        active = ~self._autoreset
        for k in np.flatnonzero(active & (self._noise_used == NOISE_ACTIONS)).tolist():
            rng = self._rngs[k]
            if rng is None:
                raise gymnasium.error.ResetNeeded("call reset before step")
            rng.random(out=self._noise[k])  # the single env's next draws, in its order
            self._noise_used[k] = 0
        restarted = self._autoreset  # replaced below, never written in place
        if restarted.any():  # most steps restart no one: skip the masked writes and the call
            self._restart(restarted)
            self._rewards[restarted] = 0.0
        vector_step(
            self.template.task, self._stats, self._poses, self._times, commands, self._noise,
            self._noise_used, active, self._kind, self._geometry, self._rewards,
            self._terminated, self._collided, self._regions, self._wheel_speeds,
            self._observations,
        )  # fmt: skip
        self._times[active] += self.template.robot.action_duration
        self._elapsed[active] += 1
        observations, truncated = self._outputs()
        self._autoreset = self._terminated | truncated
        infos = self._infos(np.ones(self.num_envs, dtype=np.bool_))
        return observations, self._rewards.copy(), self._terminated.copy(), truncated, infos

    def _commands(self, actions: Any) -> np.ndarray:
        """The wheel speeds float64 (N, 2) [rad/s] of the batch of actions; ValueError for a
        batch the action space does not hold (continuous: clipped to the box)."""
        # Called every step: a message is formatted only on error (the repr of an (N, 2) batch
        # takes several times as long as the compiled step of N robots).
        if self.template.action_kind == "continuous":
            values = real_values(actions)
            if (
                values is None
                or values.shape != (self.num_envs, 2)
                or not np.isfinite(values).all()
            ):
                raise ValueError(
                    f"expected ({self.num_envs}, 2) finite wheel speeds, got {shown(actions)}"
                )
            limit = self.template.robot.wheel_speed
            return np.asarray(np.clip(values, -limit, limit))
        indices = np.asarray(actions)
        valid = indices.shape == (self.num_envs,) and indices.dtype.kind in "iu"
        if not valid or not (indices.min() >= 0 and indices.max() <= 3):
            raise ValueError(
                f"expected {self.num_envs} integer actions in 0..3, got {shown(actions)}"
            )
        return self._commands_of[indices.astype(np.int64)]

    def _outputs(self) -> tuple[np.ndarray, np.ndarray]:
        """(the observations as the batched space holds them, the truncation flags)."""
        if self.max_episode_steps is None:
            truncated = np.zeros(self.num_envs, dtype=np.bool_)
        else:
            truncated = self._elapsed >= self.max_episode_steps
        if self._kind == DISCRETE_OBSERVATION:
            return self._observations[:, 0].astype(np.int64), truncated
        return self._observations.copy(), truncated

    def _infos(self, mask: np.ndarray) -> dict[str, Any]:
        """Pose, collision, wheel speeds and region of the masked sub-envs, with their masks."""
        infos: dict[str, Any] = {}
        values_of = (self._poses, self._collided, self._wheel_speeds, self._regions)
        for key, values in zip(VECTOR_INFO_KEYS, values_of, strict=True):
            infos[key] = values.copy()
            infos[f"_{key}"] = mask.copy()
        return infos
