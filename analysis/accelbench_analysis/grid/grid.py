"""Parameter grid search: rank the harness's rows of a grid config, write the winners.

The config (grid_config.py, its axes expanded by the harness) gives the accelerator, the
objective and the constraints; the CSV gives what ran: parameter values are read back from
its `params` text, which is authoritative. Outputs, under results/grid/<config>/: best.yaml (per model, the winner as
an entry for another config's `accelerators:` list), ranked.csv (every candidate with its
objective, rank, and why it was rejected), heatmap-<model>-<p>-<q>.png (the objective over
each pair of varied parameters, minimum over the others, with the report's and pbrt's
defaults marked) and summary.md. `halve` writes the second pass of successive halving.

With successive halving, `analyse` takes the second (final) pass as the candidates and the
first (cheap) pass as context: only final rows are ranked, so best.yaml's winner was
measured at full repetitions, while the heatmaps and ranked.csv also show the cheap pass
over the whole grid (its rows judged by the same constraints, never ranked). Ranking both
passes together would let a lucky one-repetition row beat every re-measured candidate.
"""

from __future__ import annotations

import copy
import itertools
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from ..inputs.schema import ERROR_COLUMNS, RENDER_SETTING_COLUMNS, Results, normalise_value
from ..mapping.selection import kd_auto_depth_pbrt, kd_auto_depth_report
from ..outputs.errors import COMPACT_HEADER, compact_errors
from ..outputs.formatting import fmt_sig, md_table
from .grid_config import GridConfig, GridConfigError, typed

# ---- published default settings, marked on the heatmaps ---------------------------------------------------


@dataclass(frozen=True)
class PublishedSetting:
    """A setting someone published as the default (the report's Table 3, pbrt's), drawn as a
    marker on the heatmaps so the grid's best can be read against it."""

    label: str
    marker: str
    colour: str
    values: dict  # parameter -> value; a parameter it does not fix is absent
    note: str


def published_settings(accel: str, triangles: float) -> list[PublishedSetting]:
    """The report's defaults (its Table 3) and pbrt's, for the accelerators that have them."""
    if accel == "kdtree":
        costs = {"isect_cost": 80, "traversal_cost": 1, "empty_bonus": 0.5}
        return [
            PublishedSetting(
                "report",
                "*",
                "white",
                {"max_prims": 1, "max_depth": kd_auto_depth_report(triangles), **costs},
                "report Table 3: maxPrims 1, depth round(8 + 1.3 log2 N), pbrt's SAH costs",
            ),
            PublishedSetting(
                "pbrt-v3",
                "o",
                "#e7298a",
                {"max_prims": 1, "max_depth": kd_auto_depth_pbrt(triangles), **costs},
                "pbrt-v3 KdTreeAccel: maxprims 1, maxdepth -1 = round(8 + 1.3 Log2Int(N)), "
                "isectcost 80, traversalcost 1, emptybonus 0.5",
            ),
        ]
    if accel == "bvh":
        return [
            PublishedSetting(
                "report",
                "*",
                "white",
                {"split": "median", "max_prims": 1, "max_depth": 50},
                "report Table 3: median split, maxPrims 1, depth 50",
            ),
            PublishedSetting(
                "pbrt-v4",
                "o",
                "#e7298a",
                {"split": "sah", "max_prims": 4},
                "pbrt-v4 BVHAggregate: SAH over 12 buckets, maxnodeprims 4 by default "
                "(clamped to at most 255), no depth limit",
            ),
        ]
    if accel == "lbvh":
        return [
            PublishedSetting(
                "report",
                "*",
                "white",
                {"max_prims": 1, "max_depth": 50},
                "report Table 3: maxPrims 1, depth 50, Morton codes",
            )
        ]
    return []


# ---- analysis --------------------------------------------------------------------------------------

PARAM_COL = "param:"  # ranked.csv's per-parameter columns, so they never meet a statistic's name
PASS_COL = "pass"
FINAL, CHEAP = "final", "cheap"  # ranked candidates; the cheap pass's rows shown as context


