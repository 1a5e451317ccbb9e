"""Policy search: a tanh policy on the feature observation, optimised by CMA-ES."""
