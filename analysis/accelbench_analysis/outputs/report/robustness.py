"""robustness.md: the extreme-case catalogue and the stiff-parameter runs of
configs/robustness.yaml as three tables.

(a) A verdict per case and accelerator setting. A case's rows have the model label
    `case-<id>:<name>`, status ok, no timings, and the harness's `verdict` (pass/fail) with
    the counts behind it in `verdict_counts`. Columns are the accelerators, split by the
    parameters that vary between that accelerator's case rows (Embree robust=false/true,
    kd-tree max_depth=100 ...), so that every column is one configuration.
(b) Every failure with its counts and the harness's message, and every case that did not
    complete (status error/timeout/skipped: a structure that refused a case up front says
    why there).
(c) The timed rows (stiff parameters on real models): times, tree size and depth, memory
    (the structure's own and the process's high-water mark) and the error columns.
"""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd

from ...inputs.schema import CASE_PREFIX, Results
from ...mapping.errors import ERROR_METRIC, NOT_MEASURED, error_text, shown_metrics
from ...mapping.formatting import fmt_count, fmt_sig, is_missing, md_escape, md_table

ACCEL_ORDER = ("brute_force", "bvh", "lbvh", "kdtree", "embree", "reference")
MIB = 1024 * 1024
PASS, FAIL, NO_ROW = "pass", "**FAIL**", "—"


def case_id(model: str) -> tuple[str, str]:
    """("2a", "closed-meshes-translated-1.5e5") from "case-2a:closed-meshes-translated-1.5e5"."""
    label = model[len(CASE_PREFIX) :] if model.startswith(CASE_PREFIX) else model
    cid, _, name = label.partition(":")
    return cid, name


def case_sort_key(model: str) -> tuple:
    """Catalogue order: 1, 2a, 2b, ..., 10, 14a (numeric part first, then the letters)."""
    cid, name = case_id(model)
    m = re.match(r"(\d+)(.*)", cid)
    return (0, int(m.group(1)), m.group(2), name) if m else (1, 0, cid, name)


def accel_sort_key(accel: str) -> tuple:
    return (ACCEL_ORDER.index(accel) if accel in ACCEL_ORDER else len(ACCEL_ORDER), accel)


def varying_params(rows: pd.DataFrame) -> dict[str, list[str]]:
    """Per accelerator, the parameters whose values differ between its rows."""
    out = {}
    for accel, sub in rows.groupby("accel"):
        dicts = list(sub["param_dict"])
        keys = sorted({k for d in dicts for k in d})
        out[accel] = [k for k in keys if len({d.get(k, "") for d in dicts}) > 1]
    return out


def setting_label(
    accel: str, params: dict[str, str], varying: list[str], full_when_alone: bool = False
) -> str:
    """accel plus the parameters that tell its rows apart ("embree robust=true")."""
    keys = varying or (sorted(params) if full_when_alone else [])
    shown = " ".join(f"{k}={params[k]}" for k in keys if k in params)
    return f"{accel} {shown}".strip()


def newest(rows: pd.DataFrame) -> pd.Series:
    return rows.sort_values("timestamp", ascending=False, kind="stable").iloc[0]


def one_line(text) -> str:
    return " ".join(str(text or "").split())


def verdict_cell(row: pd.Series | None) -> str:
    if row is None:
        return NO_ROW
    if row["status"] != "ok":
        return row["status"]
    return {"pass": PASS, "fail": FAIL}.get(row["verdict"], "no verdict")


def mib(x) -> str:
    return "—" if is_missing(x) else fmt_sig(float(x) / MIB)


