"""How an agent is drawn: its one colour and its interval bands (:func:`draw_band`), in every
figure of a report (:mod:`skidnav.experiments.report.plots`) and of the docs' figure scripts
(``docs/tools/*.py``).

An agent keeps its colour from one figure to the next and from one report to another, whatever
other agents are drawn beside it: the colour is a function of the label alone
(:func:`agent_colour`). A registered agent name (:func:`skidnav.agents.catalog.agent_names`) takes
the :data:`PALETTE` entry at its place in the catalog, so ``q-learning`` is always the first
colour (blue) and ``dyna-full`` the seventh (pink); any other label (``dyna-full-expected``,
``dyna-full[kinematic_model=learned]``) takes a hue drawn from a hash of its text (SHA-256, the
same on every machine and Python version) at a fixed saturation and brightness. Two hashed hues
can lie close; the registered names' colours are all different.
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Iterable
from typing import Any, Literal

import matplotlib

matplotlib.use("Agg")

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.colors import hsv_to_rgb

from skidnav.agents.catalog import agent_names

Colour = tuple[float, float, float]
"""Matplotlib's (red, green, blue), each in [0, 1]."""

PALETTE: tuple[Colour, ...] = tuple(
    tuple(float(channel) for channel in colormaps["tab20"](index)[:3])  # type: ignore[misc]
    for index in (*range(0, 20, 2), *range(1, 20, 2))
)
"""The registered agents' colours in catalog order: matplotlib's ten ``tab10`` colours, then
their ten lighter twins of ``tab20`` (one per registered agent; a catalog longer than this wraps
round)."""
HASHED_SATURATION = 0.75
"""Saturation of the hashed colours of labels that are not registered names (0–1)."""
HASHED_BRIGHTNESS = 0.7
"""Brightness (HSV value) of the hashed colours (0–1): dark enough to read on white."""


@functools.cache
def _catalog_places() -> dict[str, int]:
    """Every registered agent name → its place in the catalog."""
    return {name: place for place, name in enumerate(agent_names())}


def agent_colour(label: str) -> Colour:
    """The colour of the agent ``label`` in every figure: a registered name's catalog colour
    (:data:`PALETTE`), else a hue from the SHA-256 of ``label``.

    >>> agent_colour("q-learning") == PALETTE[0]
    True
    >>> agent_colour("my-agent") == agent_colour("my-agent")
    True
    """
    place = _catalog_places().get(label)
    if place is not None:
        return PALETTE[place % len(PALETTE)]
    digest = hashlib.sha256(label.encode("utf-8")).digest()
    hue = int.from_bytes(digest[:8], "big") / 2.0**64
    red, green, blue = hsv_to_rgb((hue, HASHED_SATURATION, HASHED_BRIGHTNESS))
    return float(red), float(green), float(blue)


def agent_colours(labels: Iterable[str]) -> dict[str, Colour]:
    """``label`` → :func:`agent_colour` for each of ``labels``, in their order."""
    return {label: agent_colour(label) for label in labels}


BAND_ALPHA = 0.1
"""Opacity of an interval band's fill. Light, so that where the bands of several agents overlap
each agent's colour still shows through instead of blending into one dark patch; the band's
edges (:data:`BAND_EDGE`) mark where each band ends."""
BAND_EDGE: dict[str, Any] = {"linewidth": 0.7, "linestyle": (0, (3, 2)), "alpha": 0.8}
"""Style of an interval band's two edges: thin dashed lines in the agent's colour, told apart
from its estimate (a solid line, thicker) and traceable through other bands."""


def draw_band(
    axes: Axes,
    x: np.ndarray,
    low: np.ndarray,
    high: np.ndarray,
    colour: Colour,
    *,
    step: Literal["pre", "post", "mid"] | None = None,
) -> None:
    """An interval band from ``low`` to ``high`` (shape (n,) each) over ``x`` (n,): a light fill
    (:data:`BAND_ALPHA`) with both edges drawn (:data:`BAND_EDGE`), in the agent's ``colour``;
    ``step``: a step band, as :meth:`~matplotlib.axes.Axes.step` draws with ``where=step``."""
    axes.fill_between(x, low, high, step=step, color=colour, alpha=BAND_ALPHA, linewidth=0)
    for edge in (low, high):
        if step is None:
            axes.plot(x, edge, color=colour, **BAND_EDGE)
        else:
            axes.step(x, edge, where=step, color=colour, **BAND_EDGE)
