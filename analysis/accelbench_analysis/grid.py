"""Parameter grid search: rank the harness's rows of a grid config, write the winners.

The config (grid_config.py) gives the accelerator, the objective and the constraints;
the CSV gives what ran: parameter values are read back from its `params` text, which is
authoritative. Outputs, under results/grid/<config>/: best.yaml (per model, the winner as
an entry for another config's `accelerators:` list), ranked.csv (every candidate with its
objective, rank, and why it was rejected), heatmap-<model>-<p>-<q>.png (the objective over
each pair of varied parameters, minimum over the others, with the report's and pbrt's
defaults marked) and summary.md. `halve` writes the second pass of successive halving.
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

from .grid_config import GridConfig, GridConfigError
from .render import fmt_sig, md_table
from .errors import COMPACT_HEADER, compact_errors
from .schema import ERROR_COLUMNS, Results, normalise_value
from .selection import kd_auto_depth_pbrt, kd_auto_depth_report


# ---- the reference points marked on the heatmaps ---------------------------------------------------

@dataclass(frozen=True)
class Reference:
    label: str
    marker: str
    colour: str
    values: dict  # parameter -> value; a parameter it does not fix is absent
    note: str


def references(accel: str, triangles: float) -> list[Reference]:
    """The report's defaults (its Table 3) and pbrt's, for the accelerators that have them."""
    if accel == "kdtree":
        costs = {"isect_cost": 80, "traversal_cost": 1, "empty_bonus": 0.5}
        return [
            Reference("report", "*", "white",
                      {"max_prims": 1, "max_depth": kd_auto_depth_report(triangles), **costs},
                      "report Table 3: maxPrims 1, depth round(8 + 1.3 log2 N), pbrt's SAH costs"),
            Reference("pbrt-v3", "o", "#e7298a",
                      {"max_prims": 1, "max_depth": kd_auto_depth_pbrt(triangles), **costs},
                      "pbrt-v3 KdTreeAccel: maxprims 1, maxdepth -1 = round(8 + 1.3 Log2Int(N)), "
                      "isectcost 80, traversalcost 1, emptybonus 0.5"),
        ]
    if accel == "bvh":
        return [
            Reference("report", "*", "white", {"split": "median", "max_prims": 1, "max_depth": 50},
                      "report Table 3: median split, maxPrims 1, depth 50"),
            Reference("pbrt-v4", "o", "#e7298a", {"split": "sah", "max_prims": 4},
                      "pbrt-v4 BVHAggregate: SAH over 12 buckets, maxnodeprims 4 by default "
                      "(clamped to at most 255), no depth limit"),
        ]
    if accel == "lbvh":
        return [Reference("report", "*", "white", {"max_prims": 1, "max_depth": 50},
                          "report Table 3: maxPrims 1, depth 50, Morton codes")]
    return []


# ---- analysis --------------------------------------------------------------------------------------

PARAM_COL = "param:"  # ranked.csv's per-parameter columns, so they never meet a statistic's name


@dataclass
class GridAnalysis:
    config: GridConfig
    ranked: pd.DataFrame  # one row per candidate: model, rank, objective, rejected, reason, ...
    varied: list[str]
    notes: list[str] = field(default_factory=list)
    constraints_checked: dict[str, bool] = field(default_factory=dict)
    files: list[str] = field(default_factory=list)

    def models(self) -> list[str]:
        return list(dict.fromkeys(self.ranked["model"]))

    def best(self, model: str) -> pd.Series | None:
        r = self.ranked[(self.ranked["model"] == model) & (self.ranked["rank"] == 1)]
        return None if r.empty else r.iloc[0]

    def accepted(self, model: str | None = None) -> pd.DataFrame:
        r = self.ranked[~self.ranked["rejected"]]
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
    """One candidate per (model, params): given several CSVs (e.g. both passes of successive
    halving), the row with the most repetitions wins, then the newest."""
    ordered = rows.sort_values(["repetitions", "timestamp"], ascending=False, kind="stable")
    kept = ordered.drop_duplicates(["model", "params"]).sort_index()
    if len(kept) < len(rows):
        notes.append(f"{len(rows) - len(kept)} rows measure a candidate already measured with "
                     f"more repetitions (or later) and were set aside")
    return kept


def analyse(results: Results, cfg: GridConfig) -> GridAnalysis:
    notes: list[str] = []
    df = results.rows
    others = df[df["accel"] != cfg.accel]
    if not others.empty:
        notes.append(f"{len(others)} rows of other accelerators "
                     f"({', '.join(sorted(set(others['accel'])))}) were ignored")
    rows = df[df["accel"] == cfg.accel]
    if rows.empty:
        raise GridConfigError(f"the CSV has no rows of accelerator {cfg.accel!r} "
                              f"(the config's accelerator)")
    configs = sorted(set(rows["config"]))
    if cfg.name not in configs:
        notes.append(f"the CSV's rows come from config(s) {', '.join(configs)}, not {cfg.name!r}")
    rows = _dedupe(rows, notes)

    out = pd.DataFrame({
        "model": rows["model"].values, "accel": rows["accel"].values,
        "params": rows["params"].values, "triangles": rows["triangles"].values,
        "status": rows["status"].values,
        "objective": cfg.objective.value(rows["build_s_median"], rows["render_s_median"]).values,
        "build_s_median": rows["build_s_median"].values,
        "render_s_median": rows["render_s_median"].values,
        "repetitions": rows["repetitions"].values})
    for extra in ("combo_id", "config"):
        if extra in rows.columns:
            out[extra] = rows[extra].values
    for col in ERROR_COLUMNS:  # how wrong each candidate is (issue 6), constrained or not
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
        values = (pd.to_numeric(rows[col].replace("", np.nan), errors="coerce")
                  if col in rows.columns else pd.Series(np.nan, index=rows.index))
        checked[col] = bool(values.notna().any())
        out[col] = values.values
        if not checked[col]:
            why = ("the harness wrote no error columns (run with the reference comparison on)"
                   if col in ERROR_COLUMNS else "the CSV has no such column")
            notes.append(f"constraint {col} <= {limit:g} NOT CHECKED: no row has a {col} "
                         f"value; {why}. No candidate was rejected for it.")
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
        ok = out[(out["model"] == model) & ~out["rejected"]]
        order = ok.sort_values(["objective", "params"], kind="stable").index
        out.loc[order, "rank"] = list(range(1, len(order) + 1))
    out = out.sort_values(["model", "rejected", "rank", "params"], kind="stable",
                          na_position="last").reset_index(drop=True)
    notes += _coverage(cfg, out)
    return GridAnalysis(cfg, out, varied, notes, checked, results.files)


def _coverage(cfg: GridConfig, ranked: pd.DataFrame) -> list[str]:
    """Grid points of the config with no row in the CSV (an unfinished run or a missing
    shard), and rows outside the grid (a CSV of another config)."""
    names = cfg.given
    if not names:
        return []
    expected = {tuple(normalise_value(str(p[n])) for n in names) for p in cfg.points()}
    notes = []
    for model in dict.fromkeys(ranked["model"]):
        sel = ranked[ranked["model"] == model]
        seen = {tuple(sel[PARAM_COL + n].iat[i] for n in names) for i in range(len(sel))}
        missing, extra = expected - seen, seen - expected
        if missing:
            notes.append(f"{model}: {len(missing)} of the config's {len(expected)} grid points "
                         f"have no row (run not finished, or a shard not merged)")
        if extra:
            notes.append(f"{model}: {len(extra)} candidates lie outside the config's grid "
                         f"(ranked all the same)")
    return notes


# ---- outputs -------------------------------------------------------------------------------------------

def typed(text: str):
    """A parameter's canonical text as the YAML scalar the harness reads back to the same value."""
    t = normalise_value(text)
    if t in ("true", "false"):
        return t == "true"
    if re.fullmatch(r"-?[0-9]+", t):
        return int(t)
    f = _num(t)
    return f if f is not None else t


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
        n_ok = len(a.accepted(model))
        if r is None:
            best[model] = {"accepted": 0, "candidates": int((a.ranked["model"] == model).sum()),
                           "accelerators": None}
            continue
        best[model] = {
            "objective_s": float(r["objective"]), "build_s_median": float(r["build_s_median"]),
            "render_s_median": float(r["render_s_median"]), "repetitions": int(r["repetitions"]),
            "accepted": n_ok, "candidates": int((a.ranked["model"] == model).sum()),
            "accelerators": snippet(cfg, r)}
    return {"config": cfg.name, "config_file": str(cfg.path), "csv": a.files,
            "objective": cfg.objective.label,
            "constraint": {c: (v if not float(v).is_integer() else int(v))
                           for c, v in cfg.constraints.items()},
            "constraint_checked": a.constraints_checked, "best": best}


