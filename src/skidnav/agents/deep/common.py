"""What the Stable-Baselines3 agents (DQN, PPO, SAC) share, written once.

Each agent is a thin subclass of :class:`DeepAgent` that names its config, builds its
Stable-Baselines3 model and says which network acts; everything else lives here:

1. configs: :class:`DeepConfig`, the base of the frozen dataclasses, checks every field's type
   and range on construction and refuses unknown keys of a mapping, each in one line;
2. one root seed per agent (Stable-Baselines3 seeds PyTorch, NumPy and the env from it) and
   PyTorch on one thread (the experiment runner runs one process per core); the global
   generators Stable-Baselines3 explores with are the agent's own, swapped in only while it
   builds or trains (:class:`RandomState`), so agents trained in turn do not share them;
3. observations rescaled from the ``Box`` bounds to [−1, 1] (Gymnasium's ``RescaleObservation``
   in training, its ``rescale_box`` function when acting), so metres and radians reach the
   network on one scale;
4. training by **episodes** (:meth:`DeepAgent.train_episodes`, with the
   :class:`~skidnav.agents.training.Evaluation` of every trainer): a callback records each
   episode's return, length, collisions and success, runs the greedy evaluation, and stops after
   the last episode with Stable-Baselines3's state as if the step had run to its end;
5. saved files that are not pickle (:meth:`DeepAgent.save`, :func:`load_agent`): the acting
   network's weights as float32 arrays in ``.npz`` and the config, spaces, seed and counters in
   ``.json``; loading checks every array's name, dtype and shape against a new network of the
   saved config before any weight is used, and refuses anything else in one line.
"""

from __future__ import annotations

import itertools
import json
import math
import random
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Generic, NamedTuple, Self, TypeVar

import gymnasium
import numpy as np
from gymnasium.wrappers import RescaleObservation
from gymnasium.wrappers.utils import rescale_box

from skidnav.agents.greedy import Rollout
from skidnav.agents.saving import new_save_paths, save_paths
from skidnav.agents.training import (
    NO_EVALUATION,
    Episode,
    Evaluation,
    LogRows,
    TrainingLog,
    plain_evaluations,
)
from skidnav.errors import CorruptFileError, first_line, shown
from skidnav.files.atomic import write_atomic, write_npz_atomic
from skidnav.files.configtables import check_keys
from skidnav.files.saved import READ_ERRORS, ArraySpec, SavedArchive, read_json

if TYPE_CHECKING:
    import torch
    from stable_baselines3.common.base_class import BaseAlgorithm
    from stable_baselines3.common.callbacks import BaseCallback

SAVE_VERSION = 1
MAX_LAYER_WIDTH = 4096
MAX_LAYERS = 8
MAX_TRAINING_STEPS = 10**12
MAX_COUNT = 10**7
"""Upper bound of every integer setting (buffer and rollout sizes, steps): a 10⁷-transition
replay buffer of a 15-dimensional observation is already ~1.2 GB."""
MAX_HIDDEN_WEIGHTS = 1 << 24
"""Weights between the hidden layers of one network at most (64 MiB of float32)."""
"""The step budget handed to Stable-Baselines3: training ends by episodes, not by it."""
MAX_META_BYTES = 1 << 20
"""Largest ``.json`` of a saved agent read [bytes]."""


def hidden_ok(hidden: tuple[int, ...]) -> bool:
    """True for 1 to :data:`MAX_LAYERS` hidden widths, each an int in 1..:data:`MAX_LAYER_WIDTH`,
    with at most :data:`MAX_HIDDEN_WEIGHTS` weights between consecutive hidden layers."""
    shaped = 1 <= len(hidden) <= MAX_LAYERS and all(
        type(width) is int and 1 <= width <= MAX_LAYER_WIDTH for width in hidden
    )
    return shaped and sum(a * b for a, b in itertools.pairwise(hidden)) <= MAX_HIDDEN_WEIGHTS