def final_config_name(cfg: GridConfig) -> str:
    """The name `halve` gives the second pass's config (its rows carry it in `config`)."""
    return f"{cfg.name}-final"


@dataclass
class PassInfo:
    """What one pass contributed: its CSVs, its rows of the accelerator (one per candidate)
    and the repetitions its measured rows had."""

    files: list[str]
    rows: int
    repetitions: list[int]

    def repetitions_text(self) -> str:
        reps = "/".join(str(r) for r in self.repetitions) or "no measured"
        return f"{reps} repetition{'' if self.repetitions == [1] else 's'}"

    def describe(self) -> str:
        return f"{', '.join(self.files)}: {self.rows} rows at {self.repetitions_text()}"


@dataclass
class GridAnalysis:
    config: GridConfig
    ranked: pd.DataFrame  # one row per candidate: model, rank, objective, rejected, reason, ...
    varied: list[str]
    notes: list[str] = field(default_factory=list)
    constraints_checked: dict[str, bool] = field(default_factory=dict)
    final: PassInfo | None = None
    cheap: PassInfo | None = None  # the cheap pass given as context, if any

    @property
    def files(self) -> list[str]:
        return self.final.files if self.final else []

    def models(self) -> list[str]:
        return list(dict.fromkeys(self.ranked["model"]))

    def best(self, model: str) -> pd.Series | None:
        r = self.ranked[(self.ranked["model"] == model) & (self.ranked["rank"] == 1)]
        return None if r.empty else r.iloc[0]

    def candidates(self, model: str | None = None) -> pd.DataFrame:
        """The rows that compete for the best: the final pass's."""
        r = self.ranked[self.ranked[PASS_COL] == FINAL]
        return r if model is None else r[r["model"] == model]

    def accepted(self, model: str | None = None, with_cheap: bool = False) -> pd.DataFrame:
        """Candidates no constraint rejected; with_cheap adds the cheap pass's such rows."""
        r = self.ranked if with_cheap else self.candidates()
        r = r[~r["rejected"]]
        return r if model is None else r[r["model"] == model]


def _num(text: str) -> float | None:
    try:
        f = float(text)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def axis_order(texts) -> list[str]:
    """Distinct values, numerically sorted when all are numbers, else in order of appearance."""
    values = list(dict.fromkeys(texts))
    if all(_num(v) is not None for v in values):
        return sorted(values, key=_num)
    return values


def _dedupe(rows: pd.DataFrame, notes: list[str]) -> pd.DataFrame:
    """One candidate per (model, params): given several CSVs (shards, or a rerun), the row
    with the most repetitions wins, then the newest."""
    ordered = rows.sort_values(["repetitions", "timestamp"], ascending=False, kind="stable")
    kept = ordered.drop_duplicates(["model", "params"]).sort_index()
    if len(kept) < len(rows):
        notes.append(
            f"{len(rows) - len(kept)} rows measure a candidate already measured with "
            f"more repetitions (or later) and were set aside"
        )
    return kept


def workloads(rows: pd.DataFrame) -> list[str]:
    """The workloads the rows measure: the ray set and the render settings (image, threads,
    light, ...) that tell them apart, as text; one entry when every row traced the same."""
    settings = ["ray_set"] + [c for c in RENDER_SETTING_COLUMNS if c in rows.columns]
    kinds = rows[settings].astype(str).drop_duplicates()
    return ["; ".join(f"{c}={v}" for c, v in r.items()) for _, r in kinds.iterrows()]


