"""How far one combination's time moves between measurements of this run: the spread a
claim's verdict is judged against (`within noise` where its margin lies inside it).

One combination (one `combo_id`: model, structure, parameters, image) may be measured by
several configs of a run (a table config and the faithful or ablation configs), by several
processes of one config (shards, resumed runs), and always by several repetitions. Its
relative spread is the largest of:

- between measurements: the largest over the smallest median of its rows, minus one, over
  every row of the combination whatever its config or process (ablation rows included);
- the repetitions' interval: how far the repetitions of one row (its .reps.csv, else its
  confidence interval's ends) reach from that row's median, relatively.

A claim's spread is the largest over the combinations and timed metrics it read, and never
less than the widest gap between two measurements of any one combination in the run (for
the metrics it read): what the run shows one combination can move, any of its
combinations may have moved.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import pandas as pd

from ..inputs.schema import Results

TIMED = {"build": "build_s", "render": "render_s"}


@dataclass(frozen=True)
class Spread:
    """A relative spread and where it comes from (for the reason text)."""

    value: float
    how: str

    def __str__(self) -> str:
        return f"{self.value:.0%} ({self.how})" if self.how else f"{self.value:.0%}"


def _between_measurements(rows: pd.DataFrame, col: str) -> pd.Series:
    med = pd.to_numeric(rows[f"{col}_median"], errors="coerce")
    g = med.groupby(rows["combo_id"])
    gap = g.max() / g.min() - 1
    return gap.where(g.count() > 1).dropna()


def _repetitions(results: Results, rows: pd.DataFrame, col: str) -> pd.Series:
    """Per combo_id, the largest relative reach of one row's repetitions from its median."""
    reps = results.reps
    if reps is not None and not reps.empty and {"combo_id", col}.issubset(reps.columns):
        key = ["combo_id", "source"] if "source" in reps.columns else ["combo_id"]
        times = pd.to_numeric(reps[col], errors="coerce")
        g = times.groupby([reps[k] for k in key])
        med = g.median()
        reach = pd.concat([g.max() / med - 1, 1 - g.min() / med], axis=1).max(axis=1)
        return reach.groupby(level=0).max()
    if not {f"{col}_ci_lo", f"{col}_ci_hi"}.issubset(rows.columns):
        return pd.Series(dtype=float)
    lo, hi, med = (pd.to_numeric(rows[f"{col}_{s}"], errors="coerce") for s in ("ci_lo", "ci_hi", "median"))
    reach = pd.concat([hi / med - 1, 1 - lo / med], axis=1).max(axis=1)
    return reach.groupby(rows["combo_id"]).max().dropna()


def measured_spread(results: Results, combo_ids: Iterable[str], metric: str) -> dict[str, Spread]:
    """Per combo_id of `combo_ids`, the relative spread of `metric` ("build" or "render")
    measured in this run (module docstring). A combination measured once with one
    repetition has spread 0 ("measured once")."""
    col = TIMED[metric]
    rows = results.ok()
    rows = rows[rows["combo_id"].isin(set(combo_ids))] if "combo_id" in rows else rows.iloc[0:0]
    between = _between_measurements(rows, col) if not rows.empty else pd.Series(dtype=float)
    within = _repetitions(results, rows, col) if not rows.empty else pd.Series(dtype=float)
    out: dict[str, Spread] = {}
    for cid in dict.fromkeys(combo_ids):
        b, w = float(between.get(cid, 0.0)), float(within.get(cid, 0.0))
        n = int((rows["combo_id"] == cid).sum()) if not rows.empty else 0
        if b >= w and b > 0:
            out[cid] = Spread(b, f"{metric} between {n} measurements of one combination")
        elif w > 0:
            out[cid] = Spread(w, f"{metric} repetitions around their median")
        else:
            out[cid] = Spread(0.0, "measured once")
    return out


def widest_gap(results: Results, metric: str) -> Spread:
    """The widest gap between two measurements of one combination anywhere in the run."""
    rows = results.ok()
    if "combo_id" not in rows or rows.empty:
        return Spread(0.0, "")
    gaps = _between_measurements(rows, TIMED[metric])
    if gaps.empty:
        return Spread(0.0, "")
    return Spread(
        float(gaps.max()), f"{metric}: the run's widest gap between two measurements of one combination"
    )


def claim_spread(results: Results, read: Iterable[tuple[str, str]]) -> Spread:
    """The largest spread over the (combo_id, metric) pairs a claim read, at least the
    run's widest gap for each timed metric it read; metrics that are not timed (counts,
    nodes) are exact and add nothing."""
    best = Spread(0.0, "no timed value read")
    by_metric: dict[str, set[str]] = {}
    for cid, metric in read:
        if metric in TIMED:
            by_metric.setdefault(metric, set()).add(cid)
    for metric, ids in by_metric.items():
        for s in [*measured_spread(results, ids, metric).values(), widest_gap(results, metric)]:
            if s.value > best.value:
                best = s
    return best
