"""How far one combination's time moves between measurements of one run: the spread a
claim's verdict is judged against (`within noise` where its margin lies inside it).

One combination (one `combo_id`: model, structure, parameters, image) may be measured by
several configs of a run (a table config, the faithful and ablation configs), by the same
config in several processes (the job's second pass, shards, resumed runs: each row is its
own measuring process; and the child processes one row's repetitions are pooled from, the
`processes` column), and always by several repetitions. Its relative spread is the
largest of three parts, each relative to the smaller or the middle value:

- between processes: the largest over the smallest median among the rows of one config,
  minus one (the largest such gap over its configs), or, where larger, the largest
  `build_s_process_gap` / `render_s_process_gap` of its rows (the harness's max / min - 1
  of the per-process medians of one row); a row without that gap (one process, older
  CSVs) adds nothing, it is unknown rather than zero; the `how` text says which;
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

import math
import weakref
from collections.abc import Iterable
from dataclasses import dataclass, replace
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


def _gap(values: list[float]) -> float:
    return max(values) / min(values) - 1 if len(values) > 1 and min(values) > 0 else 0.0


def _between_configs(by_config: dict[str, list[float]]) -> float:
    gaps = [
        max(max(a) / min(b), max(b) / min(a)) - 1
        for a, b in combinations(by_config.values(), 2)
        if min(a) > 0 and min(b) > 0
    ]
    return float(max(gaps, default=0.0))


@dataclass(frozen=True)
class _Measurement:
    """One ok row's numbers of one timed metric (NaN where the CSV has none)."""

    config: str
    median: float
    lo: float
    hi: float
    coverage: float
    process_gap: float  # `*_process_gap`: NaN where unknown (one process, older CSVs)
    processes: float


def _interval(rows: list[_Measurement]) -> tuple[float, float | None]:
    """The widest reach of a row's interval from its median, and that interval's coverage
    (the first row of the widest reach). A zero median has no relative reach (loading
    refuses zero times; hand-made frames may hold one)."""
    best, cov = None, None
    for r in rows:
        if r.median <= 0:
            continue
        ends = [x for x in (r.hi / r.median - 1, 1 - r.lo / r.median) if not math.isnan(x)]
        if ends and (best is None or max(ends) > best):
            best, cov = max(ends), r.coverage
    if best is None:
        return 0.0, None
    return best, (None if math.isnan(cov) else cov)


def _process_part(
    rows: list[_Measurement], by_config: dict[str, list[float]], metric: str
) -> tuple[float, str]:
    """Between processes: the largest gap between the rows of one config (each row its own
    measuring process) or, larger, the largest `*_process_gap` of a row (the child processes
    that measured that one row). Unknown gaps (no column, one process) count as nothing."""
    own = max((_gap(v) for v in by_config.values()), default=0.0)
    gaps = [r for r in rows if not math.isnan(r.process_gap)]
    widest = max(gaps, key=lambda r: r.process_gap, default=None)
    if widest is not None and widest.process_gap > own:
        k = "several" if math.isnan(widest.processes) else f"{widest.processes:g}"
        return widest.process_gap, f"{metric} between processes: {k} processes measured one row"
    return own, f"{metric} between {len(rows)} measurements of one combination, processes of one config"


def _spread_of(rows: list[_Measurement], metric: str) -> Spread:
    by_config: dict[str, list[float]] = {}
    for r in rows:
        by_config.setdefault(r.config, []).append(r.median)
    processes, process_how = _process_part(rows, by_config, metric)
    between = _between_configs(by_config)
    interval, coverage = _interval(rows)
    n = len(rows)
    parts = {
        f"{metric} between {n} measurements of one combination in {len(by_config)} configs": between,
        process_how: processes,
        f"{metric} repetitions' interval"
        + (f" ({coverage:.0%} coverage)" if coverage is not None else ""): interval,
    }
    how, value = max(parts.items(), key=lambda kv: kv[1])
    if value <= 0:
        how = "measured once"
    return Spread(value, how, processes, between, interval, coverage)


