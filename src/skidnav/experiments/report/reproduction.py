"""The "thesis reproduction" section of the report: each thesis claim next to what was measured.

Claims (Alhawary (2020), ch. 7): model-based agents converge up to 16× faster than Q-learning;
success rate rises by up to 70 %; no significant difference in final trajectory length; a rough
floor about doubles the success rate of a slippery one. The verdicts only read the intervals;
nothing is tuned to agree with the thesis.
"""

from __future__ import annotations

import html

import pandas as pd

from skidnav.experiments.config import ExperimentConfig
from skidnav.experiments.report.analysis import speedup_of
from skidnav.experiments.report.page import table
from skidnav.statistics.formatting import NOT_AVAILABLE, interval, plural

MIN_PAIRS = 10
"""Fewer paired seeds than this make a "no difference" verdict inconclusive."""

SURFACES_ELSEWHERE = (
    "not in this experiment: it needs the slip presets 'rough' and 'slippery'. "
    "configs/surfaces.toml measures it; its report holds this row"
)
"""The floor claim's row in a report of an experiment without both floors."""

THESIS = {
    "speedup": "up to 16× faster convergence than Q-learning",
    "success": "success rate up to 70 % higher",
    "length": "no significant difference in final trajectory length",
    "surfaces": "rough floor ≈ 2× the success rate of a slippery floor (real robot)",
}


def _ci(row: pd.Series, name: str, scale: float = 1.0, unit: str = "") -> str:
    """``name`` of a comparison row with its interval, times ``scale``, ``unit`` after the
    estimate (:func:`skidnav.statistics.formatting.interval`: "n/a" when undefined)."""
    estimate, low, high = (float(row[key]) * scale for key in (name, f"{name}_low", f"{name}_high"))
    return _unit(interval(estimate, low, high), unit)


def _ratio(ratio: object, low: object, high: object) -> str:
    """A ratio with its interval (table cells), "×" after the estimate."""
    return _unit(interval(float(ratio), float(low), float(high)), "×")  # type: ignore[arg-type]


def _unit(text: str, unit: str) -> str:
    """``unit`` after the estimate of an :func:`~skidnav.statistics.formatting.interval` text (none
    after
    "n/a")."""
    if text == NOT_AVAILABLE:
        return text
    shown, _, bounds = text.partition(" ")
    return f"{shown}{unit} {bounds}".rstrip()


def _name(row: pd.Series) -> str:
    return html.escape(f"{row['agent']} on {row['map']}/{row['preset']}")


def _verdict(flag: bool, yes: str, no: str) -> str:
    return f'<span class="yes">{yes}</span>' if flag else f'<span class="no">{no}</span>'


def _best(frame: pd.DataFrame, column: str) -> pd.Series | None:
    valid = frame[frame[column].notna()]
    return None if valid.empty else valid.iloc[int(valid[column].to_numpy().argmax())]


def _length_claim(comparisons: pd.DataFrame) -> tuple[str, str, str]:
    """Final-length claim: only seeds where both final greedy trajectories reached the goal;
    comparisons with fewer than :data:`MIN_PAIRS` such seeds cannot settle it either way."""
    width = comparisons["length_difference_high"] - comparisons["length_difference_low"]
    defined = comparisons[width.notna()]
    if defined.empty:
        return THESIS["length"], "fewer than 2 seeds where both reached the goal", "undetermined"
    pairs = defined["length_pairs"]
    same = defined["length_no_difference"]
    solid = pairs >= MIN_PAIRS
    measured = (
        f"{int(same.sum())} of {len(defined)} comparisons: interval of the difference contains 0 "
        f"(widest interval {width.max():.1f} actions; {pairs.min()}–{pairs.max()} seeds per "
        "comparison where both final greedy trajectories reached the goal)"
    )
    if (solid & ~same).any():
        return THESIS["length"], measured, _verdict(False, "", "differences found")
    if solid.all():
        return THESIS["length"], measured, _verdict(True, "no difference found", "")
    return THESIS["length"], measured, f"inconclusive (< {MIN_PAIRS} paired seeds)"


def _surface_claim(surfaces: pd.DataFrame) -> tuple[str, str, str]:
    """Rough / slippery success ratio per agent against the thesis's ≈ 2×; without both floors
    in this experiment, a pointer to the one that measures it."""
    if surfaces.empty:
        return THESIS["surfaces"], SURFACES_ELSEWHERE, "not measured here"
    rates = surfaces[surfaces["metric"] == "success_rate"]
    parts = [
        f"{html.escape(str(r.agent))}: {_ratio(r.ratio, r.ratio_low, r.ratio_high)}"
        for r in rates.itertuples()
    ]
    contains = (rates["ratio_low"] <= 2.0) & (rates["ratio_high"] >= 2.0)
    better = int((rates["ratio_low"] > 1.0).sum())
    measured = "; ".join(parts) + f". Rough significantly better for {better} of {len(rates)}."
    if contains.all():
        return THESIS["surfaces"], measured, _verdict(True, "consistent with 2×", "")
    if not contains.any():
        return THESIS["surfaces"], measured, _verdict(False, "", "2× outside every interval")
    return THESIS["surfaces"], measured, f"mixed: 2× within {int(contains.sum())} of {len(rates)}"