class DeepConfig:
    """Base of the deep agents' frozen config dataclasses.

    A subclass is a ``@dataclass(frozen=True)`` with Stable-Baselines3's names, ``hidden`` (the
    widths of the hidden layers) among its fields, and :meth:`ranges`. On construction ``hidden``
    becomes a tuple; a field whose default is an int must be an int, one whose default is a
    float a number (bools are neither), and every range must hold:
    ``ValueError("<agent>: <field> = <value> is out of range")`` otherwise.
    """

    agent_name: ClassVar[str] = "deep"
    hidden: tuple[int, ...]

    def ranges(self) -> dict[str, bool]:
        """Per field (``hidden`` excepted), whether its value is in range."""
        raise NotImplementedError

    def __post_init__(self) -> None:
        object.__setattr__(self, "hidden", tuple(self.hidden))
        for field in fields(self):  # type: ignore[arg-type]
            value, default = getattr(self, field.name), field.default
            number = isinstance(value, int | float) and not isinstance(value, bool)
            if type(default) is int and type(value) is not int:
                raise ValueError(
                    f"{self.agent_name}: {field.name} = {shown(value)} is not an integer"
                )
            if type(value) is int and not -MAX_COUNT <= value <= MAX_COUNT:
                raise ValueError(
                    f"{self.agent_name}: {field.name} = {shown(value)} is out of range"
                )
            if isinstance(default, float) and not number:
                raise ValueError(
                    f"{self.agent_name}: {field.name} = {shown(value)} is not a number"
                )
        checks = {**self.ranges(), "hidden": hidden_ok(self.hidden)}
        for name, ok in checks.items():
            value = getattr(self, name)
            if (isinstance(value, float) and not math.isfinite(value)) or not ok:
                raise ValueError(f"{self.agent_name}: {name} = {shown(value)} is out of range")

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any]) -> Self:
        """A config from a mapping (e.g. a TOML table); unknown keys are refused in one line."""
        check_keys(values, sorted(f.name for f in fields(cls)), cls.agent_name)  # type: ignore[arg-type]
        return cls(**values)


ConfigT = TypeVar("ConfigT", bound=DeepConfig)
AgentT = TypeVar("AgentT", bound="DeepAgent[Any]")


def deterministic_action(
    network: Any, scale: Callable[[np.ndarray], np.ndarray], observation: Any
) -> Any:
    """The deterministic action of a Stable-Baselines3 policy ``network`` (its ``predict``) at
    ``observation`` rescaled by ``scale``: the one way every deep agent and frozen policy acts."""
    scaled = scale(np.asarray(observation, dtype=np.float64))
    action, _ = network.predict(scaled, deterministic=True)
    return action


def silent_logger() -> Any:
    """A Stable-Baselines3 logger that writes nothing and creates no folder. Left to itself,
    ``learn`` configures one in a new ``$TMPDIR/SB3-<date>`` folder, empty at verbosity 0, on
    every call."""
    from stable_baselines3.common.logger import Logger

    return Logger(folder=None, output_formats=[])