def write_ranked(a: GridAnalysis, path: Path) -> Path:
    cols = (["model", "rank", "objective", "rejected", "reason"]
            + [PARAM_COL + n for n in a.varied]
            + ["build_s_median", "render_s_median", "repetitions", "status"]
            + list(dict.fromkeys(list(a.config.constraints) + ERROR_COLUMNS))
            + ["accel", "params"]
            + [c for c in ("combo_id", "config") if c in a.ranked.columns])
    path.parent.mkdir(parents=True, exist_ok=True)
    a.ranked[cols].to_csv(path, index=False)
    return path


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", text)


def marker_position(axis_values: list[str], value) -> float | None:
    """Where a reference value sits on a heatmap axis (cell index, fractional between two
    numeric cells, geometric axes interpolated in log space); None when off the grid."""
    if value is None:
        return None
    text = normalise_value(str(value))
    if text in axis_values:
        return float(axis_values.index(text))
    v, nums = _num(text), [_num(x) for x in axis_values]
    if v is None or any(x is None for x in nums) or len(nums) < 2 or not nums[0] <= v <= nums[-1]:
        return None
    log = nums[0] > 0 and len(nums) >= 3 and np.allclose(
        np.diff(np.log(nums)), math.log(nums[1] / nums[0]), rtol=1e-6)
    f = np.log if log else (lambda x: x)
    return float(np.interp(f(v), f(np.array(nums)), np.arange(len(nums))))


