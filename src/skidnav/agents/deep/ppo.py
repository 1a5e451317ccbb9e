"""PPO on the wheel-speed actions of the navigation env (the ``deep`` extra).

Proximal policy optimisation (Schulman, Wolski, Dhariwal, Radford & Klimov 2017, "Proximal
Policy Optimization Algorithms", arXiv:1707.06347): an on-policy actor-critic whose Gaussian
policy over (ω_L, ω_R) is improved on each batch of ``n_steps`` fresh steps by several epochs of
the clipped surrogate objective, with advantages by generalised advantage estimation
(λ = ``gae_lambda``). The implementation is Stable-Baselines3's ``PPO`` (Raffin et al. 2021,
JMLR 22(268)) on the CPU build of PyTorch, with skidnav's conventions from
:mod:`skidnav.agents.deep.common` and :mod:`skidnav.agents.deep.wheel_speeds`; the deterministic
policy is the Gaussian's mean, clipped to the wheel-speed box.
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
    from stable_baselines3 import PPO

AGENT_NAME = "ppo"


@dataclass(frozen=True)
class PPOConfig(DeepConfig):
    """PPO's settings (Stable-Baselines3 names; defaults sized for the 0.62 m arena, where a
    path takes 15 to 80 actions of 1 s to 0.2 s).

    Attributes:
        learning_rate: Adam step size. n_steps: real steps per update (a few episodes).
        batch_size: steps per minibatch (≤ ``n_steps``). n_epochs: passes over each batch.
        gamma: discount. gae_lambda: λ of generalised advantage estimation.
        clip_range: ε of the clipped probability ratio. ent_coef: weight of the entropy bonus.
        vf_coef: weight of the value loss. max_grad_norm: gradient clipping norm.
        log_std_init: initial log standard deviation of each wheel speed [log rad/s].
        hidden: widths of the hidden layers of the actor and of the critic (tanh).
    """

    agent_name = AGENT_NAME
    learning_rate: float = 3e-4
    n_steps: int = 1024
    batch_size: int = 64
    n_epochs: int = 10
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_range: float = 0.2
    ent_coef: float = 0.0
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    log_std_init: float = 0.0
    hidden: tuple[int, ...] = (64, 64)

    def ranges(self) -> dict[str, bool]:
        """Per field, whether its value is in range."""
        return {
            "learning_rate": 0 < self.learning_rate < 1,
            "n_steps": self.n_steps >= 2,
            "batch_size": 2 <= self.batch_size <= self.n_steps,
            "n_epochs": self.n_epochs >= 1,
            "gamma": 0 <= self.gamma <= 1,
            "gae_lambda": 0 <= self.gae_lambda <= 1,
            "clip_range": self.clip_range > 0,
            "ent_coef": self.ent_coef >= 0,
            "vf_coef": self.vf_coef >= 0,
            "max_grad_norm": self.max_grad_norm > 0,
            "log_std_init": -10 <= self.log_std_init <= 2,
        }


class PPOAgent(WheelSpeedAgent[PPOConfig]):
    """Stable-Baselines3 PPO on ``env`` (the feature observation, wheel-speed actions)."""

    name = AGENT_NAME
    config_class = PPOConfig

    def _build(self, env: gymnasium.Env[Any, Any]) -> PPO:
        from stable_baselines3 import PPO

        c = self.config
        return PPO(
            "MlpPolicy", env, learning_rate=c.learning_rate, n_steps=c.n_steps,
            batch_size=c.batch_size, n_epochs=c.n_epochs, gamma=c.gamma,
            gae_lambda=c.gae_lambda, clip_range=c.clip_range, ent_coef=c.ent_coef,
            vf_coef=c.vf_coef, max_grad_norm=c.max_grad_norm,
            policy_kwargs={"net_arch": list(c.hidden), "log_std_init": c.log_std_init},
            seed=self.seed, device="cpu", verbose=0,
        )  # fmt: skip

    def network(self) -> torch.nn.Module:
        """The actor-critic policy (actor and critic in one module; its weights are saved)."""
        return self.model.policy


def load_ppo(path: str | Path, env: gymnasium.Env[Any, Any]) -> PPOAgent:
    """A :class:`PPOAgent` on ``env`` with the weights of ``agent.save(path)``; CorruptFileError
    naming the file when it is missing, damaged or does not fit ``env`` or its config."""
    return load_agent(PPOAgent, path, env)


def policy_from_file(json_path: Path, meta: dict[str, Any]) -> FrozenWheelPolicy:
    """The frozen policy saved by :meth:`PPOAgent.save` (``meta``: its parsed ``.json``), as
    its family (:mod:`skidnav.agents.deep.family`) calls it, without an env."""
    return saved_policy(PPOAgent, json_path, meta)


AGENT_CLASS = PPOAgent
CONFIG_CLASS = PPOConfig
