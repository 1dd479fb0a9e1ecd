"""The rows the ranking is made of: each measured row's trace and build time as a ratio to
the baseline's (Embree's) row beside it, and what the row is by the structure table.

Ratios, never seconds: a ratio to the baseline measured beside it on the same machine and
rays is what carries from one machine to another. A ratio's interval divides the two
medians' intervals end by end (the row's low end by the baseline's high end, and the other
way round), so it is wider than either, never narrower.

What a row is (`kind`), from the structure table (mapping/structures.py) and the row:
- "structure": a structure at a variant the table declares (the BVH's splits, the wide
  BVH's widths), whatever its other parameters; the baseline at the one setting every ratio
  divides by (its preferred parameters, then the one measured most widely); a structure the
  table lacks (a plugin not loaded now), under its CSV `label`.
- "ablation": a row whose CSV `label` (the registry's, of the resolved parameters) is not
  the label of the table variant its parameters are: the registry marks the setting as
  not that structure (the wide BVH's tests without the guarantees say "ablation" there).
  Each also has its ratio to its own structure: the row of the declared variant beside it
  that differs from it in the fewest parameters.
- "baseline variant": the baseline at any other setting (Embree's robust or max_isa).
A CSV without a `label` column has no ablations: every row is its variant's structure."""

from __future__ import annotations

import math
from dataclasses import dataclass

import pandas as pd

from ...inputs.schema import RENDER_SETTING_COLUMNS, Results
from ...mapping.formatting import fmt_sig
from ...mapping.selection import PREFERRED, SINGLE_THREAD, label_of
from ...mapping.structures import baseline_accels, table_row, variant_of_row

STRUCTURE, ABLATION, BASELINE_VARIANT = "structure", "ablation", "baseline variant"
NO_RATIO = "—"  # the one mark of a cell without a ratio


@dataclass(frozen=True)
class Ratio:
    value: float
    lo: float
    hi: float

    def ok(self) -> bool:
        return self.value == self.value and self.value > 0

    def text(self) -> str:
        if not self.ok():
            return NO_RATIO
        if self.lo == self.lo and self.hi == self.hi:
            return f"{fmt_sig(self.value, 3)} [{fmt_sig(self.lo, 3)}–{fmt_sig(self.hi, 3)}]"
        return fmt_sig(self.value, 3)

    def short(self) -> str:
        """The ratio and ± the larger side of its interval in per cent of it, rounded up to
        two digits (never narrower than the interval): "0.981 ±1.4%"."""
        if not self.ok():
            return NO_RATIO
        if not (self.lo == self.lo and self.hi == self.hi):
            return fmt_sig(self.value, 3)
        side = 100 * max(1 - self.lo / self.value, self.hi / self.value - 1, 0.0)
        pct = f"{math.ceil(side - 1e-9):.0f}" if side >= 10 else f"{math.ceil(side * 10 - 1e-9) / 10:.1f}"
        return f"{fmt_sig(self.value, 3)} ±{pct}%"


NONE = Ratio(math.nan, math.nan, math.nan)


def ratio(row: pd.Series, base: pd.Series | None, measure: str) -> Ratio:
    """row's `measure` (render_s, build_s) over base's, the interval end by end."""
    if base is None:
        return NONE
    m, b = row[f"{measure}_median"], base[f"{measure}_median"]
    if not (m > 0 and b > 0):
        return NONE
    lo_r, hi_r = row[f"{measure}_ci_lo"], row[f"{measure}_ci_hi"]
    lo_b, hi_b = base[f"{measure}_ci_lo"], base[f"{measure}_ci_hi"]
    lo = lo_r / hi_b if lo_r > 0 and hi_b > 0 else math.nan
    hi = hi_r / lo_b if hi_r > 0 and lo_b > 0 else math.nan
    return Ratio(m / b, lo, hi)


def geomean(ratios: list[Ratio]) -> Ratio:
    """The geometric mean of the ratios that have a value; its interval is the mean of their
    low ends and of their high ends (every ratio at its end at once: wider than the mean's
    own interval, never narrower). NONE when none has a value."""
    have = [r for r in ratios if r.ok()]
    if not have:
        return NONE

    def mean(xs: list[float]) -> float:
        if any(not (x == x and x > 0) for x in xs):
            return math.nan
        return math.exp(sum(math.log(x) for x in xs) / len(xs))

    return Ratio(mean([r.value for r in have]), mean([r.lo for r in have]), mean([r.hi for r in have]))


def ray_group(row: pd.Series) -> str:
    """A row's ray set (camera for the camera's rays), with its render threads when not 1."""
    text = str(row.get("ray_set", "") or "camera")
    threads = row.get("render_threads", math.nan)
    if threads == threads and float(threads) != 1:
        text += f" · {float(threads):g} threads"
    return text


def _settings_key(row: pd.Series) -> tuple:
    return tuple(str(row.get(c, "")) for c in ["model", "ray_set", *RENDER_SETTING_COLUMNS])


def _label(row: pd.Series) -> str:
    text = row.get("label", "")
    return "" if not isinstance(text, str) else text.strip()


def _baseline_params(rows: pd.DataFrame, baseline: str) -> dict[tuple, str]:
    """Per settings key, the `params` text of the baseline's row every ratio there divides
    by: its preferred parameters (mapping/selection.py), then the setting measured on the
    most settings keys, then the first parameters text."""
    ok = rows[(rows["accel"] == baseline) & (rows["status"] == "ok")]
    if ok.empty:
        return {}
    prefer = PREFERRED.get(baseline, SINGLE_THREAD)
    reach = ok.groupby("params")["key"].nunique()

    def rank(params: str, p: dict) -> tuple:
        return (-sum(p.get(k) == v for k, v in prefer), -int(reach[params]), params)

    chosen: dict[tuple, str] = {}
    for key, g in ok.groupby("key", sort=False):
        chosen[key] = min(rank(pt, pd_) for pt, pd_ in zip(g["params"], g["param_dict"]))[2]
    return chosen