def _accel_rows(results: Results, cfg: GridConfig, what: str, notes: list[str]) -> pd.DataFrame:
    """The rows of the config's accelerator, one per candidate (what: "the CSV", ...). Rows
    of more than one workload (ray sets, thread counts, images) are refused: one candidate
    would be ranked by one workload's time and the next by another's."""
    df = results.rows
    others = df[df["accel"] != cfg.accel]
    if not others.empty:
        notes.append(
            f"{what}: {len(others)} rows of other accelerators "
            f"({', '.join(sorted(set(others['accel'])))}) were ignored"
        )
    rows = df[df["accel"] == cfg.accel]
    if rows.empty:
        raise GridConfigError(f"{what} has no rows of accelerator {cfg.accel!r} (the config's accelerator)")
    if len(kinds := workloads(rows)) > 1:
        raise GridConfigError(
            f"{what} holds rows of {len(kinds)} workloads ({' | '.join(kinds[:4])}): candidates are "
            f"ranked within one; give the CSVs of one"
        )
    configs = sorted(set(rows["config"]))
    if not {cfg.name, final_config_name(cfg)} & set(configs):
        notes.append(
            f"{what}'s rows come from config(s) {', '.join(configs)}, not {cfg.name!r} "
            f"or its second pass {final_config_name(cfg)!r}"
        )
    return _dedupe(rows, notes)


def _pass_info(results: Results, rows: pd.DataFrame) -> PassInfo:
    ok = rows[rows["status"] == "ok"]
    return PassInfo(
        list(results.files), len(rows), sorted({int(r) for r in pd.to_numeric(ok["repetitions"]).dropna()})
    )


def analyse(results: Results, cfg: GridConfig, cheap: Results | None = None) -> GridAnalysis:
    """Ranks the rows of `results`; `cheap` (the first pass of successive halving) adds
    context rows, judged by the same constraints but never ranked (module doc)."""
    notes: list[str] = []
    rows = _accel_rows(results, cfg, "the CSV", notes)
    final = _pass_info(results, rows)
    if len(final.repetitions) > 1 and cheap is None:
        notes.append(
            f"the ranked rows were measured with different repetitions "
            f"({', '.join(map(str, final.repetitions))}): a candidate measured only "
            f"cheaply competes with re-measured ones; give a cheap pass with --cheap"
        )
    rows = rows.assign(**{PASS_COL: FINAL})
    cheap_info = None
    if cheap is not None:
        context = _accel_rows(cheap, cfg, "the cheap pass's CSV", notes)
        if workloads(context) != workloads(rows):
            raise GridConfigError(
                f"the cheap pass measured another workload ({workloads(context)[0]}) than the ranked "
                f"rows ({workloads(rows)[0]}): its rows cannot stand beside them"
            )
        cheap_info = _pass_info(cheap, context)
        final_keys = pd.MultiIndex.from_frame(rows[["model", "params"]])
        again = pd.MultiIndex.from_frame(context[["model", "params"]]).isin(final_keys)
        if again.any():
            notes.append(
                f"{int(again.sum())} cheap-pass rows were re-measured in the final "
                f"pass: their final values are used"
            )
        rows = pd.concat([rows, context[~again].assign(**{PASS_COL: CHEAP})], ignore_index=True)

    out = pd.DataFrame(
        {
            "model": rows["model"].values,
            "accel": rows["accel"].values,
            "params": rows["params"].values,
            "triangles": rows["triangles"].values,
            "status": rows["status"].values,
            "objective": cfg.objective.value(rows["build_s_median"], rows["render_s_median"]).values,
            "build_s_median": rows["build_s_median"].values,
            "render_s_median": rows["render_s_median"].values,
            "repetitions": rows["repetitions"].values,
            PASS_COL: rows[PASS_COL].values,
        }
    )
    for extra in ("combo_id", "config"):
        if extra in rows.columns:
            out[extra] = rows[extra].values
    for col in ERROR_COLUMNS:  # how wrong each candidate is, constrained or not
        out[col] = rows[col].values
    dicts = list(rows["param_dict"])
    names = list(dict.fromkeys([n for n in cfg.given] + sorted({n for d in dicts for n in d})))
    varied = [n for n in names if len({d.get(n) for d in dicts}) > 1]
    for n in names:
        out[PARAM_COL + n] = [d.get(n, "") for d in dicts]

    reasons = [[] for _ in range(len(rows))]
    for i, (status, message) in enumerate(zip(rows["status"], rows["message"])):
        if status != "ok":
            reasons[i].append(f"status {status}" + (f": {message}" if message else ""))
        elif math.isnan(out["objective"].iat[i]):
            reasons[i].append("no build or render time")
    checked = {}
    for col, limit in cfg.constraints.items():
        values = (
            pd.to_numeric(rows[col].replace("", np.nan), errors="coerce")
            if col in rows.columns
            else pd.Series(np.nan, index=rows.index)
        )
        checked[col] = bool(values.notna().any())
        out[col] = values.values
        if not checked[col]:
            why = (
                "the harness wrote no error columns (run with the reference comparison on)"
                if col in ERROR_COLUMNS
                else "the CSV has no such column"
            )
            notes.append(
                f"constraint {col} <= {limit:g} NOT CHECKED: no row has a {col} "
                f"value; {why}. No candidate was rejected for it."
            )
            continue
        for i, v in enumerate(values):
            if reasons[i]:
                continue
            if pd.isna(v):
                reasons[i].append(f"{col} not measured")
            elif v > limit:
                reasons[i].append(f"{col} = {v:g} > {limit:g}")
    out["reason"] = ["; ".join(r) for r in reasons]
    out["rejected"] = out["reason"] != ""
    out["rank"] = pd.array([pd.NA] * len(out), dtype="Int64")
    for model in dict.fromkeys(out["model"]):
        ok = out[(out["model"] == model) & ~out["rejected"] & (out[PASS_COL] == FINAL)]
        order = ok.sort_values(["objective", "params"], kind="stable").index
        out.loc[order, "rank"] = list(range(1, len(order) + 1))
    out = (
        out.assign(_cheap=out[PASS_COL] == CHEAP)
        .sort_values(
            ["model", "_cheap", "rejected", "rank", "objective", "params"], kind="stable", na_position="last"
        )
        .drop(columns="_cheap")
        .reset_index(drop=True)
    )
    second_pass_only = cheap is None and set(rows["config"]) == {final_config_name(cfg)}
    notes += _coverage(cfg, out, second_pass_only)
    return GridAnalysis(cfg, out, varied, notes, checked, final, cheap_info)


