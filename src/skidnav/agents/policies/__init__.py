"""Wheel-speed policies: the policy interface, the goal tracker, loading saved policies, and CMA-ES
policy search."""
