"""Policy search by CMA-ES: the tanh policy's parameters optimised on the return of real episodes.

CMA-ES (Hansen & Ostermeier 2001; Hansen 2016, "The CMA Evolution Strategy: A Tutorial",
arXiv:1604.00772) samples λ parameter vectors from N(m, σ² C), ranks them by their score and
moves m, σ and C toward the better ones. Here (docs/agents/cmaes.md):

1. the parameters are those of :class:`~skidnav.agents.policies.search.tanh_policy.TanhPolicy`, from
   m = 0 (the policy that stands still), σ = ``sigma0``, C = I;
2. each generation asks λ candidates and scores each by its mean undiscounted return over
   ``episodes_per_candidate`` real episodes (plus ``progress_weight`` × its mean gain in goal
   distance [m], 0 by default), all λ · E episodes in one vector env
   (:class:`~skidnav.agents.policies.search.rollouts.PopulationRollouts`); CMA-ES minimises, so it
   is told the negated scores; the learning curve reports plain returns;
3. every candidate of a generation meets the same E episode seeds (common random numbers: the
   ranking compares policies, not slip noise); the seeds change from one generation to the next;
4. the distribution's mean m is the search's policy: after every ``eval_every``-th generation
   (and generation 0) it runs ``eval_episodes`` episodes on fixed evaluation seeds, the same for
   the whole search, for its mean return and success rate; after the last generation too, when
   that one is off the schedule, but that evaluation is in the result alone, never in the
   checkpoint, so a search extended with ``--resume`` records what one run would;
5. one root seed ``config.seed`` gives every random number, through three child streams
   (:data:`SEARCH_ROLES`): generation g's episode seeds are drawn from child g of the first,
   the evaluation seeds from the second, and the optimizer's generator is reseeded at
   generation g from child g of the third — so the same seed gives the same numbers, and a
   resumed search (:mod:`skidnav.agents.policies.search.checkpoint`) the same as one never stopped.

The learning curve counts real episodes: after generation g, λ · E · g of them (the mean's
evaluations are counted apart).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from threadpoolctl import threadpool_limits

from skidnav.agents.policies.search.checkpoint import (
    load_checkpoint,
    new_optimizer,
    save_checkpoint,
)
from skidnav.agents.policies.search.config import MAX_PARAMETER, SearchConfig
from skidnav.agents.policies.search.curve import GenerationRecord as GenerationRecord
from skidnav.agents.policies.search.curve import record_rows as record_rows
from skidnav.agents.policies.search.curve import scheduled
from skidnav.agents.policies.search.rollouts import EpisodeBatch, PopulationRollouts
from skidnav.agents.policies.search.tanh_policy import TanhPolicy
from skidnav.agents.saving import save_paths
from skidnav.errors import UserError, first_line
from skidnav.seeding import child, child_sequences

logger = logging.getLogger(__name__)

SEARCH_ROLES = ("episodes", "evaluation", "sampler")
"""Children of ``SeedSequence(config.seed)``: per-generation episode seeds (child g of it for
generation g), the fixed evaluation seeds, the optimizer's per-generation reseeding."""


class SearchResult(NamedTuple):
    """What :func:`run_search` returns."""

    policy: TanhPolicy
    """The distribution's mean after the last generation."""
    records: tuple[GenerationRecord, ...]
    """The learning curve, generations 0 .. ``config.generations``."""
    config: SearchConfig


def generation_seeds(config: SearchConfig, generation: int) -> list[int]:
    """The E episode seeds every candidate of ``generation`` (1-based) meets."""
    stream = child(child_sequences(config.seed, SEARCH_ROLES)["episodes"], generation)
    return [int(s) for s in stream.generate_state(config.episodes_per_candidate)]


def evaluation_seeds(config: SearchConfig) -> list[int]:
    """The fixed episode seeds of the mean policy's evaluations."""
    stream = child_sequences(config.seed, SEARCH_ROLES)["evaluation"]
    return [int(s) for s in stream.generate_state(config.eval_episodes)]


