"""What the best computable policy achieves on a world, behind one entry point
(:func:`skidnav.experiments.reference.world.world_reference`): the oracle, the fewest-action start
plan, the continuous optimum and the fine grid it is solved on."""
