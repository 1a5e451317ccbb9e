"""SAC on the wheel-speed actions of the navigation env (the ``deep`` extra).

Soft actor-critic (Haarnoja, Zhou, Abbeel & Levine 2018, "Soft Actor-Critic: Off-Policy Maximum
Entropy Deep Reinforcement Learning with a Stochastic Actor", ICML; the temperature tuned
toward a target entropy as in Haarnoja et al. 2018, arXiv:1812.05905): an off-policy
actor-critic that maximises return plus entropy, two Q networks with slowly tracking targets
(the smaller of the two in every target), and a tanh-squashed Gaussian actor, all trained from a
replay buffer. The implementation is Stable-Baselines3's ``SAC`` (Raffin et al. 2021,
JMLR 22(268)) on the CPU build of PyTorch, with skidnav's conventions from
:mod:`skidnav.agents.deep.common` and :mod:`skidnav.agents.deep.wheel_speeds`; the deterministic
policy is the squashed mean.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import gymnasium

from skidnav.agents.deep.common import DeepConfig, load_agent
from skidnav.agents.deep.wheel_speeds import FrozenWheelPolicy, WheelSpeedAgent, saved_policy

if TYPE_CHECKING:
    import torch
    from stable_baselines3 import SAC

AGENT_NAME = "sac"


@dataclass(frozen=True)
class SACConfig(DeepConfig):
    """SAC's settings (Stable-Baselines3 names; defaults sized for the 0.62 m arena, where a
    path takes 15 to 80 actions of 1 s to 0.2 s).

    Attributes:
        learning_rate: Adam step size (actor, critics, temperature).
        buffer_size: replay capacity [transitions].
        learning_starts: real steps of uniformly random wheel speeds before the first update.
        batch_size: transitions per gradient step. tau: target-network tracking rate.
        gamma: discount. train_freq: real steps between updates.
        gradient_steps: gradient steps per update.
        ent_coef: the temperature α, or ``"auto"`` to tune it toward the target entropy
            (−2, one per wheel).
        hidden: widths of the hidden layers of the actor and of each critic (ReLU).
    """

    agent_name = AGENT_NAME
    learning_rate: float = 3e-4
    buffer_size: int = 100_000
    learning_starts: int = 1000
    batch_size: int = 128
    tau: float = 0.005
    gamma: float = 0.99
    train_freq: int = 1
    gradient_steps: int = 1
    ent_coef: float | str = "auto"
    hidden: tuple[int, ...] = (64, 64)

    def ranges(self) -> dict[str, bool]:
        """Per field, whether its value is in range."""
        temperature = self.ent_coef
        return {
            "learning_rate": 0 < self.learning_rate < 1,
            "buffer_size": self.buffer_size >= 1,
            "learning_starts": self.learning_starts >= 0,
            "batch_size": self.batch_size >= 1,
            "tau": 0 < self.tau <= 1,
            "gamma": 0 <= self.gamma <= 1,
            "train_freq": self.train_freq >= 1,
            "gradient_steps": self.gradient_steps >= 1,
            "ent_coef": temperature == "auto"
            or (type(temperature) in (int, float) and float(temperature) > 0),
        }


class SACAgent(WheelSpeedAgent[SACConfig]):
    """Stable-Baselines3 SAC on ``env`` (the feature observation, wheel-speed actions)."""

    name = AGENT_NAME
    config_class = SACConfig

    def _build(self, env: gymnasium.Env[Any, Any]) -> SAC:
        from stable_baselines3 import SAC

        c = self.config
        return SAC(
            "MlpPolicy", env, learning_rate=c.learning_rate, buffer_size=c.buffer_size,
            learning_starts=c.learning_starts, batch_size=c.batch_size, tau=c.tau,
            gamma=c.gamma, train_freq=c.train_freq, gradient_steps=c.gradient_steps,
            ent_coef=c.ent_coef, policy_kwargs={"net_arch": list(c.hidden)}, seed=self.seed,
            device="cpu", verbose=0,
        )  # fmt: skip

    def network(self) -> torch.nn.Module:
        """The actor (all that acts; its weights are saved, the critics are not)."""
        return self.model.actor  # type: ignore[attr-defined, no-any-return]


def load_sac(path: str | Path, env: gymnasium.Env[Any, Any]) -> SACAgent:
    """A :class:`SACAgent` on ``env`` with the actor weights of ``agent.save(path)``;
    CorruptFileError naming the file when it is missing, damaged or does not fit ``env`` or its
    config."""
    return load_agent(SACAgent, path, env)


def policy_from_file(json_path: Path, meta: dict[str, Any]) -> FrozenWheelPolicy:
    """The frozen policy saved by :meth:`SACAgent.save` (``meta``: its parsed ``.json``), as
    its family (:mod:`skidnav.agents.deep.family`) calls it, without an env."""
    return saved_policy(SACAgent, json_path, meta)


AGENT_CLASS = SACAgent
CONFIG_CLASS = SACConfig