def verdict_section(cases: pd.DataFrame) -> tuple[list[str], list[str]]:
    """(a) and (b): the case x setting table and the failure list."""
    if cases.empty:
        return (["No catalogue case rows (model `case-<id>:<name>`) in the CSV."], ["None (no case rows)."])
    varying = varying_params(cases)
    cases = cases.assign(
        setting=[setting_label(a, p, varying.get(a, [])) for a, p in zip(cases["accel"], cases["param_dict"])]
    )
    settings = sorted(set(zip(cases["accel"], cases["setting"])), key=lambda t: (accel_sort_key(t[0]), t[1]))
    columns = [s for _, s in settings]
    models = sorted(set(cases["model"]), key=case_sort_key)
    chosen: dict[tuple[str, str], pd.Series] = {}
    for (model, setting), sub in cases.groupby(["model", "setting"]):
        chosen[(model, setting)] = newest(sub)

    table_rows, fails_per_column = [], {c: 0 for c in columns}
    for model in models:
        cid, name = case_id(model)
        cells = [cid, name]
        for c in columns:
            cell = verdict_cell(chosen.get((model, c)))
            fails_per_column[c] += cell != PASS and cell != NO_ROW
            cells.append(cell)
        table_rows.append(cells)
    table_rows.append(["", "**not passed**"] + [str(fails_per_column[c]) for c in columns])
    counts = pd.Series([verdict_cell(r) for r in chosen.values()]).value_counts()
    summary = (
        f"{len(models)} cases x {len(columns)} accelerator settings: "
        f"{counts.get(PASS, 0)} pass, {counts.get(FAIL, 0)} FAIL, "
        f"{sum(v for k, v in counts.items() if k not in (PASS, FAIL))} did not complete "
        f"or have no verdict, {len(models) * len(columns) - len(chosen)} combinations "
        f"without a row (—)."
    )
    verdicts = [summary, ""] + md_table(["case", "name"] + columns, table_rows, align="ll")

    failures = []
    for (model, setting), r in sorted(chosen.items(), key=lambda kv: (case_sort_key(kv[0][0]), kv[0][1])):
        cell = verdict_cell(r)
        if cell == PASS:
            continue
        cid, name = case_id(model)
        failures.append(
            [cid, name, setting, cell.strip("*"), one_line(r["verdict_counts"]), one_line(r["message"])]
        )
    fail_lines = (
        md_table(
            ["case", "name", "accelerator", "verdict / status", "counts", "message"], failures, align="llllll"
        )
        if failures
        else ["None: every case row passed."]
    )
    return verdicts, fail_lines


def timed_section(timed: pd.DataFrame) -> list[str]:
    """(c): the stiff-parameter rows."""
    if timed.empty:
        return ["No timed rows in the CSV."]
    varying = varying_params(timed)
    metrics = [
        ERROR_METRIC[c]
        for c in (
            "false_misses",
            "false_hits",
            "prim_mismatches",
            "nan_results",
            "t_err_ulp_p50",
            "t_err_ulp_max",
        )
    ]
    metrics += [m for m in shown_metrics(timed) if m.image]
    header = (
        [
            "model",
            "accelerator",
            "status",
            "build (s)",
            "render (s)",
            "nodes",
            "max depth",
            "memory (MiB)",
            "peak RSS (MiB)",
        ]
        + [m.short for m in metrics]
        + ["message"]
    )
    out = []
    order = timed.assign(_a=timed["accel"].map(accel_sort_key)).sort_values(
        ["model", "_a", "params"], kind="stable"
    )
    for _, r in order.iterrows():
        ok = r["status"] == "ok"
        label = setting_label(r["accel"], r["param_dict"], varying.get(r["accel"], []), full_when_alone=True)
        out.append(
            [
                r["model"],
                label,
                r["status"] if ok else f"**{r['status']}**",
                fmt_sig(r["build_s_median"]),
                fmt_sig(r["render_s_median"]),
                fmt_count(r["nodes"]),
                fmt_count(r["tree_depth"]),
                mib(r["memory_bytes"]),
                mib(r["peak_rss_bytes"]),
            ]
            + [error_text(r, m) if ok else "—" for m in metrics]
            + [one_line(r["message"]) if not ok else ""]
        )
    return md_table(header, out, align="lll" + "r" * (len(header) - 4) + "l")


def robustness_markdown(results: Results) -> str:
    from .report import provenance_lines  # the same provenance block as REPORT.md

    cases, timed = results.case_rows(), results.measured_rows()
    verdicts, failures = verdict_section(cases)
    out = ["# Robustness: the extreme-case catalogue and stiff parameters", ""]
    out += [f"> **Warning:** {md_escape(w)}\n" for w in results.warnings]
    out += provenance_lines(results)
    out += [
        "",
        "## Verdicts per case and accelerator setting",
        "",
        "Each cell is the harness's verdict for the case's scene and rays on that "
        "configuration (what a correct implementation must do is written beside each case in "
        "core/accelbench/robustness_cases.cpp; `accelbench list` prints it). A status (error, timeout, skipped) means the case did "
        "not complete; — means no row. Columns show only the parameters that vary "
        "between the accelerator's case rows.",
        "",
    ]
    out += verdicts
    out += [
        "",
        "## Failures",
        "",
        "Every cell above that is not a pass, with the counts behind the verdict and the harness's message.",
        "",
    ] + failures
    out += [
        "",
        "## Stiff parameters (timed rows)",
        "",
        "Extreme parameter values on real models: they must terminate with bounded memory "
        "or be refused with a message naming the limit. Memory is the structure's own "
        "(memory_bytes); peak RSS is the measuring process's high-water mark, loaded "
        "model included. Errors are counts over the primary rays against the "
        f"`reference` accelerator ({NOT_MEASURED}: the comparison did not run). "
        "Accelerator labels show the parameters that vary between its rows (all of "
        "them when it has one row).",
        "",
    ]
    out += timed_section(timed)
    return "\n".join(out) + "\n"


def write_robustness(results: Results, out_dir: Path) -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "robustness.md"
    path.write_text(robustness_markdown(results))
    return path
