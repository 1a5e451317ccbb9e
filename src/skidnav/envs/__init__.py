"""Gymnasium environments: thin shells over robot/, world/ and sim/."""