def _coverage(cfg: GridConfig, ranked: pd.DataFrame, second_pass_only: bool) -> list[str]:
    """Grid points of the config with no row in the CSV (an unfinished run, a missing
    shard, or a second pass given without its first), and rows outside the grid (a CSV of
    another config)."""
    names = cfg.given
    if not names:
        return []
    expected = {tuple(normalise_value(str(p[n])) for n in names) for p in cfg.points()}
    notes = []
    for model in dict.fromkeys(ranked["model"]):
        sel = ranked[ranked["model"] == model]
        seen = {tuple(sel[PARAM_COL + n].iat[i] for n in names) for i in range(len(sel))}
        missing, extra = expected - seen, seen - expected
        why = (
            "only the second pass was given: add the first with --cheap"
            if second_pass_only
            else "run not finished, or a shard not merged"
        )
        if missing:
            notes.append(
                f"{model}: {len(missing)} of the config's {len(expected)} grid points have no row ({why})"
            )
        if extra:
            notes.append(
                f"{model}: {len(extra)} candidates lie outside the config's grid (ranked all the same)"
            )
    return notes


# ---- outputs -------------------------------------------------------------------------------------------


def snippet(cfg: GridConfig, row: pd.Series) -> list[dict]:
    """The winner as an `accelerators:` list entry: the parameters the grid config gives."""
    params = {n: typed(row[PARAM_COL + n]) for n in cfg.given if row[PARAM_COL + n] != ""}
    return [{"name": cfg.accel, "params": params}]


def dump_yaml(doc: dict, comments: list[str]) -> str:
    head = "".join(f"# {c}\n" for c in comments)
    return head + yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=100)


