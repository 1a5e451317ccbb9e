"""Survival statistics of convergence episodes, with right-censoring, and RL-evaluation statistics.

A training run either converges at episode ``e`` (an observed event, ``observed = 1``) or is
*right-censored* at ``c`` (``observed = 0``: it had not converged by episode ``c``, its true
convergence episode is > ``c``). Every function takes ``times`` (``e`` or ``c``, shape (n,)) and
``observed`` (1.0 / 0.0, shape (n,)), one entry per run; runs whose time or flag is NaN are dropped.

* Kaplan–Meier (1958) product-limit estimator S(t) = ∏_{t_i ≤ t} (1 − d_i / n_i), with d_i events
  at t_i and n_i runs still at risk; at tied times events come before censorings (a run censored
  at t was still at risk at t). Its median is the smallest t with S(t) ≤ 0.5, ``math.inf`` when
  more than half of the runs stay censored.
* Percentile bootstrap over runs (Efron & Tibshirani (1993) ch. 13) of the KM median and of
  speed-ups (ratio of KM medians, seeds resampled jointly when paired). An infinite resampled
  median is kept: percentiles then become infinite, which is the honest answer.
* Probability of improvement and performance profiles of Agarwal et al. (2021), "Deep RL at the
  edge of the statistical precipice", over convergence episodes (smaller = better); censored pairs
  are scored as in Gehan's (1965) generalized Wilcoxon test; each sample is resampled on its own
  (Agarwal's stratified bootstrap).

Every bootstrap is vectorized: a resample is a sorted row of indices into the sample sorted by
(time, event first), so each row is itself sorted and the KM product is one ``cumprod`` per row.

>>> times, observed = [1, 2, 2, 3, 4, 5], [1, 1, 0, 1, 0, 1]
>>> event_times, survival = kaplan_meier(times, observed)
>>> event_times.tolist(), survival.round(3).tolist()
([1.0, 2.0, 3.0, 5.0], [0.833, 0.667, 0.444, 0.0])
>>> km_median(times, observed)
3.0
>>> km_median([10, 10, 10, 4], [0, 0, 0, 1])
inf
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from skidnav.statistics.intervals import NAN_INTERVAL, ArrayLike, Interval

HALF = 0.5 + 1e-9
"""S(t) ≤ 0.5 test with a rounding margin: a per-run product such as 3/4 · 2/3 must count as 0.5."""


SPEEDUP_BOUNDS = ("", "lower", "upper", "unknown")
"""What a speed-up's estimate is: "" a ratio of two medians, "lower" a lower bound (the
baseline's median is censored), "upper" an upper bound (the agent's is), "unknown" (both are)."""


class SpeedupInterval(NamedTuple):
    """Speed-up KM-median(baseline) / KM-median(agent) (> 1: the agent converges sooner).

    ``bound`` (one of :data:`SPEEDUP_BOUNDS`) says what ``estimate`` is when a median is
    infinite (more than half of the runs censored): that side's largest censoring time stands
    in for it, so with the baseline censored the speed-up is at least ``estimate`` (``high`` is
    then inf: no upper end), with the agent censored at most ``estimate`` (``low`` is 0), and
    with both censored it is unknown (every field NaN). Every resample makes the same
    substitutions.
    """

    estimate: float
    low: float
    high: float
    bound: str = ""

    @property
    def interval(self) -> Interval:
        """The same numbers as a plain :class:`~skidnav.statistics.intervals.Interval` (bound
        dropped)."""
        return Interval(self.estimate, self.low, self.high)

    def words(self, digits: int = 2) -> str:
        """The speed-up as a reader should take it; no interval with one seed.

        >>> SpeedupInterval(12.3, 8.1, 20.0).words(1)
        '12.3× [8.1, 20.0]'
        >>> SpeedupInterval(4.0, 2.5, math.inf, "lower").words(1)
        '≥ 4.0× [2.5, ∞)'
        >>> SpeedupInterval(0.5, 0.0, 0.9, "upper").words(1)
        '≤ 0.5× (0, 0.9]'
        >>> SpeedupInterval(math.nan, math.nan, math.nan, "unknown").words()
        'unknown (both mostly censored)'
        """
        if self.bound == "unknown" or self.estimate != self.estimate:
            return "unknown (both mostly censored)"
        sign = {"lower": "≥ ", "upper": "≤ "}.get(self.bound, "")
        text = f"{sign}{self.estimate:.{digits}f}×"
        if self.low != self.low or self.high != self.high:  # one seed: no interval
            return text
        if self.bound == "lower":
            return f"{text} [{self.low:.{digits}f}, ∞)"
        if self.bound == "upper":
            return f"{text} (0, {self.high:.{digits}f}]"
        return f"{text} [{self.low:.{digits}f}, {self.high:.{digits}f}]"


class _Sample(NamedTuple):
    """Runs sorted by (time, event first), shape (n,) each; ``rank[i]`` = sorted position of run i
    of the (NaN-free) input."""

    times: np.ndarray
    observed: np.ndarray
    rank: np.ndarray


def _clean_runs(times: ArrayLike, observed: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Validated float times and boolean flags with NaN runs kept (dropped by the caller)."""
    t = np.asarray(times, dtype=np.float64).ravel()
    o = np.asarray(observed, dtype=np.float64).ravel()
    if t.shape != o.shape:
        raise ValueError(f"expected times and observed of the same length, got {t.size}, {o.size}")
    flags = o[~np.isnan(o)]
    if not np.all((flags == 0.0) | (flags == 1.0)):
        raise ValueError(f"expected observed flags 0 or 1, got {np.unique(flags).tolist()}")
    return t, o


