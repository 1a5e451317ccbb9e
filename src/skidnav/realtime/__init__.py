"""Running agents in real time on a robot or its hardware-in-the-loop stand-in."""
