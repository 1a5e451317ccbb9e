"""Compiled hot loops (numba), written once and called by envs, agents and the real-time loop."""
