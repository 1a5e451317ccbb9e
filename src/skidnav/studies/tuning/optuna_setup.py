"""The Optuna objects of a tuning search: the journal storage on one file, the sampler of each
trial (seeded so that a resumed study proposes what an uninterrupted one would have) and the
pruner (docs/tuning.md).
"""

from __future__ import annotations

import logging
import warnings
import zlib
from pathlib import Path

import numpy as np
import optuna

from skidnav.errors import CorruptFileError
from skidnav.experiments.journalfile import check_journal
from skidnav.studies.tuning.config import TuneConfig
from skidnav.studies.tuning.runs import TUNE_STREAM

logger = logging.getLogger(__name__)

SAMPLER_STREAM = 2
"""Child of the tuning root that seeds the samplers (0, 1: tuning worlds and runs)."""


def open_storage(journal: Path, repair: bool = True) -> optuna.storages.JournalStorage:
    """The journal storage on ``journal`` (created if missing), checked first
    (:func:`~skidnav.experiments.journalfile.check_journal`). With ``repair``, a last line cut
    short by a kill during a write is then dropped, so appending to the file stays valid (a
    reader leaves it: Optuna skips it).

    Raises:
        CorruptFileError: the journal is not one (nothing is changed then).
    """
    from optuna.storages.journal import JournalFileBackend, JournalFileOpenLock

    if journal.exists():
        check = check_journal(journal)
        if repair and check.torn_bytes:
            logger.warning("%s: dropping a last line cut short by an interruption", journal)
            with open(journal, "r+b") as handle:
                handle.truncate(check.complete_bytes)
    try:
        backend = JournalFileBackend(str(journal), lock_obj=JournalFileOpenLock(str(journal)))
        return optuna.storages.JournalStorage(backend)
    except (ValueError, KeyError, TypeError) as error:
        raise CorruptFileError(f"{journal}: not an Optuna journal ({error})") from None


def make_sampler(
    tune: TuneConfig, root_seed: int, label: str, finished: int
) -> optuna.samplers.BaseSampler:
    """The sampler of the next trial of ``label``'s study, seeded from the root seed, the label
    and the trials finished before it (module docs)."""
    key = (TUNE_STREAM, SAMPLER_STREAM, zlib.crc32(label.encode()), finished)
    seed = int(np.random.SeedSequence(root_seed, spawn_key=key).generate_state(1)[0])
    if tune.sampler == "random":
        return optuna.samplers.RandomSampler(seed=seed)
    with warnings.catch_warnings():  # experimental in Optuna 4, the default in Optuna 5
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        return optuna.samplers.TPESampler(
            seed=seed, n_startup_trials=tune.startup_trials, multivariate=True
        )


def make_pruner(tune: TuneConfig) -> optuna.pruners.BasePruner:
    """The pruner of every study: MedianPruner over seed steps, or none."""
    if tune.pruner == "none":
        return optuna.pruners.NopPruner()
    return optuna.pruners.MedianPruner(
        n_startup_trials=tune.pruner_startup_trials, n_warmup_steps=tune.pruner_warmup_seeds
    )
