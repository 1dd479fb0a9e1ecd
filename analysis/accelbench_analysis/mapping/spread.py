"""How far one combination's time moves between measurements of one run: the spread a
claim's verdict is judged against (`within noise` where its margin lies inside it).

One combination (one `combo_id`: model, structure, parameters, image) may be measured by
several configs of a run (a table config, the faithful and ablation configs), by the same
config in several processes (the job's second pass, shards, resumed runs: each row is its
own measuring process), and always by several repetitions. Its relative spread is the
largest of three parts, each relative to the smaller or the middle value:

- between processes: the largest over the smallest median among the rows of one config,
  minus one (the largest such gap over its configs);
- between configs: the largest gap between two rows of different configs (ablation rows
  included), max / min - 1;
- the repetitions' interval: how far one row's order-statistics interval of the median
  (`*_ci_lo`, `*_ci_hi`) reaches from its median, max(hi / median - 1, 1 - lo / median),
  the widest over the combination's rows, with the coverage that interval has
  (`ci_coverage`, `median_ci`).

So the spread is at least the widest gap between any two measurements of the combination.
A claim's spread is the largest over the combinations and timed metrics it read, and never
less than the widest gap between two measurements of any one combination in the run.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from itertools import combinations
from math import comb

import pandas as pd

from ..inputs.schema import Results

TIMED = {"build": "build_s", "render": "render_s"}
WANTED_COVERAGE = 0.95


@dataclass(frozen=True)
class Spread:
    """A relative spread, its three parts and where the largest comes from (for reasons)."""

    value: float
    how: str
    between_processes: float = 0.0
    between_configs: float = 0.0
    interval: float = 0.0
    coverage: float | None = None  # of the interval counted in `interval`

    def __str__(self) -> str:
        return f"{self.value:.0%} ({self.how})" if self.how else f"{self.value:.0%}"


def median_ci(n: int, wanted: float = WANTED_COVERAGE) -> tuple[int, float]:
    """The order-statistics interval of the median of n samples: (k, coverage), the
    interval [x(k), x(n+1-k)] (1-based) with the largest k whose coverage
    sum_{j=k}^{n-k} C(n, j) / 2^n reaches `wanted`, else k = 1 ([min, max]). The harness
    computes the same for `*_ci_lo`, `*_ci_hi` and `ci_coverage` (docs/configs.md)."""
    if n < 2:
        raise ValueError(f"an interval of the median needs two samples or more, not {n}")
    best = 1
    for k in range(1, n // 2 + 1):
        if sum(comb(n, j) for j in range(k, n - k + 1)) / 2**n >= wanted:
            best = k
    return best, sum(comb(n, j) for j in range(best, n - best + 1)) / 2**n


def _gap(values: pd.Series) -> float:
    return float(values.max() / values.min() - 1) if len(values) > 1 and values.min() > 0 else 0.0


def _between_configs(medians: pd.Series, configs: pd.Series) -> float:
    groups = {c: medians[configs == c] for c in configs.unique()}
    gaps = [
        max(a.max() / b.min(), b.max() / a.min()) - 1
        for a, b in (pair for pair in combinations(groups.values(), 2))
        if a.min() > 0 and b.min() > 0
    ]
    return float(max(gaps, default=0.0))


def _interval(rows: pd.DataFrame, col: str) -> tuple[float, float | None]:
    """The widest reach of a row's interval from its median, and that interval's coverage."""
    if not {f"{col}_ci_lo", f"{col}_ci_hi"}.issubset(rows.columns):
        return 0.0, None
    lo, hi, med = (pd.to_numeric(rows[f"{col}_{s}"], errors="coerce") for s in ("ci_lo", "ci_hi", "median"))
    reach = pd.concat([hi / med - 1, 1 - lo / med], axis=1).max(axis=1).dropna()
    if reach.empty:
        return 0.0, None
    widest = reach.idxmax()
    cov = pd.to_numeric(rows["ci_coverage"], errors="coerce").get(widest) if "ci_coverage" in rows else None
    return float(reach.max()), (None if cov is None or pd.isna(cov) else float(cov))


def _spread_of(rows: pd.DataFrame, col: str, metric: str) -> Spread:
    medians = pd.to_numeric(rows[f"{col}_median"], errors="coerce")
    keep = medians.notna()
    rows, medians = rows[keep], medians[keep]
    configs = rows["config"].astype(str) if "config" in rows else pd.Series("", index=rows.index)
    processes = max((_gap(medians[configs == c]) for c in configs.unique()), default=0.0)
    between = _between_configs(medians, configs)
    interval, coverage = _interval(rows, col)
    n = len(rows)
    parts = {
        f"{metric} between {n} measurements of one combination in {configs.nunique()} configs": between,
        f"{metric} between {n} measurements of one combination, processes of one config": processes,
        f"{metric} repetitions' interval"
        + (f" ({coverage:.0%} coverage)" if coverage is not None else ""): interval,
    }
    how, value = max(parts.items(), key=lambda kv: kv[1])
    if value <= 0:
        how = "measured once"
    return Spread(value, how, processes, between, interval, coverage)


def measured_spread(results: Results, combo_ids: Iterable[str], metric: str) -> dict[str, Spread]:
    """Per combo_id of `combo_ids`, the relative spread of `metric` ("build" or "render")
    measured in this run (module docstring): the largest of between processes, between
    configs and the repetitions' interval. A combination measured once with one repetition
    (or not at all) has spread 0, "measured once"."""
    col = TIMED[metric]
    ids = list(dict.fromkeys(combo_ids))
    rows = results.ok()
    rows = rows[rows["combo_id"].isin(set(ids))] if "combo_id" in rows else rows.iloc[0:0]
    by_id = dict(tuple(rows.groupby("combo_id"))) if not rows.empty else {}
    return {
        cid: _spread_of(by_id[cid], col, metric) if cid in by_id else Spread(0.0, "measured once")
        for cid in ids
    }


def widest_gap(results: Results, metric: str) -> Spread:
    """The widest spread of `metric` of any one combination anywhere in the run."""
    rows = results.ok()
    if "combo_id" not in rows or rows.empty:
        return Spread(0.0, "")
    spreads = measured_spread(results, rows["combo_id"].unique(), metric).values()
    widest = max(spreads, key=lambda s: s.value)
    how = f"the run's widest gap, {widest.how}" if widest.value > 0 else ""
    return Spread(
        widest.value, how, widest.between_processes, widest.between_configs, widest.interval, widest.coverage
    )


def claim_spread(results: Results, read: Iterable[tuple[str, str]]) -> Spread:
    """The largest spread over the (combo_id, metric) pairs a claim read, at least the
    run's widest for each timed metric it read; metrics that are not timed (counts, nodes)
    are exact and add nothing."""
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
