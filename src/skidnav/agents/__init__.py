"""Agents by family: ``tabular/`` (a Q table over the discrete state), ``linear/`` (tile-coded
features), ``deep/`` (Stable-Baselines3), ``policies/`` (wheel-speed policies and CMA-ES search),
``mpc/`` (model-based control of the wheel speeds: MPPI through the learned kinematic model);
the learning-step registry (:mod:`skidnav.agents.learning`), the two training loops
(:mod:`skidnav.agents.training`, :mod:`skidnav.agents.tabular.fast_training`) and the catalog of
every
agent by name (:mod:`skidnav.agents.catalog`). docs/agents/core.md describes the tabular core.
"""