class DeepAgent(Generic[ConfigT]):
    """A Stable-Baselines3 algorithm on ``env`` (a ``Box`` observation), trained by episodes.

    Subclasses set ``name``, ``config_class``, ``action_space_class`` and define
    :meth:`_build` (the model on the rescaled env) and :meth:`network` (the acting network whose
    weights are saved)."""

    name: ClassVar[str]
    config_class: ClassVar[type[DeepConfig]]
    action_space_class: ClassVar[type[gymnasium.Space[Any]]]

    def __init__(
        self, env: gymnasium.Env[Any, Any], config: ConfigT | None = None, seed: int = 0
    ) -> None:
        import torch

        if not isinstance(env.observation_space, gymnasium.spaces.Box):
            raise ValueError(
                f"{self.name}: expected a Box observation (observation='pose' or 'features')"
            )
        if not isinstance(env.action_space, self.action_space_class):
            kind = "Discrete" if self.action_space_class is gymnasium.spaces.Discrete else "Box"
            raise ValueError(f"{self.name}: expected {kind} actions")
        torch.set_num_threads(1)
        self.scaled = RescaleObservation(env, -1.0, 1.0)  # type: ignore[arg-type]
        self.config: ConfigT = config if config is not None else self.config_class()  # type: ignore[assignment]
        self.seed = seed
        outside = global_random_state()
        self.model: BaseAlgorithm = self._build(self.scaled)
        self.model.set_logger(silent_logger())
        self._random_state = global_random_state()
        set_global_random_state(outside)
        self.episodes = 0

    def _build(self, env: gymnasium.Env[Any, Any]) -> BaseAlgorithm:
        """The Stable-Baselines3 model of this config and seed on ``env`` (rescaled)."""
        raise NotImplementedError

    def network(self) -> torch.nn.Module:
        """The network that acts (a Stable-Baselines3 policy with ``predict``); it is saved."""
        raise NotImplementedError

    def _load_network(self, state: dict[str, torch.Tensor]) -> None:
        """Put saved weights into the acting network."""
        self.network().load_state_dict(state)

    def extra_meta(self) -> dict[str, Any]:
        """What a subclass adds to the saved ``.json`` (nothing here)."""
        return {}

    @property
    def steps(self) -> int:
        """Real steps taken in training."""
        return int(self.model.num_timesteps)

    def scale(self, observation: np.ndarray) -> np.ndarray:
        """``observation`` of the env rescaled to [−1, 1] as the network sees it."""
        return self.scaled.observation(observation)  # type: ignore[no-any-return]

    def greedy_action(self, observation: np.ndarray) -> Any:
        """The acting network's deterministic action at ``observation``."""
        return deterministic_action(self.network(), self.scale, observation)

    def train_episodes(
        self, episodes: int, *, evaluation: Evaluation = NO_EVALUATION, seed: int | None = None
    ) -> TrainingLog:
        """Learn for ``episodes`` more episodes, the greedy policy measured after each by
        ``evaluation`` with the pieces of the one loop
        (:func:`~skidnav.agents.training.train_episodes`): the evaluation env's first reset
        (:meth:`~skidnav.agents.training.Evaluation.start`), the rollouts of
        :func:`~skidnav.agents.training.plain_evaluations`
        (:meth:`~skidnav.agents.training.Evaluation.run`, each cut at
        ``evaluation.limit(None)`` actions: the env's own limit cuts the episodes) and the log
        (:class:`~skidnav.agents.training.LogRows`; ``planning_updates`` 0, wall time without
        the evaluations). ``seed`` seeds this call's first reset (None: Stable-Baselines3
        continues its env).

        Stable-Baselines3 owns the step loop: ``learn`` collects steps across episodes (PPO's
        ``n_steps``, the off-policy ``train_freq``) and trains between collections, so a call
        per episode would change what it learns; a callback records each episode instead
        (:func:`episode_recorder`)."""
        rows = LogRows(evaluation.n_rollouts)
        limit, evaluate = evaluation.limit(None), plain_evaluations(self, evaluation)
        if seed is not None:
            self._reset_env(seed)
        evaluation.start(seed)
        if episodes > 0:
            recorder = episode_recorder(episodes, rows, lambda: evaluation.run(evaluate, limit))
            outside = global_random_state()
            set_global_random_state(self._random_state)
            try:
                self.model.learn(
                    total_timesteps=MAX_TRAINING_STEPS, callback=recorder,
                    reset_num_timesteps=False,
                )  # fmt: skip
            finally:
                self._random_state = global_random_state()
                set_global_random_state(outside)
        self.episodes += len(rows)
        return rows.log()

    def _reset_env(self, seed: int) -> None:
        """Reset the training env with ``seed`` and make its observation the next one
        Stable-Baselines3 acts on (as its ``learn`` does for a model that has not started)."""
        env = self.model.get_env()
        assert env is not None
        env.seed(seed)
        self.model._last_obs = env.reset()  # type: ignore[assignment]
        self.model._last_episode_starts = np.ones((env.num_envs,), dtype=bool)

    def weights(self) -> dict[str, np.ndarray]:
        """The acting network's parameters by name, float32 arrays (copies)."""
        return {
            name: tensor.detach().cpu().numpy().copy()
            for name, tensor in self.network().state_dict().items()
        }

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write ``path.npz`` (the acting network's weights) and ``path.json`` (config, spaces,
        seed, counters), each atomically. Returns both paths."""
        npz_path, json_path = new_save_paths(path)
        write_npz_atomic(npz_path, self.weights(), compress=True)
        space = self.scaled.env.observation_space
        assert isinstance(space, gymnasium.spaces.Box)
        meta = {
            "format": f"skidnav-{self.name}",
            "version": SAVE_VERSION,
            "agent": self.name,
            "config": asdict(self.config),  # type: ignore[call-overload]
            "observation_low": space.low.astype(np.float64).tolist(),
            "observation_high": space.high.astype(np.float64).tolist(),
            **action_meta(self.model.action_space),
            **self.extra_meta(),
            "seed": self.seed,
            "counters": {"steps": self.steps, "episodes": self.episodes},
        }
        write_atomic(json_path, json.dumps(meta, indent=1).encode("utf-8"))
        return npz_path, json_path


class RandomState(NamedTuple):
    """The global generators Stable-Baselines3 seeds and draws from (its exploration: PyTorch's
    samples, NumPy's legacy ε-greedy draws, Python's), saved."""

    python: Any
    numpy: Any
    torch: Any


def global_random_state() -> RandomState:
    """The global generators' states now."""
    import torch

    return RandomState(random.getstate(), np.random.get_state(), torch.get_rng_state())


