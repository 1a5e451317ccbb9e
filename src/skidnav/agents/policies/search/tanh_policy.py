"""A small tanh network from the feature observation to the two wheel speeds.

The policy searched by CMA-ES (:mod:`skidnav.agents.policies.search.cmaes`): deterministic, one flat
float64 parameter vector, evaluated for a whole population at once.

Forward pass, for an observation o float64 (d,), d = 7 + k (:mod:`skidnav.sim.features`):

1. x = clip(2 (o − low) / (high − low) − 1, −1, 1): each feature rescaled from the observation
   box [low, high] to [−1, 1], so metres, cosines and ranges reach the network on one scale;
2. h = tanh(W₁ x + b₁), W₁ (H, d), b₁ (H,) — left out when ``hidden`` H = 0 (a linear policy);
3. (ω_L, ω_R) = ω_max · tanh(W₂ h + b₂), W₂ (2, H) (or (2, d)), b₂ (2,): wheel speeds [rad/s]
   inside the env's action box ± ω_max.

The flat vector lists the layers in order, each as its weights row-major (out, in) then its
biases (out,): ``n = H·d + H + 2·H + 2`` parameters (``2·d + 2`` for H = 0). All zeros is the
policy that stands still.

>>> import numpy as np
>>> layout = PolicyLayout(np.zeros(9), np.ones(9), hidden=3, wheel_speed=1.7, lidar_rays=2)
>>> layout.n_parameters
38
>>> policy = TanhPolicy(layout, np.zeros(layout.n_parameters))
>>> policy.wheel_speeds(np.full(9, 0.5))
(0.0, 0.0)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from skidnav.checks import check_integer, check_number
from skidnav.sim.features import MAX_LIDAR_RAYS as MAX_LIDAR_RAYS  # the env's cap, re-exported

MAX_HIDDEN = 1024
"""Widest hidden layer accepted (a saved file announcing more is refused before allocation)."""


@dataclass(frozen=True, eq=False)
class PolicyLayout:
    """What a parameter vector means: the input scaling, the layer widths, the output range.

    Attributes:
        observation_low: float64 (d,), the observation box's lower bounds (the feature units:
            m for positions, distances and ranges; none for cosines and sines).
        observation_high: float64 (d,), its upper bounds, each > the lower one.
        hidden: H ≥ 0 tanh units in the one hidden layer (0: no hidden layer).
        wheel_speed: ω_max > 0 [rad/s], the largest wheel speed the output reaches.
        lidar_rays: k, the range readings at the end of the observation (d = 7 + k).
        lidar_range: their largest reading [m] (the env's ``lidar_range``).
    """

    observation_low: np.ndarray
    observation_high: np.ndarray
    hidden: int
    wheel_speed: float
    lidar_rays: int
    lidar_range: float = 0.3

    def __post_init__(self) -> None:
        low = np.array(self.observation_low, dtype=np.float64).reshape(-1)
        high = np.array(self.observation_high, dtype=np.float64).reshape(-1)
        check_integer("hidden", self.hidden, 0, MAX_HIDDEN)
        check_integer("lidar_rays", self.lidar_rays, 0, MAX_LIDAR_RAYS)
        if low.shape != (7 + self.lidar_rays,) or high.shape != low.shape:
            raise ValueError(
                f"expected observation bounds of shape ({7 + self.lidar_rays},), "
                f"got {low.shape} and {high.shape}"
            )
        if not (np.isfinite(low).all() and np.isfinite(high).all() and (high > low).all()):
            raise ValueError("expected finite observation bounds with high > low")
        for name in ("wheel_speed", "lidar_range"):
            object.__setattr__(self, name, check_number(name, getattr(self, name), 0.0))
        low.flags.writeable = high.flags.writeable = False
        object.__setattr__(self, "observation_low", low)
        object.__setattr__(self, "observation_high", high)

    @property
    def n_inputs(self) -> int:
        """d = 7 + k features per observation."""
        return 7 + self.lidar_rays

    @property
    def layer_shapes(self) -> tuple[tuple[int, int], ...]:
        """(out, in) of each layer's weights, in the order of the flat vector."""
        if self.hidden == 0:
            return ((2, self.n_inputs),)
        return ((self.hidden, self.n_inputs), (2, self.hidden))

    @property
    def n_parameters(self) -> int:
        """Length n of the flat parameter vector (:func:`parameter_count`)."""
        return parameter_count(self.n_inputs, self.hidden)

    def scaled(self, observations: np.ndarray) -> np.ndarray:
        """``observations`` float64 (..., d) rescaled to [−1, 1] (step 1 of the module doc)."""
        span = self.observation_high - self.observation_low
        unit = 2.0 * (observations - self.observation_low) / span - 1.0
        return np.asarray(np.clip(unit, -1.0, 1.0), dtype=np.float64)

    def forward(self, parameters: np.ndarray, observations: np.ndarray) -> np.ndarray:
        """Wheel speeds float64 (P, M, 2) (ω_L, ω_R) [rad/s] of P policies, ``parameters``
        float64 (P, n), each at its own M observations ``observations`` float64 (P, M, d)."""
        parameters = np.asarray(parameters, dtype=np.float64)
        observations = np.asarray(observations, dtype=np.float64)
        population = parameters.shape[0]
        if parameters.shape != (population, self.n_parameters):
            raise ValueError(
                f"expected parameters of shape (P, {self.n_parameters}), got {parameters.shape}"
            )
        if observations.ndim != 3 or observations.shape[::2] != (population, self.n_inputs):
            raise ValueError(
                f"expected observations of shape ({population}, M, {self.n_inputs}), "
                f"got {observations.shape}"
            )
        activations = self.scaled(observations)
        for weights, biases in self._layers(parameters):
            # (P, out, in) · (P, M, in) → (P, M, out): each policy on its own rows only.
            activations = np.tanh(
                np.einsum("poi,pmi->pmo", weights, activations) + biases[:, None, :]
            )
        return self.wheel_speed * activations

    def _layers(self, parameters: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """(weights (P, out, in), biases (P, out)) of each layer, views of ``parameters``."""
        layers, start = [], 0
        for rows, columns in self.layer_shapes:
            weights = parameters[:, start : start + rows * columns]
            start += rows * columns
            biases = parameters[:, start : start + rows]
            start += rows
            layers.append((weights.reshape(-1, rows, columns), biases))
        return layers

    def same_as(self, other: PolicyLayout) -> bool:
        """Whether ``other`` gives every parameter vector the same meaning."""
        return (
            self.hidden == other.hidden
            and self.lidar_rays == other.lidar_rays
            and self.wheel_speed == other.wheel_speed
            and self.lidar_range == other.lidar_range
            and np.array_equal(self.observation_low, other.observation_low)
            and np.array_equal(self.observation_high, other.observation_high)
        )


def parameter_count(n_inputs: int, hidden: int) -> int:
    """Length n of the flat parameter vector of a policy of ``n_inputs`` features and ``hidden``
    tanh units: (d + 1)·H + (H + 1)·2, or (d + 1)·2 without a hidden layer.

    >>> parameter_count(15, 8), parameter_count(15, 0)
    (146, 32)
    """
    if hidden == 0:
        return (n_inputs + 1) * 2
    return (n_inputs + 1) * hidden + (hidden + 1) * 2


class TanhPolicy:
    """One parameter vector of a :class:`PolicyLayout`: a
    :class:`~skidnav.agents.wheel_policy.WheelSpeedPolicy`.

    Args:
        layout: the meaning of the parameters.
        parameters: float64 (n,), finite; copied and frozen.
    """

    def __init__(self, layout: PolicyLayout, parameters: Sequence[float] | np.ndarray) -> None:
        values = np.array(parameters, dtype=np.float64)
        if values.shape != (layout.n_parameters,) or not np.isfinite(values).all():
            raise ValueError(
                f"expected {layout.n_parameters} finite parameters, got shape {values.shape}"
            )
        values.flags.writeable = False
        self.layout = layout
        self.parameters = values
        self.lidar_rays = layout.lidar_rays
        self.lidar_range = layout.lidar_range

    def batch_wheel_speeds(self, observations: np.ndarray) -> np.ndarray:
        """Wheel speeds float64 (N, 2) (ω_L, ω_R) [rad/s] at N observations float64 (N, d)."""
        observations = np.asarray(observations, dtype=np.float64)
        if observations.ndim != 2:
            raise ValueError(f"expected observations of shape (N, d), got {observations.shape}")
        speeds = self.layout.forward(self.parameters[None, :], observations[None])
        return np.asarray(speeds[0], dtype=np.float64)

    def wheel_speeds(self, observation: np.ndarray) -> tuple[float, float]:
        """(ω_L, ω_R) [rad/s] for one observation float64 (d,)."""
        left, right = self.batch_wheel_speeds(np.asarray(observation)[None, :])[0].tolist()
        return left, right
