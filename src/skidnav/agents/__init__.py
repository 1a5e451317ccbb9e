"""Tabular agents over one shared core (docs/agents/core.md).

``make_agent(name, n_states, n_actions, config, rng)`` and ``load_agent(path)`` live in
:mod:`skidnav.agents.tabular.registry`; the plain training loop in :mod:`skidnav.agents.training`.
"""
