"""Hyperparameters of ``mppi-kinematic``: one frozen dataclass, validated on construction.

>>> MPPIConfig(samples=128).horizon is None  # derived from the control period
True
>>> with_horizon(MPPIConfig(), 1.0).horizon, with_horizon(MPPIConfig(), 0.1).horizon
(10, 40)
>>> MPPIConfig(temperature=0.0)
Traceback (most recent call last):
...
ValueError: expected temperature to be a finite number in (0, 1e+12], got 0.0
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from skidnav.agents.config import KinematicModelFields
from skidnav.checks import check_integer, check_number
from skidnav.errors import shown
from skidnav.files.configtables import check_keys

MAX_SAMPLES = 65_536
"""Most sampled wheel-speed sequences K per control step."""
MAX_HORIZON = 10_000
"""Longest horizon H [control steps]."""
LOOKAHEAD_TIME = 10.0
"""How far ahead [s] the default horizon looks, at most :data:`DEFAULT_MAX_HORIZON` control
steps: 10 steps of 1-s actions, where 40 steps (40 s) made every perturbed sequence meet a wall
and 10 let every maze run of the targets' grid learn (docs/agents/mppi-kinematic.md, "The horizon
in seconds")."""
DEFAULT_MAX_HORIZON = 40
"""Most control steps of the default horizon: 40 × 0.1 s = 4 s at the 0.1-s period, the
setting every 0.1-s table was measured at (against 20 and 60), and the cost of a control step
grows with it."""
MAX_ROLLOUT_STEPS = 10_000_000
"""Most K · M · H per control step: the pre-drawn normals take 7 · 8 bytes each (about 0.5 GB)."""
MAX_MODEL_DRAWS = 64
"""Most model draws M per sequence."""
RISKS = ("mean", "worst")
"""Values of :attr:`MPPIConfig.risk`."""
MAX_DURATIONS = 8
"""Most lattice durations."""
COST_TO_GO = ("states", "cells")
"""Values of :attr:`MPPIConfig.cost_to_go`."""
ROUTE_SPEEDS = ("nominal", "learned")
"""Values of :attr:`MPPIConfig.route_speed`."""
PLAN_UPDATES = ("clipped", "drawn")
"""Values of :attr:`MPPIConfig.plan_update`."""
PRECISIONS = ("float64", "float32")
"""Values of :attr:`MPPIConfig.precision`."""
LATTICE_GUARDS = ("rings", "window")
"""Values of :attr:`MPPIConfig.lattice_guard`."""
CHOICES = {
    "risk": RISKS,
    "cost_to_go": COST_TO_GO,
    "route_speed": ROUTE_SPEEDS,
    "plan_update": PLAN_UPDATES,
    "precision": PRECISIONS,
    "lattice_guard": LATTICE_GUARDS,
}
"""The fields of :class:`MPPIConfig` that take one of a few names, and those names."""
MAX_COST = 1e12
"""Greatest cost weight [cost units]: sums of costs stay far from overflow."""


