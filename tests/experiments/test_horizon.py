"""The convergence episode of a real run does not depend on how long the run lasts."""

from __future__ import annotations

import dataclasses

import pytest

from skidnav.experiments.configfile import parse_config
from skidnav.experiments.runs import expand_runs
from skidnav.experiments.trial import run_trial

HORIZON_TOML = """
[experiment]
name = "horizon"
episodes = 60
max_steps = 200
seeds = 3
root_seed = 7
convergence_window = 5
eval_rollouts = 3
oracle_samples = 8

[[maps]]
kind = "free"

[[agents]]
name = "q-learning"
params = { alpha = 0.5 }

[[agents]]
name = "dyna-sweep"
params = { alpha = 0.5, planning_steps = 30 }
"""


def _convergence(episodes: int) -> dict[tuple[str, int], tuple[float, float]]:
    config = dataclasses.replace(parse_config(HORIZON_TOML), episodes=episodes)
    results = {}
    for spec in expand_runs(config):
        summary = run_trial(spec).summary
        results[spec.agent.label, spec.seed] = (
            summary["convergence_episode"],
            summary["converged"],
        )
    return results


@pytest.mark.timeout(600)
def test_same_run_stopped_at_n_or_2n_has_the_same_convergence_episode() -> None:
    window, short, long = 5, _convergence(60), _convergence(120)
    converged_early = [key for key, (_, converged) in short.items() if converged]
    assert converged_early, "no run converged: the test would check nothing"
    for key, (episode, converged) in short.items():
        if converged:
            assert long[key] == (episode, 1.0), key
        else:  # censored at N − W + 1: later, either still censored or converged after it
            assert episode == 60 - window + 1
            assert long[key][0] > episode, key
    # Q-learning does not get near the oracle in 120 episodes here: censored, not "converged
    # at the last episode".
    for seed in range(3):
        assert long["q-learning", seed] == (120 - window + 1, 0.0)
