"""Questions asked of the runner and of the real-time platform: tuning, continuity, generalisation,
transfer, the hardware-in-the-loop study and the discretization gap."""
