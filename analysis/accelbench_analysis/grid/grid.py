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
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from ..inputs.schema import ERROR_COLUMNS, RENDER_SETTING_COLUMNS, Results, normalise_value
from ..mapping.errors import COMPACT_HEADER, compact_errors
from ..mapping.formatting import fmt_sig, md_table
from .grid_config import (
    CHEAP,
    FINAL,
    PARAM_COL,
    PASS_COL,
    GridConfig,
    GridConfigError,
    final_config_name,
    typed,
)
from .heatmaps import write_heatmaps

# ---- analysis --------------------------------------------------------------------------------------


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
