"""The open peers (and any plugin's structures) beside ours and Embree (configs/peers.yaml).

When a run has rows of structures loaded from a plugin (a `plugin_file`, or the structure
table's role `plugin`), every structure measured on the same model, ray set and workload is
ranked by its trace time against Embree's default there (the same Embree row as the ray-set
table's, workloads.baseline_row), with its build time against Embree's:

- tables/peers.md: per model, one row per structure, one column per ray set (the trace
  ratio and the structure's rank in that set), the build ratio (the median over the sets:
  each combination builds anew) and the wrong answers summed over the sets;
- tables/peers.csv: the same, one row per model, set and structure;
- figures/peers.png (and its Vega-Lite spec): the trace ratios per set, a panel per model.

A wrong answer against the reference (false misses, false hits, wrong primitives) and a
failed row are shown where they are, never dropped. Runs without plugin rows get none of
this."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ...inputs.schema import CAMERA_SET, RAY_SETS, Results
from ...mapping.formatting import md_escape
from ...mapping.structures import role_of
from ..figures.interactive import peers_spec, write_figure
from ..figures.workloads import (
    baseline_row,
    cells_per_set,
    hue_palette,
    md_table,
    structure_labels,
    workload_labels,
)

PEERS_DOC = "tables/peers.md"
PEERS_CSV = "tables/peers.csv"
PEERS_FIGURE = "figures/peers.png"
WRONG = ["false_misses", "false_hits", "prim_mismatches"]


def plugin_mask(rows: pd.DataFrame) -> pd.Series:
    """Per row: its structure came from a plugin."""
    roles = {a: role_of(a) for a in set(rows["accel"])}
    return (rows["plugin_file"] != "") | (rows["accel"].map(roles) == "plugin")


def origin(row: pd.Series) -> str:
    """Where a row's structure comes from: the plugin's version and file, Embree, or ours."""
    if row["plugin"]:
        name = Path(row["plugin_file"]).name if row["plugin_file"] else ""
        return f"plugin {row['plugin_version']} ({name})" if name else "plugin"
    return "Embree" if role_of(row["accel"]) == "baseline" else "ours"


def peer_rows(results: Results) -> pd.DataFrame:
    """Every measured row (failed ones too) of the models and workloads where a plugin's
    structure was measured, with its structure label, origin and panel; empty without
    plugin rows."""
    rows = results.measured_rows()
    rows = rows[rows["ray_set"].isin((CAMERA_SET, *RAY_SETS))].copy()
    if rows.empty:
        return rows
    rows["plugin"] = plugin_mask(rows)
    rows["structure"] = structure_labels(rows)
    rows["workload"] = workload_labels(rows)
    rows["panel"] = [m if not w else f"{m} ({w})" for m, w in zip(rows["model"], rows["workload"])]
    rows = rows[rows.groupby("panel")["plugin"].transform("any")].copy()
    rows["from"] = [origin(r) for _, r in rows.iterrows()] if len(rows) else []
    return rows


def peer_table(rows: pd.DataFrame) -> pd.DataFrame:
    """One row per panel, ray set and structure: trace and build time over Embree's default
    row of the same panel and set, and the rank by trace ratio among the set's ok rows (1 =
    fastest)."""
    parts = []
    for _, g in rows.groupby(["panel", "ray_set"], sort=False):
        t = g.copy()
        base = baseline_row(g[g["status"] == "ok"])
        ok = t["status"] == "ok"
        for what, col in (("trace", "render_s_median"), ("build", "build_s_median")):
            denominator = float("nan") if base is None else base[col]
            t[f"{what}_ratio"] = np.where(ok, t[col] / denominator, np.nan)
        t["rank"] = t["trace_ratio"].rank(method="min")
        parts.append(t)
    cols = [
        "model",
        "workload",
        "panel",
        "ray_set",
        "structure",
        "from",
        "accel",
        "params",
        "status",
        "render_s_median",
        "build_s_median",
        "trace_ratio",
        "build_ratio",
        "rank",
        *[c for c in WRONG if c in rows.columns],
    ]
    return pd.concat(parts)[cols].reset_index(drop=True)


def _sets(table: pd.DataFrame) -> list[str]:
    present = set(table["ray_set"])
    return [s for s in (CAMERA_SET, *RAY_SETS) if s in present]


def _wrong(values: pd.Series) -> str:
    return "-" if values.isna().all() else f"{int(values.fillna(0).sum()):,}"


def _ratio_cell(r: pd.Series) -> str:
    """A structure's cell in one set: its trace ratio and rank, its wrong answers, or the
    status of a failed row."""
    if r["status"] != "ok":
        return f"**{md_escape(r['status'])}**"
    cell = "-" if pd.isna(r["trace_ratio"]) else f"{r['trace_ratio']:.2f} ({int(r['rank'])})"
    wrong = sum(int(r[c]) for c in WRONG if c in r and pd.notna(r[c]))
    return cell + (f" [{wrong:,} wrong]" if wrong else "")


def _panel_lines(g: pd.DataFrame, sets: list[str]) -> list[str]:
    """One panel's table: the structures by the geometric mean of their trace ratios."""
    order = (
        g.groupby("structure")["trace_ratio"]
        .apply(lambda r: float(np.exp(np.log(r.dropna()).mean())) if r.notna().any() else np.inf)
        .sort_values(kind="stable")
    )
    body = []
    for place, (structure, mean) in enumerate(order.items(), 1):
        s = g[g["structure"] == structure]
        build = s["build_ratio"].dropna()
        body.append(
            [
                str(place) if np.isfinite(mean) else "-",
                md_escape(structure),
                md_escape(s["from"].iloc[0]),
                *cells_per_set(s, sets, _ratio_cell),
                f"{build.median():.2f}" if len(build) else "-",
                *[_wrong(s[c]) if c in s else "-" for c in WRONG],
            ]
        )
    return md_table(
        ["rank", "structure", "from", *sets, "build", *[c.replace("_", " ") for c in WRONG]], body
    )