def _speedup_claim(comparisons: pd.DataFrame) -> tuple[str, str, str]:
    """Largest speed-up (ratio of Kaplan–Meier medians), how many comparisons are significant,
    and the censoring behind them."""
    best = _best(comparisons, "speedup")
    if best is None:
        return (
            THESIS["speedup"],
            "unknown: in every comparison both the baseline and the agent stayed censored in "
            "more than half of their runs",
            "undetermined",
        )
    faster = comparisons[comparisons["speedup_low"] > 1.0]
    measured = (
        f"largest: {_name(best)}, {speedup_of(best).words()}; {len(faster)} of "
        f"{len(comparisons)} agent × cell comparisons significantly faster. The baseline "
        f"converged in {comparisons['baseline_converged'].min():.0%}–"
        f"{comparisons['baseline_converged'].max():.0%} of its runs (the others are censored; "
        "where more than half of the baseline's are, the speed-up is a lower bound, marked ≥; "
        "of the agent's, an upper bound, marked ≤; of both, unknown)"
    )
    return (
        THESIS["speedup"],
        measured,
        _verdict(not faster.empty, "model-based faster", "no speed-up"),
    )


def _success_claim(comparisons: pd.DataFrame) -> tuple[str, str, str] | None:
    """Largest success-rate gain, absolute and relative."""
    best = _best(comparisons, "success_gain")
    if best is None:
        return None
    higher = comparisons[comparisons["success_gain_low"] > 0.0]
    measured = (
        f"largest: {_name(best)}, {_ci(best, 'success_gain', 100, ' pp')} absolute, "
        f"{_ci(best, 'success_gain_relative', 100, ' %')} relative"
    )
    return THESIS["success"], measured, _verdict(not higher.empty, "higher success", "no gain")


def _claims(comparisons: pd.DataFrame, surfaces: pd.DataFrame) -> list[tuple[str, str, str]]:
    """(claim, measured, verdict) rows, over every map × preset cell."""
    rows = [
        _speedup_claim(comparisons),
        _success_claim(comparisons),
        _length_claim(comparisons),
        _surface_claim(surfaces),
    ]
    return [row for row in rows if row is not None]


def _details(comparisons: pd.DataFrame) -> pd.DataFrame:
    records = []
    for _, row in comparisons.iterrows():
        records.append(
            {
                "map": row["map"],
                "preset": row["preset"],
                "agent": row["agent"],
                "speed-up": speedup_of(row).words(),
                "speed-up, real actions": speedup_of(row, "speedup_steps").words()
                if "speedup_steps" in row
                else NOT_AVAILABLE,
                "P(improvement)": _ci(row, "improvement_probability"),
                "success gain": _ci(row, "success_gain", 100, " pp"),
                "relative gain": _ci(row, "success_gain_relative", 100, " %"),
                "gain, last 10 %": _ci(row, "success_gain_last10", 100, " pp"),
                "length difference": _ci(row, "length_difference", unit=" act."),
                "optimality-gap difference (pairs)": f"{_ci(row, 'gap_difference', 100, ' pp')} "
                f"({int(row['gap_pairs'])})",
                "no sig. difference": "yes" if row["length_no_difference"] else "no",
                "pairs (both reached goal)": int(row["length_pairs"]),
                "baseline converged": f"{row['baseline_converged']:.0%}",
            }
        )
    return pd.DataFrame.from_records(records)


def reproduction_section(
    comparisons: pd.DataFrame,
    surfaces: pd.DataFrame,
    summaries: pd.DataFrame,
    config: ExperimentConfig,
) -> str:
    """HTML of the thesis-reproduction section."""
    parts = [
        "<h2>Thesis reproduction</h2>",
        f"<p class='note'>Baseline: <b>{html.escape(config.baseline)}</b>. Intervals: "
        f"{config.confidence:.0%} bootstrap, paired by seed. {plural(config.seeds, 'seed')} per "
        f"cell (the thesis's claims need ≥ 30). Convergence: within "
        f"{config.convergence_tolerance:.0%} of the oracle, staying there in at least "
        f"{config.convergence_level:.0%} of the evaluations to the end of the run "
        "(definitions above).</p>",
    ]
    if comparisons.empty:
        parts.append("<p>Only one agent: nothing to compare.</p>")
        return "".join(parts)
    claims = pd.DataFrame(
        _claims(comparisons, surfaces), columns=["thesis claim", "measured here", "verdict"]
    )
    parts.append(table(claims, prose=True, escape=False))
    parts.append("<h3>Every agent against the baseline</h3>")
    parts.append(table(_details(comparisons), labels=3))
    return "".join(parts)
