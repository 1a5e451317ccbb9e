"""The learned kinematic model's refit: from the per-ring moments kept up to date sample by sample
(``incremental``, the default) against the rebuild of every fit from the raw window, both measured
in this run on one core, on the same samples.

A random drive of the slippery floor (world 0, uniformly random actions, 0.1-s sub-steps) fills
the default model (49 slip regions, windows of 500 samples); then, :data:`ROUNDS` times, the next
:data:`BATCH` samples are fed (``refit_every``'s default) and every region is refitted (the most
a refit does: the pooled model and all 49 regions). Each side's time is the median over the
rounds; the coefficients of the two are checked equal to floating-point rounding in each round.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from skidnav.models.kinematic import KinematicModel
from skidnav.models.kinematic_config import KinematicModelConfig
from skidnav.robot.params import RobotParams
from skidnav.studies.kinematic_models.trial import drive_log
from skidnav.world.discretization import Discretization

BATCH = 500
ROUNDS = 20
FILL = 20_000
TARGET_SECONDS = 0.010


def refit_seconds(rounds: int = ROUNDS) -> tuple[float, float]:
    """(incremental, full) median wall time [s] of a refit of every region, after each of
    ``rounds`` batches of :data:`BATCH` new samples."""
    log = drive_log(0, FILL + rounds * BATCH, "slippery", 0.0, 1.0e9)
    models = {
        incremental: KinematicModel(
            RobotParams(), Discretization(), KinematicModelConfig(incremental=incremental)
        )
        for incremental in (True, False)
    }
    times: dict[bool, list[float]] = {True: [], False: []}
    for model in models.values():
        model.feed(log[:FILL])
        model.refit()
    for start in range(FILL, FILL + rounds * BATCH, BATCH):
        for incremental, model in models.items():
            model.feed(log[start : start + BATCH])
            model.fitted_counts[:] = 0  # every region refits
            began = time.perf_counter()
            model.refit()
            times[incremental].append(time.perf_counter() - began)
        difference = np.abs(models[True].coefficients - models[False].coefficients).max()
        assert difference < 1e-9, f"incremental refit differs by {difference:g}"
    return statistics.median(times[True]), statistics.median(times[False])


def refit_rates(quick: bool) -> tuple[float, float]:
    """(incremental, full) refits per second (the speed guard's and the history's form)."""
    incremental, full = refit_seconds(5 if quick else ROUNDS)
    return 1.0 / incremental, 1.0 / full


def main() -> None:
    incremental, full = refit_seconds()
    print(
        f"kinematic model refit, all 49 regions, window 500, after {BATCH} new samples: "
        f"incremental {incremental * 1e3:.2f} ms, full rebuild {full * 1e3:.2f} ms "
        f"({full / incremental:.1f}× faster; target ≤ {TARGET_SECONDS * 1e3:.0f} ms: "
        f"{'met' if incremental <= TARGET_SECONDS else 'NOT met'})"
    )


if __name__ == "__main__":
    main()
