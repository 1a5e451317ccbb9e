"""Hyperparameter search over experiment configs (Optuna)."""
