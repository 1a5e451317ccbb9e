"""The sim-to-sim transfer study as ``skidnav run`` executes it (``kind = "transfer"``,
:mod:`skidnav.studies.kind`): its config becomes a
:class:`~skidnav.studies.transfer.grid.TransferGrid`, whose runs (agent × seed) the runner
executes with :func:`transfer_trial`, one run file each; ``skidnav study transfer`` writes the
same config from its flags and runs it the same way.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict
from pathlib import Path
from typing import Any

from skidnav.agents.catalog import entry, family
from skidnav.errors import ConfigError, UserError, shown, within
from skidnav.experiments.runner import TrialFunction
from skidnav.experiments.runs import RunSpec
from skidnav.experiments.store import RunLayout, TrialResult
from skidnav.physics.backend import PhysicsUnavailable, load_mujoco
from skidnav.studies.agent_grid import read_grid, training_episodes
from skidnav.studies.kind import STUDY_BACKENDS
from skidnav.studies.transfer.evaluation import transfer_run
from skidnav.studies.transfer.grid import KIND, LAYOUT, TransferGrid
from skidnav.studies.transfer.report import report_section


def transfer_trial(spec: RunSpec[TransferGrid]) -> TrialResult:
    """Run ``spec``: its agent trained on the kinematic simulator of seed ``spec.seed``'s world,
    its greedy policy evaluated there and on the MuJoCo robot; the training episodes, and the
    :class:`~skidnav.studies.transfer.evaluation.TransferResult` but agent and seed (the run's
    coordinates) as the summary.

    Raises:
        UserError: MuJoCo cannot be loaded.
    """
    grid = spec.config
    try:
        result, log = transfer_run(
            spec.agent.name, spec.seed, grid.episodes, params=spec.agent.params_dict(),
            env_options=grid.env_options, rollouts=grid.rollouts, max_steps=grid.max_steps,
        )  # fmt: skip
    except PhysicsUnavailable as error:
        raise UserError(str(error)) from None
    summary = {key: value for key, value in asdict(result).items() if key not in ("agent", "seed")}
    return TrialResult(spec.run_id, spec.coordinates, training_episodes(log), summary, {})


class TransferStudy:
    """The :class:`~skidnav.studies.kind.Study` of ``kind = "transfer"``."""

    kind: str = KIND
    layout: RunLayout = LAYOUT
    backends = STUDY_BACKENDS

    def grid(self, document: Mapping[str, Any], path: Path) -> TransferGrid:
        """The validated grid of a parsed config; every agent a tabular one, its params checked
        as a new agent would check them.

        Raises:
            UserError: one line naming ``path`` and the key or agent.
        """
        grid = read_grid(TransferGrid, document, path, KIND)
        known = family("tabular").agents
        for agent in grid.agents:
            if agent.name not in known:
                problem = f"expected name to be a tabular agent, got {shown(agent.name)}"
                detail = f"tabular agents: {', '.join(known)}"
                raise ConfigError(problem, (str(path), "[[agents]]"), detail)
            try:
                entry(agent.name).config(agent.params_dict())
            except UserError as error:
                raise within(within(error, "[[agents]]"), str(path)) from None
        return grid

    def trial(self, grid: TransferGrid, out: Path) -> TrialFunction:
        """:func:`transfer_trial`, once MuJoCo loads (UserError naming what is missing)."""
        try:
            load_mujoco()
        except PhysicsUnavailable as error:
            raise UserError(str(error)) from None
        return transfer_trial

    def report(self, run_dir: Path) -> str:
        """The study's table (:func:`~skidnav.studies.transfer.report.report_section`)."""
        return report_section(run_dir)


STUDY = TransferStudy()
"""The transfer study (:data:`skidnav.studies.kind.STUDY_MODULES`)."""
