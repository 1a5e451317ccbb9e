"""The physical robot: the thesis's skid-steer robot as a MuJoCo model (docs/physics.md), a
stand-in for the real robot whose time-variant skidding the ICR model did not predict
(Alhawary (2020), ch. 7).

:mod:`~skidnav.physics.materials` names the floor materials, :mod:`~skidnav.physics.mjcf` writes
the robot, its arena and its floor as MJCF, :mod:`~skidnav.physics.mujoco_robot` drives it. MuJoCo
is an optional dependency (the ``physics`` extra); :func:`~skidnav.physics.backend.load_mujoco`
says in one line when it is missing. Importing this package chooses MuJoCo's GL backend
(``MUJOCO_GL``) if the user has not; import it before ``mujoco`` for offscreen rendering.
"""

from skidnav.physics.backend import choose_gl_backend

choose_gl_backend()  # before anyone imports MuJoCo: it reads MUJOCO_GL once, at import