def best_document(a: GridAnalysis) -> dict:
    cfg = a.config
    best = {}
    for model in a.models():
        r = a.best(model)
        n_ok, n = len(a.accepted(model)), len(a.candidates(model))
        if r is None:
            best[model] = {"accepted": 0, "candidates": n, "accelerators": None}
            continue
        best[model] = {
            "objective_s": float(r["objective"]),
            "build_s_median": float(r["build_s_median"]),
            "render_s_median": float(r["render_s_median"]),
            "repetitions": int(r["repetitions"]),
            "accepted": n_ok,
            "candidates": n,
            "accelerators": snippet(cfg, r),
        }
    context = {"cheap_csv": a.cheap.files} if a.cheap else {}
    return {
        "config": cfg.name,
        "config_file": str(cfg.path),
        "csv": a.files,
        **context,
        "objective": cfg.objective.label,
        "constraint": {c: (v if not float(v).is_integer() else int(v)) for c, v in cfg.constraints.items()},
        "constraint_checked": a.constraints_checked,
        "best": best,
    }


def write_ranked(a: GridAnalysis, path: Path) -> Path:
    cols = (
        ["model", "rank", "objective", "rejected", "reason"]
        + [PARAM_COL + n for n in a.varied]
        + ["build_s_median", "render_s_median", "repetitions", PASS_COL, "status"]
        + list(dict.fromkeys(list(a.config.constraints) + ERROR_COLUMNS))
        + ["accel", "params"]
        + [c for c in ("combo_id", "config") if c in a.ranked.columns]
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    a.ranked[cols].to_csv(path, index=False)
    return path


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", text)


def marker_position(axis_values: list[str], value) -> float | None:
    """Where a published setting's value sits on a heatmap axis (cell index, fractional between two
    numeric cells, geometric axes interpolated in log space); None when off the grid."""
    if value is None:
        return None
    text = normalise_value(str(value))
    if text in axis_values:
        return float(axis_values.index(text))
    v, nums = _num(text), [_num(x) for x in axis_values]
    if v is None or any(x is None for x in nums) or len(nums) < 2 or not nums[0] <= v <= nums[-1]:
        return None
    log = (
        nums[0] > 0
        and len(nums) >= 3
        and np.allclose(np.diff(np.log(nums)), math.log(nums[1] / nums[0]), rtol=1e-6)
    )
    f = np.log if log else (lambda x: x)
    return float(np.interp(f(v), f(np.array(nums)), np.arange(len(nums))))


MARKER_HEIGHT = 0.2  # published-setting markers sit this far up their cell (the number is at 0.5)


@dataclass
class HeatmapData:
    """One heatmap's cells, rows the values of q and columns those of p (axis order)."""

    objective: pd.DataFrame  # minimum over the other parameters among accepted rows; NaN: none
    source: pd.DataFrame  # the pass of the row giving that minimum (FINAL, CHEAP; "": none)
    rejected: pd.DataFrame  # the cell has rows, and every one was rejected
    remeasured: pd.DataFrame  # the cell has a final-pass row (accepted or not)

    @property
    def xs(self) -> list[str]:
        return list(self.objective.columns)

    @property
    def ys(self) -> list[str]:
        return list(self.objective.index)


def heatmap_data(a: GridAnalysis, model: str, p: str, q: str) -> HeatmapData:
    """The cells of heatmap(): every pass's rows count, so with a cheap pass the map covers
    the whole grid, its re-measured cells taking the final values (analyse keeps only the
    final row of a candidate measured in both)."""
    sel = a.ranked[a.ranked["model"] == model]
    px, qy = PARAM_COL + p, PARAM_COL + q
    xs, ys = axis_order(sel[px]), axis_order(sel[qy])
    acc = sel[~sel["rejected"]]
    best = acc.loc[acc.groupby([qy, px])["objective"].idxmin()] if not acc.empty else acc

    def cells(column: str) -> pd.DataFrame:
        return best.pivot(index=qy, columns=px, values=column).reindex(index=ys, columns=xs)

    def having(rows: pd.DataFrame) -> pd.DataFrame:
        counts = rows.groupby([qy, px]).size()
        return (
            counts.unstack().reindex(index=ys, columns=xs).notna()
            if len(counts)
            else pd.DataFrame(False, index=ys, columns=xs)
        )

    objective = cells("objective").astype(float)
    return HeatmapData(
        objective,
        cells(PASS_COL).fillna(""),
        having(sel) & objective.isna(),
        having(sel[sel[PASS_COL] == FINAL]),
    )


def heatmap(a: GridAnalysis, model: str, p: str, q: str, path: Path) -> Path:
    """The objective over (p, q), each cell the minimum over the other parameters among
    accepted rows (heatmap_data); grey cells have no row, hatched ones only rejected rows.
    With a cheap pass, cells holding a re-measured candidate are outlined and numbers that
    are final-pass values bold: a cheap minimum (one noisy repetition, and the least of
    several) can sit below every final value. Published default settings and the best cell are marked."""
    import matplotlib.pyplot as plt
    import seaborn as sns
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Rectangle

    from ..outputs.figures import save_figure, setup

    setup()
    sel = a.ranked[a.ranked["model"] == model]
    data = heatmap_data(a, model, p, q)
    xs, ys, grid = data.xs, data.ys, data.objective
    fig, ax = plt.subplots(figsize=(max(5.0, 0.75 * len(xs) + 2.5), max(4.0, 0.5 * len(ys) + 2.2)))
    ax.set_facecolor("#d0d0d0")
    small = len(xs) <= 12 and len(ys) <= 12
    sns.heatmap(
        grid.astype(float),
        ax=ax,
        cmap="viridis_r",
        annot=small,
        fmt=".3g",
        annot_kws={"fontsize": 7},
        cbar_kws={"label": f"{a.config.objective.label} (s)"},
        linewidths=0.5,
        linecolor="white",
    )
    ax.invert_yaxis()  # small values at the bottom, like a plot
    ax.set_xlabel(p)
    ax.set_ylabel(q)
    others = [n for n in a.varied if n not in (p, q)]
    title = f"{model}: {a.config.accel}, {a.config.objective.label}"
    if others:
        title += f"\nminimum over {', '.join(others)}"
    handles = []
    if a.cheap is not None:
        title += "\nfinal-pass values where re-measured (bold), cheap pass elsewhere"
        for iy, ix in zip(*np.nonzero(data.remeasured.to_numpy())):
            ax.add_patch(
                Rectangle((ix + 0.06, iy + 0.06), 0.88, 0.88, fill=False, edgecolor="black", lw=1.2, ls=":")
            )
        final_cells = data.source == FINAL
        for text in ax.texts:  # seaborn's numbers sit at the cell centres
            x, y = text.get_position()
            if final_cells.iat[int(y), int(x)]:
                text.set_fontweight("bold")
        handles.append(
            Patch(
                facecolor="none",
                edgecolor="black",
                ls=":",
                label=(
                    f"dotted: holds a candidate re-measured in the final pass "
                    f"({a.final.repetitions_text()}); bold number: the minimum is a final value\n"
                    f"  other numbers: cheap pass ({a.cheap.repetitions_text()}: noisier, and a minimum "
                    f"of noisy values is biased low)"
                ),
            )
        )
    ax.set_title(title, fontsize=10)
    for iy, ix in zip(*np.nonzero(data.rejected.to_numpy())):
        ax.add_patch(Rectangle((ix, iy), 1, 1, fill=False, hatch="xxx", edgecolor="#707070", lw=0))
    best = a.best(model)
    if best is not None:
        bx, by = xs.index(best[PARAM_COL + p]), ys.index(best[PARAM_COL + q])
        ax.add_patch(Rectangle((bx, by), 1, 1, fill=False, edgecolor="red", lw=2.5))
        handles.append(
            Patch(
                facecolor="none",
                edgecolor="red",
                lw=2,
                label=(
                    f"best: {p}={best[PARAM_COL + p]}, {q}={best[PARAM_COL + q]} "
                    f"({fmt_sig(best['objective'])} s at {int(best['repetitions'])} repetitions)"
                ),
            )
        )
    triangles = float(sel["triangles"].iloc[0])
    for mark in published_settings(a.config.accel, triangles):
        vx, vy = mark.values.get(p), mark.values.get(q)
        px, py = marker_position(xs, vx), marker_position(ys, vy)
        where = f"{p}={vx if vx is not None else 'not fixed'}, {q}={vy if vy is not None else 'not fixed'}"
        star = mark.marker == "*"
        style = dict(
            marker=mark.marker,
            ls="none",
            mfc=mark.colour if star else "none",
            mec="black" if star else mark.colour,
            mew=1.0 if star else 2.0,
        )
        if px is not None and py is not None:
            # Low in the cell, below the cell's number; a star inside a circle when both coincide.
            ax.plot(px + 0.5, py + MARKER_HEIGHT, ms=8 if star else 12, **style)
        else:
            where += " (off this grid)"
        handles.append(Line2D([], [], ms=9, label=f"{mark.label}: {where}\n  {mark.note}", **style))
    if data.rejected.any().any():
        why = [f"{c} > {v:g}" for c, v in a.config.constraints.items()] + ["a failed run"]
        handles.append(
            Patch(
                facecolor="#d0d0d0",
                hatch="xxx",
                edgecolor="#707070",
                label=f"hatched: every row here rejected ({' or '.join(why)})",
            )
        )
    if (grid.isna() & ~data.rejected).any().any():
        handles.append(Patch(facecolor="#d0d0d0", label="grey: not measured"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(0, -0.14), fontsize=7, frameon=False)
    return save_figure(fig, path)


def write_heatmaps(a: GridAnalysis, out: Path) -> tuple[list[Path], list[str]]:
    written, notes = [], []
    for model in a.models():
        sel = a.ranked[a.ranked["model"] == model]
        varied = [n for n in a.varied if sel[PARAM_COL + n].nunique() > 1]
        if len(varied) < 2:
            notes.append(f"{model}: no heatmap, fewer than two parameters vary")
            continue
        if a.accepted(model, with_cheap=True).empty:
            notes.append(f"{model}: no heatmap, every row was rejected")
            continue
        for p, q in itertools.combinations(varied, 2):
            written.append(heatmap(a, model, p, q, out / f"heatmap-{_slug(model)}-{p}-{q}.png"))
    return written, notes


def _pass_lines(a: GridAnalysis) -> list[str]:
    if a.cheap is None:
        return [f"- CSV: {a.final.describe()}"]
    context = int((a.ranked[PASS_COL] == CHEAP).sum())
    return [
        f"- final pass (ranked: the best is chosen among these only): {a.final.describe()}",
        f"- cheap pass (context: heatmaps and ranked.csv, never ranked): "
        f"{a.cheap.describe()}; {a.cheap.rows - context} of them re-measured in the final "
        f"pass, the other {context} shown with their cheap values",
    ]


def summary_markdown(a: GridAnalysis, heatmaps: list[Path], extra_notes: list[str]) -> str:
    cfg = a.config
    lines = [
        f"# Grid search {cfg.name}: {cfg.accel}",
        "",
        f"- config: {cfg.path} ({cfg.mode}; {cfg.combinations()} combinations in the grid)",
        *_pass_lines(a),
        f"- objective: {cfg.objective.label} (seconds, medians of the repetitions)",
        "- constraints: "
        + (
            ", ".join(
                f"{c} <= {v:g} ({'checked' if a.constraints_checked[c] else 'NOT CHECKED'})"
                for c, v in cfg.constraints.items()
            )
            or "none"
        ),
        f"- varied: {', '.join(a.varied) or 'nothing'}",
        "",
    ]
    rows = []
    for model in a.models():
        r = a.best(model)
        n = len(a.candidates(model))
        if r is None:
            rows.append([model, "—", "no accepted candidate", "—", "—", f"0 of {n}"])
            continue
        rows.append(
            [
                model,
                fmt_sig(r["objective"]),
                ", ".join(f"{k}={v}" for k, v in snippet(cfg, r)[0]["params"].items()),
                f"{fmt_sig(r['build_s_median'])} / {fmt_sig(r['render_s_median'])}",
                compact_errors(r),
                f"{len(a.accepted(model))} of {n}",
            ]
        )
    lines += md_table(
        [
            "model",
            "objective (s)",
            "best parameters",
            "build / render (s)",
            f"errors ({COMPACT_HEADER})",
            "accepted" + (" (final pass)" if a.cheap else ""),
        ],
        rows,
        align="lrlrrr",
    )
    for n in a.notes + extra_notes:
        lines += ["", f"- {n}"]
    if heatmaps:
        lines += ["", "## Heatmaps", ""] + [f"![{h.stem}]({h.name})" for h in heatmaps]
    return "\n".join(lines) + "\n"


def write_outputs(a: GridAnalysis, out: Path, heatmaps: bool = True) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    cfg = a.config
    best = out / "best.yaml"
    best.write_text(
        dump_yaml(
            best_document(a),
            [
                f"Best {cfg.accel} parameters per model from grid search {cfg.name} "
                f"(python -m accelbench_analysis grid).",
                "best.<model>.accelerators is an entry for another config's `accelerators:` list.",
            ],
        )
    )
    written = [best, write_ranked(a, out / "ranked.csv")]
    maps, notes = write_heatmaps(a, out) if heatmaps else ([], ["heatmaps not drawn (--no-heatmaps)"])
    summary = out / "summary.md"
    summary.write_text(summary_markdown(a, maps, notes))
    return written + maps + [summary]


# ---- successive halving ------------------------------------------------------------------------------------


def halve(a: GridAnalysis, keep: int, csv_files: list[str]) -> tuple[dict, str]:
    """The second pass: the config with the top `keep` candidates of each model (their
    union: the harness runs every model with every kept tuple) at full repetitions."""
    if keep < 1:
        raise GridConfigError(f"--keep must be at least 1 (got {keep})")
    cfg = a.config
    acc = a.accepted()
    if acc.empty:
        raise GridConfigError("no candidate satisfies the constraints: nothing to keep")
    top = acc[acc["rank"] <= keep].sort_values(["rank", "objective"], kind="stable")
    varied = [n for n in cfg.given if n in a.varied]
    if not varied:
        raise GridConfigError("no parameter of the config varies in the CSV: nothing to halve")
    tuples = list(dict.fromkeys(tuple(r[PARAM_COL + n] for n in varied) for _, r in top.iterrows()))
    # The config's order, the kept tuples (one zipped axis) where the first varied one was.
    params: dict = {}
    for axis in cfg.axes:
        for i, n in enumerate(axis.names):
            if n == varied[0] and len(varied) == 1:
                params[n] = [typed(t[0]) for t in tuples]
            elif n == varied[0]:
                params["[" + ", ".join(varied) + "]"] = [[typed(x) for x in t] for t in tuples]
            elif n not in varied:
                values = {v[i] for v in axis.values}
                params[n] = next(iter(values)) if len(values) == 1 else typed(acc[PARAM_COL + n].iat[0])
    doc = copy.deepcopy(cfg.raw)
    doc["name"] = final_config_name(cfg)
    if cfg.final_repetitions is not None:
        doc["repetitions"] = cfg.final_repetitions
    if cfg.final_warmup is not None:
        doc["warmup"] = cfg.final_warmup
    doc["accelerators"] = [{"name": cfg.accel, "params": params}]
    grid = {k: v for k, v in doc["grid"].items() if k not in ("mode", "successive_halving")}
    first = len(a.ranked)
    grid["halved_from"] = {
        "config": str(cfg.path),
        "csv": list(csv_files),
        "first_pass_rows": first,
        "keep_per_model": keep,
        "kept": len(tuples),
    }
    doc["grid"] = grid
    models = len(cfg.raw["models"])
    text = (
        f"kept {len(tuples)} parameter tuples (top {keep} of each of {len(a.models())} "
        f"models, {len(acc)} accepted of {first} rows); the second pass runs "
        f"{models} x {len(tuples)} = {models * len(tuples)} combinations at "
        f"{doc.get('repetitions', 'the default')} repetitions"
    )
    return doc, text
