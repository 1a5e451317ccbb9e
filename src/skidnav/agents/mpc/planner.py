"""Model predictive path integral control (MPPI; Williams et al. 2017, "Information theoretic
MPC for model-based reinforcement learning", ICRA, Algorithm 2) over the two wheel speeds.

Each control step, from the robot's pose and the plan U (H, 2) [rad/s] kept from the last step:

1. draw K perturbation sequences ε (K, H, 2): ε_t = β ε_{t−1} + √(1 − β²) σ n_t, n_t standard
   normal (β = 0: the white noise of Williams et al.; β > 0 samples smoother sequences, ours);
   sequence 0 is the plan itself (ε = 0);
2. clip U + ε to the wheel-speed bounds ± Ω and keep the clipped perturbation
   ε ← clip(U + ε) − U (the sequence the robot could drive; ``plan_update = "drawn"`` keeps
   ε as drawn for step 4, the rollouts still driving clip(U + ε):
   :attr:`~skidnav.agents.mpc.config.MPPIConfig.plan_update`);
3. roll every sequence out through each of its M draws of the learned model and cost it
   (:func:`~skidnav.agents.mpc.rollouts.rollout_costs`); its cost S_k is the mean of the M
   costs (``risk = "mean"``, the expected cost under the model's uncertainty, as the particles
   of PETS, Chua et al. 2018) or their largest (``risk = "worst"``, the worst case over the
   draws); add the control cost
   γ Σ_t U_tᵀ Σ⁻¹ ε_t, Σ = σ² I (Williams et al. 2017, with γ = λ there; a parameter here,
   0 by default: :attr:`~skidnav.agents.mpc.config.MPPIConfig.control_cost`);
4. weigh the sequences w_k ∝ exp(−(S_k − min S) T / λ), S in control steps of T seconds and
   the temperature λ in seconds (so the weights do not depend on the control period), and move
   the plan: U ← clip(U + Σ_k w_k ε_k, −Ω, Ω);
5. command U_0, then shift the plan by one step for the next control step (warm start), the
   last step repeated.

Steps 1–2 and every random number are compiled (:mod:`~skidnav.agents.mpc.sampling`: the
planner's Generator's ``standard_normal`` in a fixed order, the perturbations, then the model
draws and the noise of :class:`~skidnav.agents.mpc.rollouts.RolloutDraws`, into arrays kept
from step to step), then the rollouts (3); the rollout kernel draws none. The costs' reduction,
the weights and the update (3–5) stay NumPy's, whose sums they were measured with.
"""

from __future__ import annotations

import math

import numpy as np

from skidnav.agents.mpc.config import MPPIConfig
from skidnav.agents.mpc.costmap import CostMap, MapCosts
from skidnav.agents.mpc.dynamics import N_DRAWS, SampledDynamics
from skidnav.agents.mpc.rollouts import RolloutDraws, rollout_costs
from skidnav.agents.mpc.sampling import sample_batch
from skidnav.agents.mpc.single_rollouts import single_rollout_costs
from skidnav.agents.mpc.single_sampling import SingleBatch, sample_single, single_batch
from skidnav.agents.mpc.single_update import update_plan
from skidnav.robot.params import KinematicConstants
from skidnav.world.discretization import GridShape