MARKER_HEIGHT = 0.2  # reference markers sit this far up their cell (the number is at 0.5)


def heatmap(a: GridAnalysis, model: str, p: str, q: str, path: Path) -> Path:
    """The objective over (p, q), each cell the minimum over the other parameters among
    accepted candidates; grey cells have none. References and the best cell are marked."""
    import matplotlib.pyplot as plt
    import seaborn as sns
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Rectangle

    from .figures import _save, setup

    setup()
    sel = a.ranked[a.ranked["model"] == model]
    xs, ys = axis_order(sel[PARAM_COL + p]), axis_order(sel[PARAM_COL + q])
    acc = sel[~sel["rejected"]]
    grid = (acc.pivot_table(index=PARAM_COL + q, columns=PARAM_COL + p, values="objective",
                            aggfunc="min").reindex(index=ys, columns=xs))
    fig, ax = plt.subplots(figsize=(max(5.0, 0.75 * len(xs) + 2.5), max(4.0, 0.5 * len(ys) + 2.2)))
    ax.set_facecolor("#d0d0d0")
    small = len(xs) <= 12 and len(ys) <= 12
    sns.heatmap(grid.astype(float), ax=ax, cmap="viridis_r", annot=small, fmt=".3g",
                annot_kws={"fontsize": 7}, cbar_kws={"label": f"{a.config.objective.label} (s)"},
                linewidths=0.5, linecolor="white")
    ax.invert_yaxis()  # small values at the bottom, like a plot
    ax.set_xlabel(p)
    ax.set_ylabel(q)
    others = [n for n in a.varied if n not in (p, q)]
    ax.set_title(f"{model}: {a.config.accel}, {a.config.objective.label}"
                 + (f"\nminimum over {', '.join(others)}" if others else ""), fontsize=10)

    handles = []
    best = a.best(model)
    if best is not None:
        bx, by = xs.index(best[PARAM_COL + p]), ys.index(best[PARAM_COL + q])
        ax.add_patch(Rectangle((bx, by), 1, 1, fill=False, edgecolor="red", lw=2.5))
        handles.append(Patch(facecolor="none", edgecolor="red", lw=2,
                             label=f"best: {p}={best[PARAM_COL + p]}, {q}={best[PARAM_COL + q]}"))
    triangles = float(sel["triangles"].iloc[0])
    for ref in references(a.config.accel, triangles):
        vx, vy = ref.values.get(p), ref.values.get(q)
        px, py = marker_position(xs, vx), marker_position(ys, vy)
        where = (f"{p}={vx if vx is not None else 'not fixed'}, "
                 f"{q}={vy if vy is not None else 'not fixed'}")
        star = ref.marker == "*"
        style = dict(marker=ref.marker, ls="none", mfc=ref.colour if star else "none",
                     mec="black" if star else ref.colour, mew=1.0 if star else 2.0)
        if px is not None and py is not None:
            # Low in the cell, below the cell's number; a star inside a circle when both coincide.
            ax.plot(px + 0.5, py + MARKER_HEIGHT, ms=8 if star else 12, **style)
        else:
            where += " (off this grid)"
        handles.append(Line2D([], [], ms=9, label=f"{ref.label}: {where}\n  {ref.note}", **style))
    if grid.isna().any().any():
        handles.append(Patch(facecolor="#d0d0d0", label="grey: no accepted candidate"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(0, -0.14), fontsize=7,
              frameon=False)
    return _save(fig, path)


def write_heatmaps(a: GridAnalysis, out: Path) -> tuple[list[Path], list[str]]:
    written, notes = [], []
    for model in a.models():
        sel = a.ranked[a.ranked["model"] == model]
        varied = [n for n in a.varied if sel[PARAM_COL + n].nunique() > 1]
        if len(varied) < 2:
            notes.append(f"{model}: no heatmap, fewer than two parameters vary")
            continue
        if a.accepted(model).empty:
            notes.append(f"{model}: no heatmap, every candidate was rejected")
            continue
        for p, q in itertools.combinations(varied, 2):
            written.append(heatmap(a, model, p, q, out / f"heatmap-{_slug(model)}-{p}-{q}.png"))
    return written, notes


def summary_markdown(a: GridAnalysis, heatmaps: list[Path], extra_notes: list[str]) -> str:
    cfg = a.config
    lines = [f"# Grid search {cfg.name}: {cfg.accel}", "",
             f"- config: {cfg.path} ({cfg.mode}; {cfg.combinations()} combinations in the grid)",
             f"- CSV: {', '.join(a.files)}",
             f"- objective: {cfg.objective.label} (seconds, medians of the repetitions)",
             "- constraints: " + (", ".join(
                 f"{c} <= {v:g} ({'checked' if a.constraints_checked[c] else 'NOT CHECKED'})"
                 for c, v in cfg.constraints.items()) or "none"),
             f"- varied: {', '.join(a.varied) or 'nothing'}", ""]
    rows = []
    for model in a.models():
        r = a.best(model)
        n = int((a.ranked["model"] == model).sum())
        if r is None:
            rows.append([model, "—", "no accepted candidate", "—", "—", f"0 of {n}"])
            continue
        rows.append([model, fmt_sig(r["objective"]),
                     ", ".join(f"{k}={v}" for k, v in snippet(cfg, r)[0]["params"].items()),
                     f"{fmt_sig(r['build_s_median'])} / {fmt_sig(r['render_s_median'])}",
                     compact_errors(r), f"{len(a.accepted(model))} of {n}"])
    lines += md_table(["model", "objective (s)", "best parameters", "build / render (s)",
                       f"errors ({COMPACT_HEADER})", "accepted"], rows, align="lrlrrr")
    for n in a.notes + extra_notes:
        lines += ["", f"- {n}"]
    if heatmaps:
        lines += ["", "## Heatmaps", ""] + [f"![{h.stem}]({h.name})" for h in heatmaps]
    return "\n".join(lines) + "\n"


def write_outputs(a: GridAnalysis, out: Path, heatmaps: bool = True) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    cfg = a.config
    best = out / "best.yaml"
    best.write_text(dump_yaml(best_document(a), [
        f"Best {cfg.accel} parameters per model from grid search {cfg.name} "
        f"(python -m accelbench_analysis grid).",
        "best.<model>.accelerators is an entry for another config's `accelerators:` list."]))
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
                params[n] = next(iter(values)) if len(values) == 1 else \
                    typed(acc[PARAM_COL + n].iat[0])
    doc = copy.deepcopy(cfg.raw)
    doc["name"] = f"{cfg.name}-final"
    if cfg.final_repetitions is not None:
        doc["repetitions"] = cfg.final_repetitions
    if cfg.final_warmup is not None:
        doc["warmup"] = cfg.final_warmup
    doc["accelerators"] = [{"name": cfg.accel, "params": params}]
    grid = {k: v for k, v in doc["grid"].items() if k not in ("mode", "successive_halving")}
    first = len(a.ranked)
    grid["halved_from"] = {"config": str(cfg.path), "csv": list(csv_files),
                           "first_pass_rows": first, "keep_per_model": keep,
                           "kept": len(tuples)}
    doc["grid"] = grid
    models = len(cfg.raw["models"])
    text = (f"kept {len(tuples)} parameter tuples (top {keep} of each of {len(a.models())} "
            f"models, {len(acc)} accepted of {first} rows); the second pass runs "
            f"{models} x {len(tuples)} = {models * len(tuples)} combinations at "
            f"{doc.get('repetitions', 'the default')} repetitions")
    return doc, text
