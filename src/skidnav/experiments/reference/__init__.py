"""What the best computable policy achieves on a world: the oracle, the optimum, the fine grid and
the fewest-action start plan."""
