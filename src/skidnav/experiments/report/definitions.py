"""The metric definitions of an experiment report, with the experiment's own settings
(tolerance, window, rollouts, interval): folded below the report's headline
(:mod:`skidnav.experiments.report.html`), open on a click.
"""

from __future__ import annotations

import html

from skidnav.experiments.config import ExperimentConfig


def definitions(config: ExperimentConfig) -> str:
    """The metric definitions, with this experiment's tolerance, window and interval settings,
    in a ``<details>`` element (folded)."""
    tol, window, rollouts, level = (
        config.convergence_tolerance, config.convergence_window, config.eval_rollouts,
        config.convergence_level,
    )  # fmt: skip
    measured, optimum = (
        ("length", "L*") if config.convergence_objective == "actions"
        else ("cost (minus the reward without the goal bonus: the objective of the agents' "
              "reward)", "the oracle's C*, the least expected cost from the start")
    )  # fmt: skip
    return f"""<details><summary>Definitions: oracle, evaluation, convergence, speed-up,
intervals</summary><ul class="note">
<li><b>Oracle</b> L*: the expected number of actions from the start under the best policy of the
true transition model of the discretized MDP, estimated from the simulator itself
({config.oracle_samples} sampled poses per state and action) and solved by value iteration.</li>
<li><b>Evaluation</b>: after every training episode the greedy policy is rolled out
<b>{rollouts}</b> times from the start, each from a reset with one of {rollouts} fixed evaluation
seeds (the same after every episode and for every agent of a world).</li>
<li><b>Pass</b>: an evaluation passes when every rollout reaches the goal with a mean
{measured} within <b>{tol:.0%}</b> above {optimum}. (The oracle's own greedy policy over cells
can loop from the exact start pose; the share of its rollouts that reached the goal is the column
<code>oracle_rollout_success</code>: L* is a reference, not a policy every world lets a cell
policy follow.)</li>
<li><b>Convergence episode</b> (converged means it stays converged): the first passing episode e
from which the share of passing evaluations stays at least <b>{level:.0%}</b> to the end of the
run (over e … k for every k from e + {window - 1} on: at least <b>{window}</b> evaluations of
evidence). A run that passed for a while and then fell apart is not converged at its first good
stretch; a run with no such episode is <b>censored</b> at episode {config.episodes} − {window} + 1.
A longer run can only reveal that a policy did not stay (its convergence episode is the same or
later). Medians are Kaplan–Meier estimates; ∞ means more than half of the runs never converged.
<b>Pass share after convergence</b>: share of passing evaluations from the convergence episode
to the end; <b>after the first good window</b>: the same from the first {window} passes in a row
(the drift a first-window rule would hide); <b>last 10 %</b>: share of passing evaluations in
the last 10 % of episodes. Speed-up: KM median of the baseline / KM median of the agent; where
more than half of one side's runs are censored, its largest censoring time stands in for its
median and the speed-up is a bound: <b>≥</b> (baseline censored; no upper end), <b>≤</b> (agent
censored), or <b>unknown</b> (both). Probability of improvement (Agarwal et al. 2021):
the chance that a run of the agent converges before a run of the baseline, censored pairs scored
by Gehan's rule. The mean and IQM of the convergence episode below count censored runs at their
censoring time (biased low); use the medians for claims.</li>
<li><b>Optimality gap</b>: mean greedy length over the last {window} evaluations (rollouts that
reached the goal) / L* − 1.</li>
<li><b>Final greedy length</b>: actions (and metres travelled) of one greedy rollout from the start
after the last episode (the trajectory drawn below); only runs where it reached the goal, and
comparisons only over seeds where both agents' rollouts did.</li>
<li><b>Success rate</b>: share of training episodes that reached the goal within
{config.max_steps or "the environment's"} actions (all episodes, and the last 10 %).</li>
<li>Intervals: {config.confidence:.0%} percentile bootstrap over seeds,
{config.bootstrap_samples} resamples, seeded. IQM: mean of the middle 50 % of seeds.
Comparisons with the baseline <b>{html.escape(config.baseline)}</b> are paired by seed (every agent
meets the same maps and floors). "No significant difference" means the interval of the difference
contains 0; its width tells how large a difference could have gone unnoticed.</li></ul></details>"""
