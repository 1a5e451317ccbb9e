"""Model-based control of the two wheel speeds: ``mppi-kinematic``, MPPI (Williams et al. 2017)
through the online Bayesian ridge kinematic model of the thesis, its uncertainty sampled per
sequence (as PETS, Chua et al. 2018), against the walls found so far, with a cost-to-go over the
learned map (docs/agents/mppi-kinematic.md).

Modules: ``config`` (:class:`~skidnav.agents.mpc.config.MPPIConfig`), ``dynamics`` (the model as
the rollouts sample it), ``costmap`` (wall evidence as costs, the cells' cost-to-go, the terminal
value), ``lattice`` (the states' heading-aware cost-to-go), ``evidence`` (what a real step
teaches the map), ``rollouts`` (the compiled K × H batch), ``planner`` (the MPPI step),
``observations`` (the pose and lidar readings of an observation), ``agent``
(:class:`~skidnav.agents.mpc.agent.MPPIKinematicAgent`, saving), ``policy`` (its frozen
:class:`~skidnav.agents.mpc.policy.MPPIPolicy`), ``loading``, ``training``
(:func:`~skidnav.agents.mpc.training.train_mppi`).
"""
