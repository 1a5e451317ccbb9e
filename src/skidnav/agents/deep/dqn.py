"""DQN on a continuous observation of the navigation env (the ``deep`` extra).

Deep Q-learning (Mnih et al. 2015, "Human-level control through deep reinforcement learning",
Nature 518): a Q network over the observation vector, trained from a replay buffer toward the
targets of a periodically copied target network, ε-greedy with ε decayed linearly. The
implementation is Stable-Baselines3's ``DQN`` (Raffin et al. 2021, JMLR 22(268)) on the CPU
build of PyTorch; this module gives it skidnav's conventions:

1. a frozen, validated config (:class:`DQNConfig`; a bad value is a one-line ValueError);
2. one root seed per agent, PyTorch on one thread (the experiment runner runs one process per
   core), so the same seed gives the same network on this machine;
3. observations rescaled from the ``Box`` bounds to [−1, 1] (Gymnasium's
   ``RescaleObservation``), so metres and radians reach the network on one scale;
4. training by **episodes** (:meth:`DQNAgent.train`), each episode's return, length and success
   (the goal reached, not cut by the action limit) recorded;
5. saved files that are not pickle (:meth:`DQNAgent.save`, :func:`load_dqn`): the Q network's
   weights as a ``.npz`` of float32 arrays and a ``.json`` of the config and the spaces; loading
   checks every array's name, dtype and shape against a new network of that config before it is
   used, and refuses anything else in one line.

The observation must be a ``Box`` (``observation="pose"``, or ``"features"`` for the goal and
range readings); the action space is the env's ``Discrete(4)``.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
from gymnasium.wrappers import RescaleObservation

from skidnav.agents.core import save_paths
from skidnav.agents.training import TrainingLog, greedy_evaluation, log_from_rows
from skidnav.atomicfile import write_atomic, write_npz_atomic
from skidnav.errors import CorruptFileError, first_line
from skidnav.savedfile import READ_ERRORS, ArraySpec, SavedArchive, read_json

AGENT_NAME = "dqn"
SAVE_FORMAT = "skidnav-dqn"
SAVE_VERSION = 1
MAX_LAYER_WIDTH = 4096
MAX_LAYERS = 8
MAX_TRAINING_STEPS = 10**12
"""The step budget handed to Stable-Baselines3: training ends by episodes, not by it."""


@dataclass(frozen=True)
class DQNConfig:
    """DQN's settings (Stable-Baselines3 names; defaults sized for the 0.62 m arena).

    Attributes:
        learning_rate: Adam step size. buffer_size: replay capacity [transitions].
        learning_starts: real steps before the first gradient step. batch_size: per gradient step.
        gamma: discount. train_freq: real steps per gradient step.
        target_update_interval: real steps between copies to the target network.
        exploration_fraction: share of ``exploration_steps`` over which ε decays from 1 to
            ``exploration_final_eps``. exploration_steps: the schedule's length [real steps].
        hidden: widths of the hidden layers (ReLU).
    """

    learning_rate: float = 1e-3
    buffer_size: int = 50_000
    learning_starts: int = 500
    batch_size: int = 64
    gamma: float = 0.95
    train_freq: int = 1
    target_update_interval: int = 500
    exploration_fraction: float = 0.3
    exploration_final_eps: float = 0.05
    exploration_steps: int = 50_000
    hidden: tuple[int, ...] = (64, 64)

    def __post_init__(self) -> None:
        object.__setattr__(self, "hidden", tuple(self.hidden))
        checks = {
            "learning_rate": 0 < self.learning_rate < 1,
            "buffer_size": self.buffer_size >= 1,
            "learning_starts": self.learning_starts >= 0,
            "batch_size": self.batch_size >= 1,
            "gamma": 0 <= self.gamma <= 1,
            "train_freq": self.train_freq >= 1,
            "target_update_interval": self.target_update_interval >= 1,
            "exploration_fraction": 0 < self.exploration_fraction <= 1,
            "exploration_final_eps": 0 <= self.exploration_final_eps <= 1,
            "exploration_steps": self.exploration_steps >= 1,
            "hidden": 1 <= len(self.hidden) <= MAX_LAYERS
            and all(isinstance(w, int) and 1 <= w <= MAX_LAYER_WIDTH for w in self.hidden),
        }
        for name, ok in checks.items():
            value = getattr(self, name)
            if (isinstance(value, float) and not math.isfinite(value)) or not ok:
                raise ValueError(f"dqn: {name} = {value!r} is out of range")

    @classmethod
    def from_mapping(cls, values: dict[str, Any]) -> DQNConfig:
        """A config from a mapping (e.g. a TOML table); unknown keys are refused in one line."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise ValueError(f"dqn: unknown key {unknown[0]!r} (expected one of {sorted(known)})")
        return cls(**values)


