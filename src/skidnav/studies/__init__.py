"""Questions asked of the runner and of the real-time platform: the plain experiment, tuning,
continuity, generalisation, transfer, the hardware-in-the-loop study and the discretization gap;
every config kind loaded and run by :mod:`skidnav.studies.loading`."""