@dataclass(frozen=True)
class MPPIConfig(KinematicModelFields):
    """MPPI through the learned kinematic model (docs/agents/mppi-kinematic.md).

    Costs are in *control steps*, the unit of the env's reward: a control step costs 1 (the
    reward −1 of a free action), a collision ``collision_cost`` more (the reward −10). The
    kinematic model's fields (``kinematic_*``, :class:`KinematicModelFields`) are those of
    ``dyna-kinematic``, with refits sooner by default (every 50 new sub-steps, then doubling),
    since this agent plans with the model from its first real step; ``kinematic_model`` "prior"
    plans with the nominal robot throughout, "true" with the coefficients handed to the agent
    (a reference for tests; no robot offers them)."""

    samples: int = 256
    """K, wheel-speed sequences sampled per control step, in [2, 65,536]."""
    horizon: int | None = None
    """H, control steps each sequence looks ahead, in [1, 10,000]; None (the default): the
    steps of :data:`LOOKAHEAD_TIME` = 10 s at the control period, at most
    :data:`DEFAULT_MAX_HORIZON` = 40 (:func:`steps_ahead`): 40 steps of 0.1 s (4 s: a quarter
    turn takes 2.5 s; measured against 20 and 60), 10 steps of 1 s. The agent sets it when it
    learns its control period (:func:`with_horizon`). A count of steps alone does not carry
    across periods: 40 steps of 1-s actions look 40 s ahead, nearly every perturbed sequence
    meets a wall and the weights fall on one (docs/agents/mppi-kinematic.md, "The horizon in
    seconds")."""
    temperature: float = 0.1
    """λ [s] of the sequence weights exp(−S T / λ) (Williams et al. 2017), > 0: S is a
    sequence's cost in control steps of T seconds, so λ is a cost in seconds of driving and the
    weights are as selective whatever the control period (0.1 s: λ = 1 control step). A
    temperature fixed in control steps is ten times hotter at 1-s actions than at 0.1-s ones: a
    4-s horizon of 1-s actions then gains 1.4–3 control steps over standing still, the weights
    barely tell the sequences apart (effective sample size 240 of 256) and the plan averages to
    standing still (docs/agents/mppi-kinematic.md, "The stall")."""
    control_cost: float = 0.0
    """γ [cost units] of MPPI's control-cost term γ Σ_t U_tᵀ Σ⁻¹ ε_t, ≥ 0. Williams et al.
    (2017) use γ = λ; it amounts to a quadratic cost ½ γ uᵀ Σ⁻¹ u on the wheel speeds, at
    λ = 1 and σ = 0.6 rad/s about 8 per control step at top speed, eight times the time cost
    of a step: the robot then crawled, 1210 actions to the free map's goal against 100
    (docs/agents/mppi-kinematic.md). 0 (the default) leaves time and collisions the only
    costs."""
    noise_std: float = 0.6
    """σ [rad/s], the standard deviation of each wheel's sampled perturbation, > 0."""
    noise_correlation: float = 0.5
    """β in [0, 1): the perturbations follow ε_t = β ε_{t−1} + √(1 − β²) σ n_t over the
    horizon (n_t standard normal), so a larger β samples smoother sequences; 0: white noise."""
    plan_update: str = "clipped"
    """The perturbations the plan moves by, U ← clip(U + Σ_k w_k ε_k): "clipped", each
    sequence's clip(U + ε) − U, the change the robot could drive; "drawn", each ε as drawn
    (Williams et al. 2017's update), the rollouts still driving the clipped sequences. At a
    wheel's limit only the inward half of the clipped perturbations is non-zero, so "clipped"
    pulls a plan at full speed back inside the limit at every step (measured at 0.1-s actions
    on 8 free maps: 1.06–1.32× the goal tracker's time to the goal, "drawn" 0.86–1.07×; in the
    mazes at 1-s actions "drawn" is no better; docs/agents/mppi-kinematic.md, "The plan's
    update at the wheels' limits")."""
    collision_cost: float = 10.0
    """C [cost units] of running into a cell known for certain to be a wall; a cell of wall
    probability p costs C · p on entering, in [0, 10¹²]."""
    blocked_cost: float = 1000.0
    """Extra cost [cost units] of entering a blocked cell (wall evidence above free evidence)
    in the cost-to-go, in [0, 10¹²]: large, so the route goes around every known wall while a
    way exists, and finite, so every cell keeps a finite cost-to-go."""
    free_prior: float = 1.0
    """f₀ ≥ 0, pseudo-passes of free evidence every cell starts with: a cell of h collisions
    and f passes has wall probability h / (h + f + f₀) and is blocked while h > f + f₀
    (f₀ = 0: the rule of ``dyna-kinematic``, one collision blocks an unvisited cell)."""
    ray_weight: float = 2.0
    """w ≥ 0, the wall evidence of one lidar reading that ends in a cell, in collisions: a cell
    of h collisions, e reading ends, f passes and r crossing rays has wall probability
    W / (W + F), W = h + w e, F = f + r + f₀, and is blocked while W > F (the inverse sensor
    model of :mod:`skidnav.agents.mpc.laser`). 2: one reading blocks a cell nothing crossed
    (f₀ = 1); 0 ignores the readings' ends."""
    cost_to_go: str = "states"
    """The terminal value: "states", the heading-aware value over the discrete states through
    the model's predictions (:mod:`skidnav.agents.mpc.lattice`), or "cells", the shortest
    route over the cells with a turn-time term (:mod:`skidnav.agents.mpc.costmap`)."""
    lattice_durations: tuple[float, ...] = (0.5, 1.0)
    """Durations [s] the four actions of the states' lattice are held for, each a whole number
    of the robot's sub-steps, 1 to 8 of them (a list is stored as a tuple); 1 s: the thesis's
    actions, 3.8 cm or 36.5° each."""
    lattice_guard: str = "window"
    """Where the lattice of the states' cost-to-go predicts with the datasheet's robot instead of
    the learned fit (:func:`~skidnav.agents.mpc.dynamics.lattice_coefficients`): in a region
    whose fit has seen too few fast commands (fewer than ``kinematic_min_samples``), counted as
    "window" (the default), the commands in the fastest third of the wheel speed among the
    region's kept samples, whatever the rings, or as "rings", the fastest speed ring's samples
    ever fed (with one ring, the default of ``kinematic_speed_strata``, no region is guarded:
    the setting every measurement before 2026-12-08 used). The rollouts keep the learned
    model."""
    route_speed: str = "nominal"
    """("cells" only) The top speeds the cells' cost-to-go turns metres and radians into
    control steps with: "nominal", the datasheet robot's r·Ω and r·Ω/c (a lower bound of the
    time where the floor is slower); "learned", once the model has been refitted, the fastest
    forward speed and turn rate its mean predicts at full commands in any region
    (:func:`~skidnav.agents.mpc.dynamics.top_speeds`), so that on a floor ten times slower
    than the datasheet a metre of progress is worth ten times the control steps it is under
    "nominal" (docs/agents/mppi-kinematic.md, "On BARN")."""
    heading_weight: float = 1.0
    """("cells" only) Weight ≥ 0 of the terminal turn time: the time [control steps] to turn,
    at the nominal top yaw rate, to face (or back towards) the route's look-ahead cell."""
    lookahead: float = 0.08
    """("cells" only) How far along the learned route the terminal value aims [m], ≥ 0
    (0: the next cell); about what the robot drives in 2 s at top speed."""
    prior_spread: float = 0.2
    """Relative standard deviation ≥ 0 of each nominal slope of the kinematic model in a
    region with no fit yet (the prior's spread, sampled per sequence like a posterior)."""
    model_draws: int = 1
    """M, draws of the model each sequence is rolled out through, in [1, 64] (K · M · H ≤
    10⁷): its cost is their mean or worst (``risk``); 1: one draw per sequence, the role of one
    ensemble member in PETS (Chua et al. 2018)."""
    risk: str = "mean"
    """How a sequence's M costs become one: "mean" (the expected cost under the model's
    uncertainty) or "worst" (their largest)."""
    sample_uncertainty: bool = True
    """Draw the model per sequence (posterior weights and sub-step noise); False plans every
    sequence with the posterior mean."""
    footprint_padding: float = 0.02
    """Margin [m] added to each side of a robot's footprint (``RobotParams.footprint_length`` ×
    ``footprint_width``, the rectangle the simulator collides by) in the rollouts' collision rule
    and in the inscribed radius of the cost-to-go's lethal cells, in [0, 100]; a point robot
    (footprint 0 × 0, the thesis robot) stays a point."""
    kinematic_refit_every: int = 50
    """Minimum new sub-step samples between refits (checked after every real step)."""
    precision: str = "float64"
    """The numbers of the sampling and the rollouts: "float64", double precision, NumPy's
    normals (the ziggurat) in NumPy's order and the C library's sine and cosine, the path every
    measured table of docs/agents/mppi-kinematic.md drove; "float32", the fast path, single
    precision, normals by Box–Muller from the Generator's uniforms, polynomial sine and cosine,
    the rollouts vectorised over the samples (:mod:`~skidnav.agents.mpc.single`): other numbers
    (the same with and without numba), a control step about twice as fast
    (docs/agents/mppi-kinematic.md, "Speed")."""

    def __post_init__(self) -> None:
        self._check_sizes()
        for name, allowed in CHOICES.items():
            if getattr(self, name) not in allowed:
                raise ValueError(f"expected {name} in {allowed}, got {shown(getattr(self, name))}")
        if self.precision == "float32" and self.plan_update != "clipped":
            raise ValueError(
                f"expected plan_update 'clipped' with precision 'float32' (the fast path moves "
                f"the plan by the clipped perturbations), got {shown(self.plan_update)}"
            )
        check_number("temperature", self.temperature, 0.0, MAX_COST)
        check_number("noise_std", self.noise_std, 0.0, MAX_COST)
        correlation = self.noise_correlation
        if isinstance(correlation, bool) or not (
            isinstance(correlation, int | float) and 0.0 <= correlation < 1.0
        ):
            raise ValueError(f"expected noise_correlation in [0, 1), got {shown(correlation)}")
        for name in (
            "control_cost",
            "collision_cost",
            "blocked_cost",
            "free_prior",
            "ray_weight",
            "heading_weight",
        ):
            check_number(name, getattr(self, name), 0.0, MAX_COST, closed=True)
        durations = self.lattice_durations
        durations = tuple(durations) if isinstance(durations, list | tuple) else ()
        if not 1 <= len(durations) <= MAX_DURATIONS:
            raise ValueError(
                f"expected lattice_durations as 1 to {MAX_DURATIONS} numbers, got "
                f"{shown(self.lattice_durations)}"
            )
        for duration in durations:
            check_number("each lattice duration", duration, 0.0, 3600.0)
        object.__setattr__(self, "lattice_durations", durations)
        check_number("lookahead", self.lookahead, 0.0, 1e6, closed=True)
        check_number("prior_spread", self.prior_spread, 0.0, 10.0, closed=True)
        check_number("footprint_padding", self.footprint_padding, 0.0, 100.0, closed=True)
        if not isinstance(self.sample_uncertainty, bool):
            raise ValueError(
                f"expected sample_uncertainty true or false, got {self.sample_uncertainty!r}"
            )
        self.kinematic_config()  # validates the kinematic model's fields

    def _check_sizes(self) -> None:
        """K, H and M each in range, and K · H · M at most :data:`MAX_ROLLOUT_STEPS` (an unset
        horizon counted at its most, :data:`DEFAULT_MAX_HORIZON`)."""
        check_integer("samples", self.samples, 2, MAX_SAMPLES)
        if self.horizon is not None:
            check_integer("horizon", self.horizon, 1, MAX_HORIZON)
        check_integer("model_draws", self.model_draws, 1, MAX_MODEL_DRAWS)
        steps = DEFAULT_MAX_HORIZON if self.horizon is None else self.horizon
        rollout_steps = self.samples * steps * self.model_draws
        if rollout_steps > MAX_ROLLOUT_STEPS:
            raise ValueError(
                f"expected samples × horizon × model_draws at most {MAX_ROLLOUT_STEPS:,}, got "
                f"{rollout_steps:,}"
            )

    def to_dict(self) -> dict[str, Any]:
        """Every field, JSON-able (read back by :meth:`from_mapping`)."""
        return dataclasses.asdict(self)

    @property
    def horizon_steps(self) -> int:
        """H [control steps], once the horizon is set (:func:`with_horizon`)."""
        if self.horizon is None:
            raise ValueError("expected the horizon set for a control period (with_horizon)")
        return self.horizon

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any]) -> MPPIConfig:
        """A config from a mapping of its fields (a TOML table, a saved agent's JSON);
        ValueError in one line for an unknown key or a bad value."""
        check_keys(values, sorted(field.name for field in dataclasses.fields(cls)))
        return cls(**dict(values))


def steps_ahead(
    period: float, lookahead: float = LOOKAHEAD_TIME, most: int = DEFAULT_MAX_HORIZON
) -> int:
    """The control steps [1, ``most``] nearest to ``lookahead`` [s] at ``period`` [s] per step."""
    return int(min(most, max(1, round(lookahead / period))))


def with_horizon(config: MPPIConfig, period: float) -> MPPIConfig:
    """``config`` with its horizon in control steps of ``period`` [s]: as given, or, unset,
    :func:`steps_ahead` of the default look-ahead."""
    if config.horizon is not None:
        return config
    return dataclasses.replace(config, horizon=steps_ahead(period))
