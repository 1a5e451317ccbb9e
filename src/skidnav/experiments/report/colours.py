"""How an agent is drawn: its one colour and its interval bands (:func:`draw_band`), in every
figure of a report (:mod:`skidnav.experiments.report.plots`) and of the docs' figure scripts
(``docs/tools/*.py``).

An agent keeps its colour from one figure to the next (each figure asks for the colours of all
the report's agents, :func:`agent_colours`) and from one report to another. A registered agent
name (:func:`skidnav.agents.catalog.agent_names`) takes
the :data:`PALETTE` entry at its place in the catalog, so ``q-learning`` is always the first
colour (blue) and ``dyna-full`` the seventh (pink), in every report. Any other label
(``dyna-full-expected``, ``dyna-full[kinematic_model=learned]``) takes one of the nine
``tab10`` colours of the palette from a hash of its text, the same in every report unless an
agent of the same report already has that colour: then the next free one
(:func:`agent_colours`). So the agents of one report never share a colour (up to 20 of them).
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

from skidnav.agents.catalog import agent_names

Colour = tuple[float, float, float]
"""Matplotlib's (red, green, blue), each in [0, 1]."""


def _colours(name: str, indices: Iterable[int]) -> list[Colour]:
    """The colours at ``indices`` of the matplotlib colour map ``name``, as (r, g, b)."""
    return [tuple(float(c) for c in colormaps[name](index)[:3]) for index in indices]  # type: ignore[misc]


PALETTE: tuple[Colour, ...] = tuple(
    _colours("tab10", (0, 1, 2, 3, 4, 5, 6, 8, 9))
    + _colours("tab20b", (0, 4, 8, 12, 16, 2, 6, 10, 14, 18))
    + _colours("tab20c", (4,))
)
"""The 20 agent colours, the registered agents' in catalog order: matplotlib's ``tab10`` without
its grey (grey is for reference lines), then the darkest and the middle shade of each of the five
hues of ``tab20b`` and a dark orange of ``tab20c``: every one dark enough for a thin line on
white (one per registered agent; a catalog longer than this wraps round)."""


@functools.cache
def _catalog_places() -> dict[str, int]:
    """Every registered agent name → its place in the catalog."""
    return {name: place for place, name in enumerate(agent_names())}


STRONG = 9
"""The first places of :data:`PALETTE` (``tab10``'s colours), the most distinct: a label that is
not a registered name is given one of them while one is free."""


def _places_to_try(label: str) -> list[int]:
    """The :data:`PALETTE` places a label that is not a registered name may take, in order: the
    :data:`STRONG` places from the one the SHA-256 of its text picks (the same on every machine,
    unlike Python's ``hash``) round, then the others."""
    digest = hashlib.sha256(label.encode("utf-8")).digest()
    first = int.from_bytes(digest[:8], "big") % STRONG
    return [(first + step) % STRONG for step in range(STRONG)] + list(range(STRONG, len(PALETTE)))


def agent_colours(labels: Iterable[str]) -> dict[str, Colour]:
    """The colour of each agent of ``labels`` (the agents of one report), all different while
    there are no more than :data:`PALETTE` has: a registered name's catalog colour, the same in
    every report; any other label the :data:`STRONG` colour its text hashes to, or, when an agent of
    ``labels`` has that one, the next free one (:func:`_places_to_try`; labels taken in sorted
    order, so the same set gives the same colours in every figure).

    >>> colours = agent_colours(["dyna-full", "q-learning", "my-agent"])
    >>> colours["q-learning"] == PALETTE[0] and colours["dyna-full"] == PALETTE[6]
    True
    >>> colours["my-agent"] in (colours["q-learning"], colours["dyna-full"])
    False
    """
    labels = list(dict.fromkeys(labels))
    catalog = _catalog_places()
    places = {label: catalog[label] % len(PALETTE) for label in labels if label in catalog}
    taken = set(places.values())
    for label in sorted(set(labels) - set(places)):
        free = [place for place in _places_to_try(label) if place not in taken]
        places[label] = free[0] if free else _places_to_try(label)[0]
        taken.add(places[label])
    return {label: PALETTE[places[label]] for label in labels}


def agent_colour(label: str) -> Colour:
    """The colour of the agent ``label`` drawn alone or with registered agents only
    (:func:`agent_colours`); a figure of several agents asks :func:`agent_colours` for all of
    the report's agents at once.

    >>> agent_colour("q-learning") == PALETTE[0]
    True
    """
    return agent_colours([label])[label]


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