def _kind(row: pd.Series, baseline: str, chosen: dict[tuple, str]) -> tuple[str, str]:
    """(kind, the label of the structure it is a kind of) of one row."""
    label = _label(row)
    if row["accel"] == baseline:
        own = label or label_of(row["accel"], row["param_dict"])
        at = chosen.get(row["key"])
        return (STRUCTURE, own) if at is None or at == row["params"] else (BASELINE_VARIANT, own)
    if table_row(row["accel"]) is None:
        return STRUCTURE, label or row["accel"]
    variant = variant_of_row(row["accel"], row["param_dict"])
    if variant is not None and label and label != variant.label:
        return ABLATION, variant.label
    return STRUCTURE, label or label_of(row["accel"], row["param_dict"])


def _changes(p: dict, own: dict) -> str:
    """The parameters p sets otherwise than own, as "k=v" text."""
    return ", ".join(f"{k}={v}" for k, v in p.items() if own.get(k, v) != v)


def _own_row(row: pd.Series, rows: pd.DataFrame) -> pd.Series | None:
    """An ablation's own structure beside it: the declared variant's ok row of the same
    accelerator and settings key differing from it in the fewest parameters."""
    mine = rows[
        (rows["key"] == row["key"])
        & (rows["accel"] == row["accel"])
        & (rows["kind"] == STRUCTURE)
        & (rows["structure"] == row["of"])
        & (rows["status"] == "ok")
    ]
    if mine.empty:
        return None
    p = row["param_dict"]
    diffs = [
        (sum(q.get(k, v) != v for k, v in p.items()), params)
        for q, params in zip(mine["param_dict"], mine["params"])
    ]
    best = min(diffs)[1]
    return mine[mine["params"] == best].iloc[0]


def ratios(results: Results) -> pd.DataFrame:
    """One row per measured row of the run (catalogue cases aside): its workload (`model ·
    ray group`), ray group, model, structure label, accelerator, parameters, status, kind,
    `of` (the structure it is an ablation or variant of), both ratios to the baseline row
    beside it (same scene, rays and render settings), and for ablations and baseline
    variants the trace and build ratio to their own structure and what they change."""
    df = results.measured_rows().copy()
    if df.empty:
        return pd.DataFrame()
    df["key"] = [_settings_key(r) for _, r in df.iterrows()]
    bases = baseline_accels()
    baseline = next((b for b in bases if (df["accel"] == b).any()), bases[0] if bases else "")
    chosen = _baseline_params(df, baseline)
    kinds = [_kind(r, baseline, chosen) for _, r in df.iterrows()]
    df["kind"] = [k for k, _ in kinds]
    df["of"] = [o for _, o in kinds]
    df["structure"] = [o if k != ABLATION else _label(r) for (k, o), (_, r) in zip(kinds, df.iterrows())]
    df["group"] = [ray_group(r) for _, r in df.iterrows()]
    df["workload"] = [f"{m} · {g}" for m, g in zip(df["model"], df["group"])]
    base_rows = {
        r["key"]: r
        for _, r in df[
            (df["accel"] == baseline) & (df["kind"] == STRUCTURE) & (df["status"] == "ok")
        ].iterrows()
    }
    out = []
    for _, r in df.iterrows():
        e = base_rows.get(r["key"]) if r["status"] == "ok" else None
        own = e if r["kind"] == BASELINE_VARIANT else _own_row(r, df) if r["kind"] == ABLATION else None
        if r["kind"] == BASELINE_VARIANT:
            r = r.copy()
            r["structure"] = (
                f"{r['of']} ({_changes(r['param_dict'], e['param_dict'])})" if e is not None else r["of"]
            )
        out.append(_record(r, e, own))
    return pd.DataFrame(out)


def _record(r: pd.Series, e: pd.Series | None, own: pd.Series | None) -> dict:
    return {
        "workload": r["workload"],
        "config": r["config"],
        "group": r["group"],
        "model": r["model"],
        "structure": r["structure"],
        "kind": r["kind"],
        "of": r["of"],
        "accel": r["accel"],
        "params": r["params"],
        "status": r["status"],
        "message": str(r.get("message", "") or ""),
        "ci_coverage": r.get("ci_coverage", math.nan),
        "trace": ratio(r, e, "render_s"),
        "build": ratio(r, e, "build_s"),
        "has_baseline": e is not None,
        "own_trace": ratio(r, own, "render_s") if own is not None else NONE,
        "own_build": ratio(r, own, "build_s") if own is not None else NONE,
        "changes": _changes(r["param_dict"], own["param_dict"]) if own is not None else "",
    }


def shown(r: pd.DataFrame) -> pd.DataFrame:
    """Per structure and workload, one row with a ratio: of the structure's settings with a
    ratio there, the one with a ratio on the most workloads in the run (ties: the first
    parameters text), so a structure keeps one setting wherever it can."""
    rated = r[(r["status"] == "ok") & r["has_baseline"]]
    if rated.empty:
        return rated
    reach = rated.groupby(["structure", "params"])["workload"].nunique().rename("reach").reset_index()
    ordered = rated.merge(reach, on=["structure", "params"]).sort_values(
        ["structure", "workload", "reach", "params"], ascending=[True, True, False, True]
    )
    return ordered.drop_duplicates(["structure", "workload"]).drop(columns="reach")
