"""The kinematic-model comparison (docs/gp-kinematic.md): the Bayesian-ridge and the
Gaussian-process kinematic models on held-out sub-steps of the fast simulator, a study run by
``skidnav run`` (``kind = "kinematic-models"``): :mod:`.grid` (the config), :mod:`.trial` (one
model on one seed), :mod:`.table` (the table over seeds), :mod:`.study` (``STUDY``)."""
