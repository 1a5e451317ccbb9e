"""Agents on neural networks (Stable-Baselines3 on PyTorch: the ``deep`` extra)."""