class DQNAgent:
    """Stable-Baselines3 DQN on ``env`` (a ``Box`` observation, ``Discrete`` actions)."""

    name = AGENT_NAME

    def __init__(
        self, env: gymnasium.Env[Any, Any], config: DQNConfig | None = None, seed: int = 0
    ) -> None:
        import torch
        from stable_baselines3 import DQN

        if not isinstance(env.observation_space, gymnasium.spaces.Box):
            raise ValueError("dqn: expected a Box observation (observation='pose' or 'features')")
        if not isinstance(env.action_space, gymnasium.spaces.Discrete):
            raise ValueError("dqn: expected Discrete actions")
        torch.set_num_threads(1)
        self.scaled = RescaleObservation(env, -1.0, 1.0)  # type: ignore[arg-type]
        self.config = config or DQNConfig()
        self.seed = seed
        c = self.config
        self.model = DQN(
            "MlpPolicy", self.scaled, learning_rate=c.learning_rate, buffer_size=c.buffer_size,
            learning_starts=c.learning_starts, batch_size=c.batch_size, gamma=c.gamma,
            train_freq=c.train_freq, target_update_interval=c.target_update_interval,
            exploration_fraction=c.exploration_fraction,
            exploration_final_eps=c.exploration_final_eps,
            policy_kwargs={"net_arch": list(c.hidden)}, seed=seed, device="cpu", verbose=0,
        )  # fmt: skip
        self.model.exploration_schedule = self._epsilon
        self.episodes = 0

    def _epsilon(self, _progress_remaining: float) -> float:
        """ε after the real steps taken so far: 1 decaying linearly to ``exploration_final_eps``
        over ``exploration_fraction · exploration_steps`` steps (Stable-Baselines3 would scale
        its schedule to each ``learn`` call's length; training by episodes has none)."""
        c = self.config
        decay = c.exploration_fraction * c.exploration_steps
        done = min(self.model.num_timesteps / decay, 1.0)
        return 1.0 + done * (c.exploration_final_eps - 1.0)

    @property
    def steps(self) -> int:
        """Real steps taken in training."""
        return int(self.model.num_timesteps)

    def train_episodes(
        self,
        episodes: int,
        *,
        greedy_eval_env: gymnasium.Env[Any, Any] | None = None,
        greedy_seeds: Sequence[int] | None = None,
        greedy_max_steps: int | None = None,
    ) -> TrainingLog:
        """Learn for ``episodes`` more episodes (ε as :meth:`_epsilon`, counted from the first
        episode of the first call); after each, the greedy policy is evaluated on
        ``greedy_eval_env`` as the plain loop does
        (:func:`~skidnav.agents.training.greedy_evaluation`, ``greedy_max_steps`` actions at
        most, default 10,000). Returns the loop's log
        (``planning_updates``: 0; wall time without the evaluations)."""
        from stable_baselines3.common.callbacks import BaseCallback

        agent = self
        columns: dict[str, list[Any]] = {name: [] for name in TrainingLog._fields}
        n_rollouts = 1 if greedy_seeds is None else len(greedy_seeds)
        limit = greedy_max_steps or 10_000

        class _Episodes(BaseCallback):
            """Records each finished episode, evaluates it, stops after ``episodes``."""

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
                columns["wall_time"].append(time.perf_counter() - self.start)
                columns["returns"].append(self.total)
                columns["lengths"].append(self.length)
                columns["successes"].append(not info.get("TimeLimit.truncated", False))
                columns["collisions"].append(self.collisions)
                columns["planning_updates"].append(0)
                greedy = [-1] * n_rollouts
                if greedy_eval_env is not None:
                    greedy = greedy_evaluation(agent, greedy_eval_env, limit, greedy_seeds)
                columns["greedy_lengths"].append(greedy)
                self.total, self.length, self.collisions = 0.0, 0, 0
                self.start = time.perf_counter()
                return len(columns["returns"]) < episodes

        if episodes > 0:
            self.model.learn(
                total_timesteps=MAX_TRAINING_STEPS, callback=_Episodes(), reset_num_timesteps=False
            )
        self.episodes += len(columns["returns"])
        return log_from_rows(columns, n_rollouts)

    def greedy_action(self, observation: np.ndarray) -> int:
        """The action of highest Q at ``observation``."""
        scaled = self.scaled.observation(np.asarray(observation, dtype=np.float64))
        action, _ = self.model.predict(scaled, deterministic=True)
        return int(action)

    def weights(self) -> dict[str, np.ndarray]:
        """The Q network's parameters by name, float32 arrays (copies)."""
        return {
            name: tensor.detach().cpu().numpy().copy()
            for name, tensor in self.model.q_net.state_dict().items()
        }

    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write ``path.npz`` (the Q network's weights) and ``path.json`` (config, spaces,
        counters), each atomically. Returns both paths."""
        npz_path, json_path = save_paths(path)
        npz_path.parent.mkdir(parents=True, exist_ok=True)
        write_npz_atomic(npz_path, self.weights(), compress=True)
        space = self.scaled.env.observation_space
        assert isinstance(space, gymnasium.spaces.Box)
        meta = {
            "format": SAVE_FORMAT,
            "version": SAVE_VERSION,
            "agent": self.name,
            "config": asdict(self.config),
            "observation_low": space.low.astype(np.float64).tolist(),
            "observation_high": space.high.astype(np.float64).tolist(),
            "n_actions": int(self.model.action_space.n),  # type: ignore[attr-defined]
            "seed": self.seed,
            "counters": {"steps": self.steps, "episodes": self.episodes},
        }
        write_atomic(json_path, json.dumps(meta, indent=1).encode("utf-8"))
        return npz_path, json_path


def load_dqn(path: str | Path, env: gymnasium.Env[Any, Any]) -> DQNAgent:
    """A :class:`DQNAgent` on ``env`` with the weights of ``agent.save(path)``; CorruptFileError
    naming the file when it is missing, damaged or does not fit ``env`` or its config."""
    npz_path, json_path = save_paths(path)
    meta = read_json(json_path, max_bytes=1 << 16, what="agent file")
    try:
        if meta.get("format") != SAVE_FORMAT or meta.get("version") != SAVE_VERSION:
            raise ValueError(f"not a skidnav DQN file of version {SAVE_VERSION}")
        config = DQNConfig.from_mapping(dict(meta["config"]))
        space = env.observation_space
        low, high = np.asarray(meta["observation_low"]), np.asarray(meta["observation_high"])
        if low.shape != space.shape or not (
            np.allclose(low, space.low) and np.allclose(high, space.high)  # type: ignore[attr-defined]
        ):
            raise ValueError("saved for another observation space")
        agent = DQNAgent(env, config, seed=int(meta["seed"]))
    except (KeyError, TypeError, ValueError) as error:
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
    state = {name: torch.from_numpy(np.array(a)) for name, a in arrays.items()}
    agent.model.q_net.load_state_dict(state)
    agent.model.q_net_target.load_state_dict(state)
    return agent


AGENT_CLASS = DQNAgent
CONFIG_CLASS = DQNConfig
