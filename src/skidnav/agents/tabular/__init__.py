"""Tabular agents: the base agent, Q-learning, the Dyna family and the model-based planners, with
their compiled planning kernels."""