def set_global_random_state(state: RandomState) -> None:
    """Put the global generators in ``state``. An agent keeps its own and swaps it in only
    while it builds or trains, so that two agents (or an agent and other code) drawing in turn
    still give each seed its own results."""
    import torch

    random.setstate(state.python)
    np.random.set_state(state.numpy)
    torch.set_rng_state(state.torch)


def episode_recorder(
    episodes: int, rows: LogRows, evaluate: Callable[[], list[Rollout]]
) -> BaseCallback:
    """A Stable-Baselines3 callback that adds each finished episode to ``rows`` (``evaluate()``
    gives its greedy rollouts) and stops training after ``episodes`` of them, or earlier when a
    training callback asks (:attr:`~skidnav.agents.training.LogRows.stopped`)."""
    from stable_baselines3.common.callbacks import BaseCallback

    class EpisodeRecorder(BaseCallback):
        """Sums the episode under way; records, evaluates and maybe stops at its end."""

        def __init__(self) -> None:
            super().__init__()
            self.total, self.length, self.collisions = 0.0, 0, 0
            self.start = time.perf_counter()

        def _on_step(self) -> bool:
            info = self.locals["infos"][0]
            self.total += float(self.locals["rewards"][0])
            self.length += 1
            self.collisions += int(bool(info.get("collision", False)))
            if not self.locals["dones"][0]:
                return True
            wall_time = time.perf_counter() - self.start
            terminated = not info.get("TimeLimit.truncated", False)
            episode = Episode(self.total, self.length, terminated, self.collisions, 0)
            rows.add(episode, wall_time, evaluate())
            self.total, self.length, self.collisions = 0.0, 0, 0
            self.start = time.perf_counter()
            if len(rows) < episodes and not rows.stopped:
                return True
            finish_step(self.model, self.locals)
            return False

    return EpisodeRecorder()


def finish_step(model: BaseAlgorithm, step: dict[str, Any]) -> None:
    """Do what Stable-Baselines3 does after a step that a callback stopped it before: an
    off-policy model stores the transition (the episode's last, often the goal's) and counts the
    step; an on-policy one takes the new (reset) observation as its next. Without this the next
    :meth:`DeepAgent.train_episodes` would begin from the previous episode's last observation,
    and the replay buffer would never hold the transition that ended each call."""
    from stable_baselines3.common.off_policy_algorithm import OffPolicyAlgorithm

    if isinstance(model, OffPolicyAlgorithm):
        model._store_transition(
            step["replay_buffer"], step["buffer_actions"], step["new_obs"], step["rewards"],
            step["dones"], step["infos"],
        )  # fmt: skip
        model._on_step()
    else:
        model._last_obs = step["new_obs"]
        model._last_episode_starts = step["dones"]