def _column(rows: pd.DataFrame, name: str) -> list[float]:
    if name not in rows:
        return [math.nan] * len(rows)
    return [float(x) for x in pd.to_numeric(rows[name], errors="coerce")]


def _measurements(rows: pd.DataFrame, col: str) -> dict[str, list[_Measurement]]:
    """Every ok row with a median of `col`, by combo_id, in the rows' order."""
    configs = rows["config"].astype(str) if "config" in rows else pd.Series("", index=rows.index)
    has_ci = {f"{col}_ci_lo", f"{col}_ci_hi"}.issubset(rows.columns)
    nan = [math.nan] * len(rows)
    columns = zip(
        rows["combo_id"],
        configs,
        _column(rows, f"{col}_median"),
        _column(rows, f"{col}_ci_lo") if has_ci else nan,
        _column(rows, f"{col}_ci_hi") if has_ci else nan,
        _column(rows, "ci_coverage"),
        _column(rows, f"{col}_process_gap"),
        _column(rows, "processes"),
    )
    out: dict[str, list[_Measurement]] = {}
    for cid, config, *numbers in columns:
        if not pd.isna(cid) and not math.isnan(numbers[0]):
            out.setdefault(cid, []).append(_Measurement(config, *numbers))
    return out


MEASURED_ONCE = Spread(0.0, "measured once")

# Per Results (a Results is never changed once loaded) and metric: every combination's
# spread and the run's widest. Judging the claims asks for them once per claim and setting.
_TABLES: dict[int, dict[str, tuple[dict[str, Spread], Spread]]] = {}


def _table(results: Results, metric: str) -> tuple[dict[str, Spread], Spread]:
    key = id(results)
    if key not in _TABLES:
        _TABLES[key] = {}
        weakref.finalize(results, _TABLES.pop, key, None)
    per = _TABLES[key]
    if metric not in per:
        rows = results.ok()
        if "combo_id" not in rows or rows.empty:
            per[metric] = ({}, Spread(0.0, ""))
        else:
            by_id = _measurements(rows, TIMED[metric])
            spreads = {cid: _spread_of(m, metric) for cid, m in by_id.items()}
            order = [spreads.get(cid, MEASURED_ONCE) for cid in rows["combo_id"].unique()]
            widest = max(order, key=lambda s: s.value)
            how = f"the run's widest gap, {widest.how}" if widest.value > 0 else ""
            per[metric] = (spreads, replace(widest, how=how))
    return per[metric]


def measured_spread(results: Results, combo_ids: Iterable[str], metric: str) -> dict[str, Spread]:
    """Per combo_id of `combo_ids`, the relative spread of `metric` ("build" or "render")
    measured in this run (module docstring): the largest of between processes, between
    configs and the repetitions' interval. A combination measured once with one repetition
    (or not at all) has spread 0, "measured once"."""
    spreads = _table(results, metric)[0]
    return {cid: spreads.get(cid, MEASURED_ONCE) for cid in dict.fromkeys(combo_ids)}


def widest_gap(results: Results, metric: str) -> Spread:
    """The widest spread of `metric` of any one combination anywhere in the run."""
    return _table(results, metric)[1]


def claim_spread(results: Results, read: Iterable[tuple[str, str]], run: Results | None = None) -> Spread:
    """The largest spread over the (combo_id, metric) pairs a claim read, at least the
    run's widest for each timed metric it read; metrics that are not timed (counts, nodes)
    are exact and add nothing. `run`: every row of the run (ray sets and thread scaling
    included) when `results` holds only those the claims judge, so that the floor is the
    widest gap anywhere in the run."""
    best = Spread(0.0, "no timed value read")
    by_metric: dict[str, set[str]] = {}
    for cid, metric in read:
        if metric in TIMED:
            by_metric.setdefault(metric, set()).add(cid)
    for metric, ids in by_metric.items():
        for s in [*measured_spread(results, ids, metric).values(), widest_gap(run or results, metric)]:
            if s.value > best.value:
                best = s
    return best