def sampler_seed(config: SearchConfig, generation: int) -> int:
    """The seed (32-bit) of the optimizer's generator for ``generation`` (1-based)."""
    stream = child(child_sequences(config.seed, SEARCH_ROLES)["sampler"], generation)
    return int(stream.generate_state(1)[0])


class CMAESSearch:
    """A search in progress: the optimizer, the two vector envs, the learning curve.

    Args:
        config: the search. checkpoint: ``NAME`` of a checkpoint written after every
            generation (None: none). resume: continue from that checkpoint (it must exist and
            its config must equal ``config`` but for ``generations``).
    """

    def __init__(
        self, config: SearchConfig, checkpoint: str | Path | None = None, resume: bool = False
    ) -> None:
        if resume and checkpoint is None:
            raise ValueError("expected a checkpoint to resume from")
        self.config, self.checkpoint = config, checkpoint
        options = config.env_options()
        self.rollouts = _rollouts(config.population, config.episodes_per_candidate, options)
        try:
            self.evaluation = _rollouts(1, config.eval_episodes, options)
        except BaseException:
            self.rollouts.close()
            raise
        self.layout = self.rollouts.layout(config.hidden)
        self.evaluation_seeds = evaluation_seeds(config)
        self.records: list[GenerationRecord] = []
        self.optimizer = new_optimizer(config, self.layout.n_parameters)
        self._clock_offset = 0.0
        if resume:
            assert checkpoint is not None
            try:
                self._resume(checkpoint)
            except BaseException:
                self.close()
                raise

    def _resume(self, checkpoint: str | Path) -> None:
        optimizer, saved, records = load_checkpoint(checkpoint, self.layout.n_parameters)
        where = save_paths(checkpoint)[0]
        if not self.config.resumes(saved):
            raise UserError(f"{where}: saved for another search (only generations may differ)")
        if optimizer.generation > self.config.generations:
            raise UserError(
                f"{where}: already {optimizer.generation} generations, more than the "
                f"{self.config.generations} asked for"
            )
        self.records = records
        self.optimizer = optimizer
        self._clock_offset = self.records[-1].wall_time

    @property
    def generation(self) -> int:
        """Generations done."""
        return int(self.optimizer.generation)

    def mean_policy(self) -> TanhPolicy:
        """The distribution's mean as a policy."""
        return TanhPolicy(self.layout, self.optimizer.mean)

    def run(self, on_generation: Callable[[GenerationRecord], None] | None = None) -> SearchResult:
        """Run the generations left; ``on_generation`` is called with every new record, the
        last one after the mean's final evaluation.

        The evaluations after generation g are those of
        :func:`~skidnav.agents.policies.search.curve.scheduled` (g a multiple of ``eval_every``),
        whatever the search's length: the records and the checkpoint hold those alone, so a search
        resumed with more generations records what one run of them would. The mean after the last
        generation is evaluated besides when that generation is not scheduled: its record, in the
        result only, gets the evaluation.
        """
        start = time.perf_counter() - self._clock_offset
        report = on_generation if on_generation is not None else _ignore
        unreported = not self.records  # the last record is this run's, not yet reported
        if unreported:
            self._record(start, math.nan, math.nan)
        while self.generation < self.config.generations:
            if unreported:  # another generation follows: that record is final
                report(self.records[-1])
            scores = self.advance().mean_returns
            self._record(start, float(scores.max()), float(scores.mean()))
            unreported = True
            if self.checkpoint is not None:
                save_checkpoint(self.checkpoint, self.optimizer, self.config, self.records)
        records = list(self.records)
        if not scheduled(self.generation, self.config.eval_every):
            records[-1] = self._evaluated(records[-1], start)
            unreported = True
        if unreported:
            report(records[-1])
        return SearchResult(self.mean_policy(), tuple(records), self.config)

    def advance(self) -> EpisodeBatch:
        """One generation more: ask / score / tell, not recorded (:meth:`run` records it); the
        batch of its λ × E episodes, whose ``mean_returns`` are the λ scores. UserError when a
        candidate reaches :data:`~skidnav.agents.policies.search.config.MAX_PARAMETER` (the
        search diverged)."""
        generation = self.generation + 1
        self.optimizer.reseed_rng(sampler_seed(self.config, generation))
        candidates = np.array([self.optimizer.ask() for _ in range(self.config.population)])
        if not (np.abs(candidates) < MAX_PARAMETER).all():  # NaN fails too
            raise UserError(
                f"generation {generation}: a candidate's parameter is not below "
                f"{MAX_PARAMETER:g} in magnitude (σ {self.optimizer._sigma:.3g}): the search "
                "diverged; start it with a smaller sigma0"
            )
        batch = self.rollouts.run(
            self.layout, candidates, generation_seeds(self.config, generation)
        )
        fitness = batch.mean_returns + self.config.progress_weight * batch.progress.mean(axis=1)
        self.optimizer.tell([(x, -float(f)) for x, f in zip(candidates, fitness, strict=True)])
        return batch

    def _record(self, start: float, best: float, population_mean: float) -> None:
        """Append the record of the generation just done (``start``: the clock's zero [s]), with
        the mean's evaluation if :func:`~skidnav.agents.policies.search.curve.scheduled`."""
        generation = self.generation
        evaluated = self.records[-1].evaluation_episodes if self.records else 0
        record = GenerationRecord(
            generation, generation * self.config.episodes_per_generation, evaluated,
            time.perf_counter() - start, best, population_mean,
            float(self.optimizer._sigma),  # cmaes has no public σ; the checkpoint saves it too
            math.nan, math.nan,
        )  # fmt: skip
        if scheduled(generation, self.config.eval_every):
            record = self._evaluated(record, start)
        self.records.append(record)
        logger.info("generation %d: %s", generation, record)

    def _evaluated(self, record: GenerationRecord, start: float) -> GenerationRecord:
        """``record`` with the current mean's evaluation on the evaluation seeds (its return,
        success rate and episode count) and the wall time after it."""
        mean = self.optimizer.mean[None, :]
        batch = self.evaluation.run(self.layout, mean, self.evaluation_seeds)
        return record._replace(
            evaluation_episodes=record.evaluation_episodes + self.config.eval_episodes,
            wall_time=time.perf_counter() - start,
            mean_return=float(batch.returns.mean()),
            mean_success=float(batch.successes.mean()),
        )

    def close(self) -> None:
        """Close both vector envs."""
        self.rollouts.close()
        self.evaluation.close()


def _ignore(record: GenerationRecord) -> None:
    """No report."""


def _rollouts(population: int, episodes: int, options: dict[str, Any]) -> PopulationRollouts:
    """The :class:`PopulationRollouts` of ``population`` × ``episodes`` sub-envs of the env
    ``options``; UserError in one line when the env refuses them."""
    try:
        return PopulationRollouts(population, episodes, options)
    except ValueError as error:
        raise UserError(f"cannot build the search's env: {first_line(error)}") from None


def run_search(
    config: SearchConfig,
    *,
    checkpoint: str | Path | None = None,
    resume: bool = False,
    on_generation: Callable[[GenerationRecord], None] | None = None,
) -> SearchResult:
    """Run the search of ``config`` (module doc); see :class:`CMAESSearch` for the arguments.

    NumPy's BLAS runs on one thread meanwhile: the optimizer's small matrix products (n × n, n
    the parameters) spread over threads took 6× longer on a loaded 2-core machine than on one
    (measured: 7.9 s against 1.3 s for 5 generations of λ 32, n 146), and the runner already
    gives each process one core."""
    search = CMAESSearch(config, checkpoint, resume)
    try:
        with threadpool_limits(limits=1):
            return search.run(on_generation)
    finally:
        search.close()
