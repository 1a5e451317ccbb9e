"""DQN on a continuous observation of the navigation env (the ``deep`` extra).

Deep Q-learning (Mnih et al. 2015, "Human-level control through deep reinforcement learning",
Nature 518): a Q network over the observation vector, trained from a replay buffer toward the
targets of a periodically copied target network, ε-greedy with ε decayed linearly. The
implementation is Stable-Baselines3's ``DQN`` (Raffin et al. 2021, JMLR 22(268)) on the CPU
build of PyTorch, with skidnav's conventions from :mod:`skidnav.agents.deep.common` (validated
frozen config, one root seed, one thread, observations rescaled to [−1, 1], training by
episodes, saved files that are not pickle: the Q network's weights).

The observation must be a ``Box`` (``observation="pose"``, or ``"features"`` for the goal and
range readings); the action space is the env's ``Discrete(4)``. A saved agent over the
features drives the robot frozen, by the wheel speeds of its greedy actions
(:func:`policy_from_file`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import gymnasium
import numpy as np

from skidnav.agents.deep.common import DeepAgent, DeepConfig, load_agent
from skidnav.agents.deep.spaces import SavedSpaces
from skidnav.agents.discrete_policy import DiscreteActionPolicy, discrete_policy
from skidnav.errors import CorruptFileError, first_line

if TYPE_CHECKING:
    import torch
    from stable_baselines3 import DQN

AGENT_NAME = "dqn"


@dataclass(frozen=True)
class DQNConfig(DeepConfig):
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

    agent_name = AGENT_NAME
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

    def ranges(self) -> dict[str, bool]:
        """Per field, whether its value is in range."""
        return {
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
        }


class DQNAgent(DeepAgent[DQNConfig]):
    """Stable-Baselines3 DQN on ``env`` (a ``Box`` observation, ``Discrete`` actions)."""

    name = AGENT_NAME
    config_class = DQNConfig
    action_space_class = gymnasium.spaces.Discrete

    def _build(self, env: gymnasium.Env[Any, Any]) -> DQN:
        from stable_baselines3 import DQN

        c = self.config
        model = DQN(
            "MlpPolicy", env, learning_rate=c.learning_rate, buffer_size=c.buffer_size,
            learning_starts=c.learning_starts, batch_size=c.batch_size, gamma=c.gamma,
            train_freq=c.train_freq, target_update_interval=c.target_update_interval,
            exploration_fraction=c.exploration_fraction,
            exploration_final_eps=c.exploration_final_eps,
            policy_kwargs={"net_arch": list(c.hidden)}, seed=self.seed, device="cpu", verbose=0,
        )  # fmt: skip
        model.exploration_schedule = self._epsilon
        return model

    def _epsilon(self, _progress_remaining: float) -> float:
        """ε after the real steps taken so far: 1 decaying linearly to ``exploration_final_eps``
        over ``exploration_fraction · exploration_steps`` steps (Stable-Baselines3 would scale
        its schedule to each ``learn`` call's length; training by episodes has none)."""
        c = self.config
        decay = c.exploration_fraction * c.exploration_steps
        done = min(self.model.num_timesteps / decay, 1.0)
        return 1.0 + done * (c.exploration_final_eps - 1.0)

    def network(self) -> torch.nn.Module:
        """The Q network (its weights are saved)."""
        return self.model.q_net  # type: ignore[attr-defined, no-any-return]

    def _load_network(self, state: dict[str, torch.Tensor]) -> None:
        """The saved weights into the Q network and its target."""
        self.model.q_net.load_state_dict(state)  # type: ignore[attr-defined]
        self.model.q_net_target.load_state_dict(state)  # type: ignore[attr-defined]

    def greedy_action(self, observation: np.ndarray) -> int:
        """The action of highest Q at ``observation``."""
        return int(super().greedy_action(observation))


def load_dqn(path: str | Path, env: gymnasium.Env[Any, Any]) -> DQNAgent:
    """A :class:`DQNAgent` on ``env`` with the weights of ``agent.save(path)``; CorruptFileError
    naming the file when it is missing, damaged or does not fit ``env`` or its config."""
    return load_agent(DQNAgent, path, env)


def policy_from_file(json_path: Path, meta: dict[str, Any]) -> DiscreteActionPolicy:
    """The agent saved by :meth:`DQNAgent.save` (``meta``: its parsed ``.json``), frozen,
    driving by the wheel speeds of its greedy actions
    (:func:`~skidnav.agents.discrete_policy.discrete_policy`), without an env;
    CorruptFileError in one line naming the file, UserError for an agent the robot cannot run."""
    try:
        spaces = SavedSpaces(meta)
    except (KeyError, TypeError, ValueError, OverflowError) as error:  # overflow: a huge integer
        raise CorruptFileError(f"{json_path}: cannot load agent: {first_line(error)}") from None
    space = spaces.observation_space
    return discrete_policy(  # its network is built once the observation is checked
        lambda: load_dqn(json_path, spaces), json_path, AGENT_NAME, (space.low, space.high),
        int(getattr(spaces.action_space, "n", 0)),
    )  # fmt: skip


AGENT_CLASS = DQNAgent
CONFIG_CLASS = DQNConfig