class MPPIPlanner:
    """The MPPI loop of the module doc for one robot.

    Args:
        config: K, H, λ, σ, β and whether to sample the model.
        robot: the robot's timing, arena, scheme and wheel-speed bound Ω [rad/s].
        grid: the discretization.
        rng: the source of every draw.
    """

    def __init__(
        self,
        config: MPPIConfig,
        robot: KinematicConstants,
        grid: GridShape,
        rng: np.random.Generator,
    ) -> None:
        self.config, self.robot, self.grid, self.rng = config, robot, grid, rng
        self.plan = np.zeros((config.horizon_steps, 2))
        """float64 (H, 2): the wheel speeds (ω_L, ω_R) [rad/s] planned for the next H steps."""
        self.costs = np.zeros(config.samples)
        """float64 (K,): the last batch's sequence costs, control cost included."""
        self.draw_costs = np.zeros(config.samples * config.model_draws)
        """float64 (K · M,): the last batch's cost of each sequence under each model draw."""
        self.weights = np.zeros(config.samples)
        """float64 (K,): the last batch's weights (summing to 1)."""
        self._batch: tuple[np.ndarray, np.ndarray, RolloutDraws] | None = None
        self._single: SingleBatch | None = None
        self.single = config.precision == "float32"
        """The fast path (``precision = "float32"``): its sequences are float32 (H, 2, K)."""
        self.temperature = config.temperature / (robot.dt * robot.substeps)
        """λ / T: the temperature in control steps (the costs' unit)."""

    def reset(self) -> None:
        """Forget the plan (a new episode): the next step starts from U = 0."""
        self.plan[...] = 0.0

    def sample(self) -> tuple[np.ndarray, np.ndarray, RolloutDraws]:
        """Steps 1–2 and the draws of step 3, compiled
        (:func:`~skidnav.agents.mpc.sampling.sample_batch`): the sequences clip(U + ε) float64
        (K, H, 2) [rad/s], their clipped perturbations ε float64 (K, H, 2) [rad/s], sequence 0
        the plan itself, and the rollouts' model draws and noise (standard normals; zeros when
        the model is not sampled). The arrays are the planner's, overwritten by the next call."""
        config = self.config
        if self.single:
            return self.sample_single()
        if self._batch is None:  # allocated once, at the first plan
            shape = (config.samples, config.horizon_steps, 2)
            rollouts = config.samples * config.model_draws
            scale = 1.0 / math.sqrt(self.robot.substeps) if config.sample_uncertainty else 0.0
            draws = RolloutDraws(
                np.zeros((rollouts, N_DRAWS)), np.zeros((rollouts, config.horizon_steps, 3)), scale,
                config.model_draws,
            )  # fmt: skip
            self._batch = np.zeros(shape), np.zeros(shape), draws
        controls, perturbation, draws = self._batch
        sample_batch(
            self.rng, self.plan, config.noise_std, config.noise_correlation,
            self.robot.wheel_speed, controls, perturbation, draws.model, draws.noise,
            config.sample_uncertainty, config.plan_update == "drawn",
        )  # fmt: skip
        return self._batch

    def sample_single(self) -> tuple[np.ndarray, np.ndarray, RolloutDraws]:
        """:meth:`sample` of the fast path (:mod:`~skidnav.agents.mpc.single_sampling`): the
        sequences and their perturbations float32 (H, 2, K) [rad/s], the model draws float32
        (5, K · M) and the noise float32 (H, 3, K · M)."""
        config = self.config
        if self._single is None:
            scale = 1.0 / math.sqrt(self.robot.substeps) if config.sample_uncertainty else 0.0
            self._single = single_batch(
                config.samples, config.horizon_steps, config.model_draws, scale,
                config.sample_uncertainty,
            )  # fmt: skip
        scales = (config.noise_std, config.noise_correlation, self.robot.wheel_speed)
        sample_single(self.rng, self.plan, scales, self._single)
        return self._single.controls, self._single.perturbation, self._single.draws

    def step(
        self,
        pose: np.ndarray,
        dynamics: SampledDynamics,
        cost_map: CostMap,
        costs: MapCosts,
    ) -> tuple[float, float]:
        """Steps 1–5 of the module doc from ``pose`` (x [m], y [m], heading [rad]); returns
        the wheel speeds (ω_L, ω_R) [rad/s] to command now."""
        controls, perturbation, draws = self.sample()
        start = np.asarray(pose, dtype=np.float64)
        if self.single:
            per_sequence = draws.per_sequence
            wheels = controls if per_sequence == 1 else np.repeat(controls, per_sequence, 2)
            single_rollout_costs(
                start, wheels, draws, dynamics, cost_map, costs, self.robot, self.grid,
                self.draw_costs,
            )  # fmt: skip
        else:
            rollout_costs(
                start, controls, draws, dynamics, cost_map, costs, self.robot, self.grid,
                self.draw_costs,
            )  # fmt: skip
        return self.update(perturbation)

    def update(self, perturbation: np.ndarray) -> tuple[float, float]:
        """Steps 3 (from the rollouts' costs in :attr:`draw_costs`) to 5 for the clipped
        perturbations ``perturbation`` float64 (K, H, 2) [rad/s]: the sequences' costs, their
        weights, the plan moved and shifted; returns the wheel speeds (ω_L, ω_R) [rad/s] to
        command now. In NumPy: its sums are NumPy's, whose order the numbers keep. On the fast
        path (perturbations float32 (H, 2, K)) the same steps compiled, each sum in a fixed
        order (:func:`~skidnav.agents.mpc.single_update.update_plan`)."""
        config, limit = self.config, self.robot.wheel_speed
        if self.single:
            scales = (
                config.risk == "worst", config.control_cost / config.noise_std**2,
                self.temperature, limit, float(config.model_draws),
            )  # fmt: skip
            return update_plan(
                self.draw_costs, perturbation, scales, self.plan, self.costs, self.weights
            )
        per_sequence = self.draw_costs.reshape(config.samples, config.model_draws)
        if config.risk == "worst":
            per_sequence.max(axis=1, out=self.costs)
        else:
            per_sequence.mean(axis=1, out=self.costs)
        if config.control_cost > 0.0:
            control_cost = np.einsum("ha,kha->k", self.plan, perturbation)
            self.costs += config.control_cost / config.noise_std**2 * control_cost
        shifted = self.costs - self.costs.min()
        np.exp(-shifted / self.temperature, out=self.weights)
        self.weights /= self.weights.sum()
        self.plan += np.einsum("k,kha->ha", self.weights, perturbation)
        np.clip(self.plan, -limit, limit, out=self.plan)
        left, right = float(self.plan[0, 0]), float(self.plan[0, 1])
        self.plan[:-1] = self.plan[1:].copy()
        return left, right

    @property
    def effective_samples(self) -> float:
        """1 / Σ w_k² of the last batch: how many sequences the update really averaged."""
        return float(1.0 / np.square(self.weights).sum())
