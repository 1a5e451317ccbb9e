"""Linear agents on continuous (``Box``) observations over tile-coded features
(docs/agents/linear-q.md, docs/agents/linear-dyna.md).

``make_linear_agent(name, observation_space, n_actions, config, rng)`` and
``load_linear_agent(path)`` live in :mod:`skidnav.agents.linear.registry`; they train in the
plain loop of every agent (:func:`skidnav.agents.training.train_agent`).
"""