def peers_markdown(table: pd.DataFrame) -> str:
    sets = _sets(table)
    out = [
        "# The open peers beside ours and Embree",
        "",
        "Per model: each structure's trace time divided by Embree's (defaults) on the same "
        "rays, per ray set, with its rank in that set in parentheses (1 = fastest; below 1 "
        "is faster than Embree); `build`: its build time over Embree's, the median over the "
        "sets (each combination builds anew). Rows ordered by the geometric mean of the "
        "trace ratios. `from`: ours, Embree, or the plugin (its version and file) the "
        "structure was loaded from. The last columns sum the wrong answers against the "
        "reference over the sets (false misses, false hits, wrong primitives: another "
        "triangle than the reference's at a distance more than 64 ulps from its hit, so "
        "never a tie of two triangles at the same distance); a cell names its own where "
        "there are any, and a failed row its status.",
        "",
    ]
    for panel, g in table.groupby("panel", sort=False):
        out += [f"## {md_escape(panel)}", ""] + _panel_lines(g, sets) + [""]
    return "\n".join(out)


def write_peers(results: Results, out_dir: Path) -> list[Path]:
    """tables/peers.md, .csv and figures/peers.png when the run has plugin rows; [] else."""
    rows = peer_rows(results)
    if rows.empty:
        return []
    table = peer_table(rows)
    (out_dir / "tables").mkdir(parents=True, exist_ok=True)
    table.drop(columns=["panel"]).to_csv(out_dir / PEERS_CSV, index=False)
    (out_dir / PEERS_DOC).write_text(peers_markdown(table))
    ok = table[table["trace_ratio"].notna()]
    figure = []
    if not ok.empty:
        palette = hue_palette(ok["structure"])
        figure = [write_figure(out_dir / PEERS_FIGURE, peers_spec(ok, _sets(ok), palette))]
    return [out_dir / PEERS_DOC, out_dir / PEERS_CSV, *figure]
