"""The real-time loop and its safety: the control loop (:mod:`.loop`), the link and stall monitor
(:mod:`.safety`), homing between episodes, the transition and statistics the loop builds,
checkpoints, run records, and the ``robot run`` command's body (:mod:`.run`)."""