def action_meta(space: gymnasium.Space[Any]) -> dict[str, Any]:
    """The saved description of an action space: ``n_actions``, or the box's bounds."""
    if isinstance(space, gymnasium.spaces.Discrete):
        return {"n_actions": int(space.n)}
    assert isinstance(space, gymnasium.spaces.Box)
    return {
        "action_low": space.low.astype(np.float64).tolist(),
        "action_high": space.high.astype(np.float64).tolist(),
    }


def check_spaces(meta: dict[str, Any], env: gymnasium.Env[Any, Any]) -> None:
    """ValueError unless the saved observation bounds (and action space, when recorded) are
    ``env``'s."""
    observations = env.observation_space
    low, high = np.asarray(meta["observation_low"]), np.asarray(meta["observation_high"])
    if not isinstance(observations, gymnasium.spaces.Box) or not same_bounds(
        (low, high), (observations.low, observations.high)
    ):
        raise ValueError("saved for another observation space")
    actions = env.action_space
    if "n_actions" in meta:
        same = isinstance(actions, gymnasium.spaces.Discrete) and meta["n_actions"] == actions.n
    else:
        saved = (np.asarray(meta["action_low"]), np.asarray(meta["action_high"]))
        same = isinstance(actions, gymnasium.spaces.Box) and same_bounds(
            saved, (actions.low, actions.high)
        )
    if not same:
        raise ValueError("saved for another action space")


def same_bounds(saved: tuple[np.ndarray, np.ndarray], space: tuple[np.ndarray, np.ndarray]) -> bool:
    """True when saved (low, high) have the space's shape and values."""
    return all(
        a.shape == b.shape and a.dtype.kind == "f" and np.allclose(a, b)
        for a, b in zip(saved, space, strict=True)
    )


def load_agent(agent_class: type[AgentT], path: str | Path, env: gymnasium.Env[Any, Any]) -> AgentT:
    """An ``agent_class`` on ``env`` with the weights of ``agent.save(path)``; CorruptFileError
    naming the file when it is missing, damaged or does not fit ``env`` or its config."""
    npz_path, json_path = save_paths(path)
    meta = read_json(json_path, max_bytes=MAX_META_BYTES, what="agent file")
    try:
        version, seed = meta.get("version"), meta.get("seed")
        if meta.get("format") != f"skidnav-{agent_class.name}" or (
            type(version) is not int or version != SAVE_VERSION
        ):
            raise ValueError(
                f"not a skidnav {agent_class.name.upper()} file of version {SAVE_VERSION}"
            )
        config = agent_class.config_class.from_mapping(dict(meta["config"]))
        check_spaces(meta, env)
        if type(seed) is not int or not 0 <= seed < 2**63:
            raise ValueError(f"seed {shown(seed)} is not an integer in [0, 2**63)")
        agent = agent_class(env, config, seed=seed)
    except (KeyError, TypeError, ValueError, OverflowError) as error:
        raise CorruptFileError(f"{json_path}: cannot load agent: {first_line(error)}") from None
    import torch

    expected = agent.weights()
    try:
        with SavedArchive(npz_path) as archive:
            arrays = archive.read_all(
                {name: ArraySpec(value.shape, "<f4") for name, value in expected.items()}
            )
    except READ_ERRORS as error:
        if isinstance(error, CorruptFileError):
            raise
        raise CorruptFileError(f"{npz_path}: cannot load agent: {first_line(error)}") from None
    if not all(np.isfinite(a).all() for a in arrays.values()):
        raise CorruptFileError(f"{npz_path}: cannot load agent: a weight is NaN or infinite")
    agent._load_network({name: torch.from_numpy(np.array(a)) for name, a in arrays.items()})
    return agent


def observation_scaler(space: gymnasium.spaces.Box) -> Callable[[np.ndarray], np.ndarray]:
    """The map of ``space`` onto [−1, 1] that ``RescaleObservation`` applies in training."""
    return rescale_box(space, np.float64(-1.0), np.float64(1.0))[1]
