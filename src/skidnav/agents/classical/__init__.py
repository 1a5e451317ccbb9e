"""The classical navigator: an occupancy grid from the laser, a Dijkstra route over it inflated by
the footprint, and a dynamic-window controller (docs/agents/classical.md)."""
