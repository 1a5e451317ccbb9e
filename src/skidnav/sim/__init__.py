"""The navigation MDP as compiled code and what reads it: the step, the task's arrays, lidar,
features, the vector step, value iteration, the fewest-action plan, the grid mazes, Q-table
primitives."""
