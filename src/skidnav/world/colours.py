"""The colours of the arena's landmarks, one convention for every picture of a world: the start
cell green, the goal cell red, the robot's trail blue (the report's figures, the frames of
``skidnav world map show`` and ``world simulate``, the env's ``rgb_array`` frames, the report's
animations, the continuity study's trajectories).

Each colour is an RGB triple of 0–255 integers (PIL); :func:`unit_rgb` gives matplotlib's 0–1
floats of the same colour.
"""

from __future__ import annotations

START = (40, 160, 60)
"""The start cell: green."""
GOAL = (215, 40, 40)
"""The goal cell: red."""
TRAIL = (30, 100, 210)
"""The robot's path: blue (neither the start's nor the goal's colour)."""
LANDMARKS = (("start", START), ("goal", GOAL))
"""(legend label, colour) of the landmark cells, in legend order."""


def unit_rgb(colour: tuple[int, int, int]) -> tuple[float, float, float]:
    """``colour`` (0–255 integers) as matplotlib's (red, green, blue) floats in [0, 1].

    >>> unit_rgb(GOAL)
    (0.8431372549019608, 0.1568627450980392, 0.1568627450980392)
    """
    red, green, blue = colour
    return red / 255.0, green / 255.0, blue / 255.0
