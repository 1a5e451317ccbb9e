"""The real-time loops and their safety: commanding the robot period by period (:mod:`.periods`),
the episodes around it (:mod:`.episodes`), a tabular agent's loop (:mod:`.loop`) and a frozen
continuous policy's (:mod:`.policy_loop`), the link and stall monitor (:mod:`.safety`), homing
between episodes, the transition and statistics the loops build, checkpoints, run records, and
the ``robot run`` command's body (:mod:`.run`)."""