def _runs(times: ArrayLike, observed: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Times and boolean event flags, shape (n,) each, runs with a NaN dropped, order kept."""
    t, o = _clean_runs(times, observed)
    keep = ~(np.isnan(t) | np.isnan(o))
    return t[keep], o[keep] == 1.0


def _sample(times: ArrayLike, observed: ArrayLike) -> _Sample:
    t, event = _runs(times, observed)
    order = np.lexsort((~event, t))  # by time, then events (False) before censorings
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return _Sample(t[order], event[order], rank)


def _step_survival(observed_rows: np.ndarray) -> np.ndarray:
    """KM survival just after each run of sorted rows, shape (m, n) → (m, n).

    Run k of a sorted row of n has n − k runs at risk; a tie group of d events at n at risk
    multiplies to ∏ (1 − 1/(n − j)) = (n − d)/n, so the value after a group is the KM value.
    """
    n = observed_rows.shape[-1]
    at_risk = n - np.arange(n)
    return np.cumprod(1.0 - observed_rows / at_risk, axis=-1)


def _rowwise_median(times_rows: np.ndarray, observed_rows: np.ndarray) -> np.ndarray:
    """KM median of each sorted row, shape (m, n) → (m,); inf when S stays above 0.5."""
    reached = _step_survival(observed_rows) <= HALF
    first = np.argmax(reached, axis=-1)
    medians = np.take_along_axis(times_rows, first[:, None], axis=-1)[:, 0]
    return np.where(reached.any(axis=-1), medians, np.inf)


def _rows(sample: _Sample, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Resampled runs from sorted positions, shape (m, n): each row stays sorted."""
    positions = np.sort(positions, axis=-1)
    return sample.times[positions], sample.observed[positions]


def _inf_percentiles(values: np.ndarray, confidence: float) -> tuple[float, float]:
    """Linear-interpolated percentiles that stay inf next to an inf (NumPy's give NaN there)."""
    ordered = np.sort(values)
    tail = (1.0 - confidence) / 2.0
    position = np.array([tail, 1.0 - tail]) * (ordered.size - 1)
    below, above = np.floor(position).astype(int), np.ceil(position).astype(int)
    fraction = position - below
    low_value, high_value = ordered[below], ordered[above]
    with np.errstate(invalid="ignore"):
        mixed = low_value + fraction * (high_value - low_value)
    bounds = np.where(fraction == 0.0, low_value, np.where(np.isinf(high_value), np.inf, mixed))
    return float(bounds[0]), float(bounds[1])


def _counts(picks: np.ndarray, n: int) -> np.ndarray:
    """How often each of n runs is drawn in each resample: picks (m, k) → counts (m, n)."""
    offsets = n * np.arange(picks.shape[0])[:, None]
    flat = np.bincount((picks + offsets).ravel(), minlength=picks.shape[0] * n)
    return flat.reshape(picks.shape[0], n).astype(np.float64)


def kaplan_meier(times: ArrayLike, observed: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Kaplan–Meier (1958) product-limit estimate of the survival function S(t) = P(T > t).

    Args:
        times: convergence episode, or censoring episode, per run, shape (n,).
        observed: 1.0 if the run converged at ``times``, 0.0 if censored there, shape (n,).

    Returns:
        (event_times, survival), shape (k,) each: the distinct observed event times, ascending,
        and ``survival[k]`` = S(t) for t in [event_times[k], event_times[k + 1]); S = 1 before
        the first event. Events come before censorings at the same time.
    """
    sample = _sample(times, observed)
    event_times = np.unique(sample.times[sample.observed])
    after_run = _step_survival(sample.observed[None, :])[0]
    last_at_or_before = np.searchsorted(sample.times, event_times, side="right") - 1
    return event_times, after_run[last_at_or_before]


def km_median(times: ArrayLike, observed: ArrayLike) -> float:
    """Smallest t with Kaplan–Meier S(t) ≤ 0.5; ``math.inf`` when more than half of the runs
    stay censored, NaN without runs. Shapes as in :func:`kaplan_meier`."""
    sample = _sample(times, observed)
    if sample.times.size == 0:
        return math.nan
    return float(_rowwise_median(sample.times[None, :], sample.observed[None, :])[0])


def median_interval(
    times: ArrayLike,
    observed: ArrayLike,
    rng: np.random.Generator,
    *,
    n_resamples: int = 2000,
    confidence: float = 0.95,
) -> Interval:
    """KM median with its percentile-bootstrap interval over runs (shapes as in
    :func:`kaplan_meier`). Infinite resampled medians count as such: ``high`` (or both bounds)
    may be inf. Bounds are NaN with fewer than two runs.

    >>> median_interval([3, 4, 5, 6, 30], [1, 1, 1, 1, 0], np.random.default_rng(0)).estimate
    5.0
    """
    sample = _sample(times, observed)
    n = sample.times.size
    if n == 0:
        return NAN_INTERVAL
    estimate = km_median(times, observed)
    if n < 2:
        return Interval(estimate, math.nan, math.nan)
    medians = _rowwise_median(*_rows(sample, rng.integers(0, n, size=(n_resamples, n))))
    return Interval(estimate, *_inf_percentiles(medians, confidence))


def _speedups(
    base: tuple[np.ndarray, np.ndarray], agent: tuple[np.ndarray, np.ndarray]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Row-wise speed-up from sorted rows (times, observed), shape (m, n), an infinite median
    replaced by the largest censoring time of its side; and whether the baseline's and the
    agent's medians were replaced, each (m,)."""
    base_median, base_censored = _censored_median(*base)
    agent_median, agent_censored = _censored_median(*agent)
    with np.errstate(divide="ignore", invalid="ignore"):
        return base_median / agent_median, base_censored, agent_censored


def _censored_median(times: np.ndarray, observed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Row-wise KM median, or the row's largest censoring time where the median is infinite;
    and where it was, shapes (m, n) → (m,)."""
    median = _rowwise_median(times, observed)
    censored = np.isinf(median)
    last_censoring = np.where(observed, -np.inf, times).max(axis=-1)
    return np.where(censored, last_censoring, median), censored


def _two_samples(
    base: tuple[ArrayLike, ArrayLike], agent: tuple[ArrayLike, ArrayLike], paired: bool
) -> tuple[_Sample, _Sample, bool]:
    """Both samples; when paired (equal lengths only), a seed with a NaN on either side is dropped
    from both so that seed k stays seed k."""
    base_t, base_o = _clean_runs(*base)
    agent_t, agent_o = _clean_runs(*agent)
    paired = paired and base_t.size == agent_t.size
    if paired:
        keep = ~(np.isnan(base_t) | np.isnan(base_o) | np.isnan(agent_t) | np.isnan(agent_o))
        base_t, base_o, agent_t, agent_o = base_t[keep], base_o[keep], agent_t[keep], agent_o[keep]
    return _sample(base_t, base_o), _sample(agent_t, agent_o), paired


def _draw_positions(
    base: _Sample, agent: _Sample, rng: np.random.Generator, paired: bool, n_resamples: int
) -> tuple[np.ndarray, np.ndarray]:
    n_base, n_agent = base.times.size, agent.times.size
    if paired:  # the same seeds for both: map seed indices to each sample's sorted positions
        seeds = rng.integers(0, n_base, size=(n_resamples, n_base))
        return base.rank[seeds], agent.rank[seeds]
    return (
        rng.integers(0, n_base, size=(n_resamples, n_base)),
        rng.integers(0, n_agent, size=(n_resamples, n_agent)),
    )


def speedup_interval(
    base_times: ArrayLike,
    base_observed: ArrayLike,
    agent_times: ArrayLike,
    agent_observed: ArrayLike,
    rng: np.random.Generator,
    *,
    paired: bool = True,
    n_resamples: int = 2000,
    confidence: float = 0.95,
) -> SpeedupInterval:
    """KM-median(baseline) / KM-median(agent) with a percentile-bootstrap interval over seeds.

    Args:
        base_times, base_observed: the baseline's runs, shape (n,) each (as in
            :func:`kaplan_meier`).
        agent_times, agent_observed: the agent's runs, shape (n,) each, seed k = seed k of the
            baseline when ``paired``.
        rng: draws the resamples.
        paired: resample seed indices jointly (needs equal lengths; a seed with a NaN time on
            either side is dropped from both); otherwise each sample on its own.

    An infinite median is replaced by the largest censoring time of its side, and the result
    is then a bound, or unknown when both are (see :class:`SpeedupInterval`), also inside every
    resample.

    >>> fast = speedup_interval([40] * 4, [1] * 4, [10] * 4, [1] * 4, np.random.default_rng(0))
    >>> fast.estimate, fast.bound
    (4.0, '')
    >>> speedup_interval([40] * 4, [0] * 4, [10] * 4, [1] * 4, np.random.default_rng(0)).high
    inf
    """
    base, agent, paired = _two_samples(
        (base_times, base_observed), (agent_times, agent_observed), paired
    )
    if base.times.size == 0 or agent.times.size == 0:
        return SpeedupInterval(math.nan, math.nan, math.nan, "unknown")
    ratio, base_censored, agent_censored = _speedups(
        (base.times[None, :], base.observed[None, :]),
        (agent.times[None, :], agent.observed[None, :]),
    )
    bound = SPEEDUP_BOUNDS[int(base_censored[0]) + 2 * int(agent_censored[0])]
    if bound == "unknown":
        return SpeedupInterval(math.nan, math.nan, math.nan, bound)
    low, high = math.nan, math.nan
    if min(base.times.size, agent.times.size) >= 2:
        base_positions, agent_positions = _draw_positions(base, agent, rng, paired, n_resamples)
        resampled = _speedups(_rows(base, base_positions), _rows(agent, agent_positions))[0]
        low, high = _inf_percentiles(resampled, confidence)
    if bound == "lower":
        high = math.inf
    elif bound == "upper":
        low = 0.0
    return SpeedupInterval(float(ratio[0]), low, high, bound)


def gehan_scores(
    agent_times: ArrayLike,
    agent_observed: ArrayLike,
    base_times: ArrayLike,
    base_observed: ArrayLike,
) -> np.ndarray:
    """Gehan (1965) score of every pair, shape (n_agent, n_base) (NaN runs dropped, order kept):
    1 if agent run i surely converged before baseline run j, 0 if surely after, 0.5 if tied or
    undeterminable.

    A run censored at c converges after c; so an agent event at a ≤ c is surely earlier, one at
    a > c is undeterminable, and a pair of censored runs always is.

    >>> gehan_scores([3, 3, 8], [1, 0, 1], [5], [0]).ravel().tolist()
    [1.0, 0.5, 0.5]
    """
    (agent_t, agent_event), (base_t, base_event) = (
        _runs(agent_times, agent_observed),
        _runs(base_times, base_observed),
    )
    a, b = agent_t[:, None], base_t[None, :]
    a_event, b_event = agent_event[:, None], base_event[None, :]
    earlier = a_event & ((a < b) | (~b_event & (a == b)))
    later = b_event & ((b < a) | (~a_event & (a == b)))
    return np.where(earlier, 1.0, np.where(later, 0.0, 0.5))


def probability_of_improvement(
    agent_times: ArrayLike,
    agent_observed: ArrayLike,
    base_times: ArrayLike,
    base_observed: ArrayLike,
    rng: np.random.Generator,
    *,
    n_resamples: int = 2000,
    confidence: float = 0.95,
) -> Interval:
    """P(agent converges before baseline) with a stratified percentile-bootstrap interval.

    Agarwal et al. (2021) probability of improvement, the mean over all pairs (agent run i,
    baseline run j) of the Gehan (1965) score of :func:`gehan_scores` (0.5 = no difference);
    each sample's runs are resampled independently. Shapes as in :func:`kaplan_meier`.

    >>> probability_of_improvement([1, 2], [1, 1], [5, 6], [1, 0], np.random.default_rng(0))
    Interval(estimate=1.0, low=1.0, high=1.0)
    """
    scores = gehan_scores(agent_times, agent_observed, base_times, base_observed)
    n_agent, n_base = scores.shape
    if scores.size == 0:
        return NAN_INTERVAL
    estimate = float(scores.mean())
    if min(n_agent, n_base) < 2:
        return Interval(estimate, math.nan, math.nan)
    agent_counts = _counts(rng.integers(0, n_agent, size=(n_resamples, n_agent)), n_agent)
    base_counts = _counts(rng.integers(0, n_base, size=(n_resamples, n_base)), n_base)
    resampled = ((agent_counts @ scores) * base_counts).sum(axis=1) / (n_agent * n_base)
    return Interval(estimate, *_inf_percentiles(resampled, confidence))


def _profile_rows(sample: _Sample, positions: np.ndarray, episodes: np.ndarray) -> np.ndarray:
    """1 − KM S(e) of each resample (sorted positions (m, n)) at each episode, shape (m, len(e))."""
    n = sample.times.size
    _, observed_rows = _rows(sample, positions)
    survival = _step_survival(observed_rows)
    # A row holds its runs with time ≤ e at the positions < k_e of the sorted sample.
    below = np.searchsorted(sample.times, episodes, side="right")
    drawn_below = np.cumsum(_counts(positions, n), axis=1)
    n_upto = np.where(below > 0, drawn_below[:, np.maximum(below - 1, 0)], 0.0).astype(int)
    at_e = np.take_along_axis(survival, np.maximum(n_upto - 1, 0), axis=1)
    return np.asarray(1.0 - np.where(n_upto > 0, at_e, 1.0))


def performance_profile(times: ArrayLike, observed: ArrayLike, episodes: ArrayLike) -> np.ndarray:
    """Share of runs converged by each episode, 1 − KM S(e), shape (len(episodes),).

    Agarwal et al. (2021) performance profile over convergence episodes. With one common horizon
    (every censored run censored at the last episode) this is the empirical share; past the
    largest time it stays at its last value. NaN everywhere without runs.

    >>> performance_profile([2, 4, 9, 9], [1, 1, 0, 0], [1, 2, 5]).tolist()
    [0.0, 0.25, 0.5]
    """
    sample = _sample(times, observed)
    points = np.asarray(episodes, dtype=np.float64).ravel()
    if sample.times.size == 0:
        return np.full(points.size, np.nan)
    rows: np.ndarray = _profile_rows(sample, np.arange(sample.times.size)[None, :], points)
    first: np.ndarray = rows[0]
    return first


def profile_band(
    times: ArrayLike,
    observed: ArrayLike,
    episodes: ArrayLike,
    rng: np.random.Generator,
    *,
    n_resamples: int = 2000,
    confidence: float = 0.95,
) -> tuple[np.ndarray, np.ndarray]:
    """Percentile-bootstrap band (low, high), shape (len(episodes),) each, of
    :func:`performance_profile` (runs resampled); NaN with fewer than two runs."""
    sample = _sample(times, observed)
    points = np.asarray(episodes, dtype=np.float64).ravel()
    n = sample.times.size
    if n < 2:
        return np.full(points.size, np.nan), np.full(points.size, np.nan)
    picks = rng.integers(0, n, size=(n_resamples, n))
    shares = _profile_rows(sample, picks, points)
    tail = (1.0 - confidence) / 2.0 * 100.0
    low, high = np.percentile(shares, [tail, 100.0 - tail], axis=0)
    return low, high
