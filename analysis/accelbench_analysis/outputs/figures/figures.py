"""Figures (PNG, seaborn on tidy data). Each function takes the loaded results and a path,
writes one PNG and returns the path, or returns None with the reason when the data for it
is not there (the REPORT.md writer prints that reason instead of the figure).

Colours are fixed per structure across all figures; nothing here draws random numbers,
but the seeds are fixed anyway (seaborn bootstraps when asked for CIs; we never ask, the
CIs come from the harness).
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker as mticker  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import seaborn as sns  # noqa: E402

from ...inputs.report_numbers import REPORT_MODELS, TABLE2_MODEL, our_model, report_value  # noqa: E402
from ...inputs.schema import Results  # noqa: E402
from ...mapping.errors import wrong_answers  # noqa: E402
from ...mapping.metrics import preferred_variant, ratio, structure_rows  # noqa: E402
from ...mapping.selection import Picker, label_of, setting_spec  # noqa: E402
from ...mapping.styles import Styles  # noqa: E402
from .interactive import build_vs_render_spec, error_pareto_spec, write_figure  # noqa: E402

SEED = 0
NO_MODES = "own (no modes)"  # traversal label of structures without traversal modes
DPI = 130
SOURCE_COLOURS = {"ours": "#d62728", "report": "#7f7f7f"}


@dataclass
class Skipped:
    reason: str


def setup() -> None:
    random.seed(SEED)
    np.random.seed(SEED)
    sns.set_theme(style="whitegrid", context="notebook", font_scale=0.9)


def model_order(results: Results) -> list[tuple[str, str]]:
    """(our model, display name): the report's models first (in its order), then the rest."""
    present = set(results.measured_rows()["model"])
    out, seen = [], set()
    for rm in REPORT_MODELS:
        ours = our_model(rm.key, present)
        if ours in present:
            name = ours if rm.stand_in is None else f"{ours}\n(for {rm.label})"
            out.append((ours, name))
            seen.add(ours)
    out += [(m, m) for m in sorted(present - seen)]
    return out


def structure_frame(results: Results) -> pd.DataFrame:
    """One tidy row per (model, structure, traversal), the report's setting preferred among a
    structure's rows (a run at the defaults is drawn too)."""
    picker = Picker(results)
    models = model_order(results)
    srows = structure_rows(picker, [m for m, _ in models])
    records = []
    for ours, name in models:
        for sr in srows:
            pick = picker.pick(ours, sr.structure.spec, sr.variant)
            if not pick.ok:
                continue
            r = pick.row
            records.append(
                {
                    "model": name,
                    "structure": sr.structure.label,
                    "traversal": sr.variant or NO_MODES,
                    "structure_key": sr.structure.key,
                    "params": r["params"],
                    "ci_coverage": r.get("ci_coverage"),
                    **{
                        c: r[c]
                        for c in (
                            "build_s_median",
                            "build_s_ci_lo",
                            "build_s_ci_hi",
                            "render_s_median",
                            "render_s_ci_lo",
                            "render_s_ci_hi",
                            "prim_tests",
                            "node_visits",
                            "rays",
                            "shadow_rays",
                        )
                    },
                }
            )
    return pd.DataFrame.from_records(records)


def save_figure(g, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = g.figure if hasattr(g, "figure") else g
    fig.savefig(path, dpi=DPI, bbox_inches="tight", metadata={"Software": None})
    plt.close(fig)
    return path


def plain_log_ticks(ax, axis: str = "y") -> None:
    """Log axes labelled 0.1, 0.2, 0.5, 1 ... instead of 10^-1, 2x10^-1 (after the limits are final)."""
    a = ax.yaxis if axis == "y" else ax.xaxis
    lo, hi = ax.get_ylim() if axis == "y" else ax.get_xlim()
    if lo <= 0 or hi <= 0:
        return
    decades = math.log10(hi / lo)
    subs = (1.0, 2.0, 5.0) if decades < 2.5 else (1.0,)
    a.set_major_locator(mticker.LogLocator(base=10, subs=subs))
    a.set_major_formatter(mticker.FuncFormatter(lambda v, _: f"{v:g}"))
    a.set_minor_formatter(mticker.NullFormatter())


def _palette(labels) -> dict[str, str]:
    return Styles(labels).palette()


# ---- build vs render ----------------------------------------------------------------------


def build_vs_render(results: Results, path: Path) -> Path | Skipped:
    """One point per structure and model, its 95% CIs as rules: one specification, the page's
    chart and the PNG."""
    df = structure_frame(results)
    df = df.dropna(subset=["build_s_median", "render_s_median"]) if len(df) else df
    if df.empty:
        return Skipped("no ok rows with build and render times at the report's default parameters")
    title = "Build vs render time at the report's default parameters (lower left is better)"
    return write_figure(path, build_vs_render_spec(df, title))


# ---- Table 2 sweeps -------------------------------------------------------------------------

SWEEP_METRICS = [
    ("nodes", "nodes", "#nodes"),
    ("prim_tests", "prim_tests", "#int. tests"),
    ("build_s_median", "build_s", "build time"),
    ("render_s_median", "render_s", "render time"),
]


def sweep_frame(results: Results, report_nums: pd.DataFrame) -> tuple[pd.DataFrame, dict[str, str]]:
    picker = Picker(results)
    model = our_model(TABLE2_MODEL, picker.models)
    t2 = report_nums[report_nums["table"] == 2]
    depths = [s.split("=")[1] for s in t2["setting"] if s.startswith("maxDepth=")]
    records, sweeps = [], {}
    for param, report_name in (("max_prims", "maxPrims"), ("max_depth", "maxDepth")):
        rep = t2[t2["setting"].str.startswith(report_name + "=")]
        # Our sweep: every kd-tree row that matches the spec of the sweep with the swept
        # parameter free (same other parameters as the report-setting rows).
        probe = setting_spec(rep["setting"].iloc[0], "kdtree", picker, model, depths)
        fixed = tuple((k, v) for k, v in probe.required if k != param)
        label = (
            f"{report_name} sweep ("
            + ", ".join(f"{k}={'auto' if v.startswith('<') else v}" for k, v in fixed)
            + ")"
        )
        sweeps[param] = label
        spec = type(probe)("kdtree", fixed, probe.preferred)
        cands = picker.candidates(model, spec)
        cands = cands[cands["status"] == "ok"]
        for _, r in cands.iterrows():
            x = r["param_dict"].get(param, "")
            try:
                x = float(x)
            except ValueError:
                continue
            records += [
                {"sweep": label, "x": x, "metric": title, "source": "ours", "value": r[col]}
                for col, _, title in SWEEP_METRICS
            ]
        for _, r in rep.iterrows():
            x = float(r["setting"].split("=")[1])
            records += [
                {"sweep": label, "x": x, "metric": title, "source": "report", "value": r[rcol]}
                for _, rcol, title in SWEEP_METRICS
            ]
    df = pd.DataFrame.from_records(records)
    if df.empty:
        return df, sweeps
    df = df.dropna(subset=["value"]).sort_values("x")
    df = df.groupby(["sweep", "metric", "source", "x"], as_index=False)["value"].median()

    df = df.sort_values(["sweep", "metric", "source", "x"])
    df["relative"] = df["value"] / df.groupby(["sweep", "metric", "source"])["value"].transform("first")
    return df, sweeps


def table2_sweeps(results: Results, report_nums: pd.DataFrame, path: Path) -> Path | Skipped:
    df, sweeps = sweep_frame(results, report_nums)
    if df.empty or not (df["source"] == "ours").any():
        return Skipped("no kd-tree sweep rows on the bunny")
    setup()
    metric_order = [m for _, _, m in SWEEP_METRICS]
    g = sns.relplot(
        data=df,
        kind="line",
        x="x",
        y="relative",
        hue="source",
        style="source",
        palette=SOURCE_COLOURS,
        markers=True,
        dashes=False,
        row="metric",
        row_order=metric_order,
        col="sweep",
        col_order=[sweeps["max_prims"], sweeps["max_depth"]],
        height=2.3,
        aspect=1.7,
        facet_kws={"sharex": "col", "sharey": False},
    )
    g.set(xscale="log", yscale="log")
    for (metric, sweep), ax in g.axes_dict.items():
        ax.axhline(1, color="black", lw=0.6, alpha=0.5)
        ax.set_title(f"{metric} — {sweep}", fontsize=9)
        plain_log_ticks(ax, "y")
    for ax in g.axes[-1]:
        xs = sorted(df.loc[df["sweep"] == ax.get_title().split(" — ")[1], "x"].unique())
        ax.set_xticks(xs)
        ax.set_xticklabels([f"{x:g}" for x in xs], rotation=0, fontsize=8)
        ax.minorticks_off()
    g.set_axis_labels("parameter value", "relative to the\nsweep's first setting")
    g.figure.suptitle(
        "Table 2 sweeps (kd-tree, Stanford bunny): how each metric moves, ours vs the report", y=1.02
    )
    return save_figure(g, path)


# ---- per-ray counters ---------------------------------------------------------------------------


def per_ray(results: Results, path: Path) -> Path | Skipped:
    df = structure_frame(results)
    if df.empty:
        return Skipped("no ok rows at the report's default parameters")
    df = df.copy()
    all_rays = df["rays"] + df["shadow_rays"].fillna(0)
    df["primitive tests per ray"] = df["prim_tests"] / all_rays
    df["node visits per ray"] = df["node_visits"] / all_rays
    df["structure"] = np.where(
        df["traversal"] == NO_MODES, df["structure"], df["structure"] + " · " + df["traversal"]
    )
    tidy = df.melt(
        id_vars=["model", "structure"],
        value_vars=["primitive tests per ray", "node visits per ray"],
        var_name="counter",
        value_name="per ray",
    ).dropna(subset=["per ray"])
    if tidy.empty:
        return Skipped("no row has prim_tests/node_visits counters")
    counted = set(tidy["structure"])
    without = sorted({s.split(" · ")[0] for s in set(df["structure"]) - counted})
    setup()
    styles = Styles(lbl.split(" · ")[0] for lbl in counted)
    order = sorted(counted, key=lambda lbl: (styles.order.index(lbl.split(" · ")[0]), lbl))
    palette = {lbl: styles.colour(lbl.split(" · ")[0]) for lbl in order}
    g = sns.catplot(
        data=tidy,
        kind="bar",
        x="model",
        y="per ray",
        hue="structure",
        hue_order=order,
        palette=palette,
        row="counter",
        sharey=False,
        height=2.8,
        aspect=4.2,
        errorbar=None,
    )
    # Hatch the report-order traversal so the two modes of one structure stay apart.
    hatched = [lbl.endswith("· report") for lbl in order]
    for ax in g.axes.flat:
        for container, hatch in zip(ax.containers, hatched):
            for bar in container:
                if hatch:
                    bar.set_hatch("//")
                    bar.set_edgecolor("white")
        ax.tick_params(axis="x", labelsize=8)
    for handle, hatch in zip(g.legend.legend_handles, hatched):
        if hatch:
            handle.set_hatch("//")
            handle.set_edgecolor("white")
    g.set_titles("{row_name}")
    g.set_axis_labels("", "per ray\n(primary + shadow)")
    note = f" ({', '.join(without)}: no counters)" if without else ""
    g.figure.suptitle(f"Traversal work per ray at the report's default parameters{note}", y=1.02)
    return save_figure(g, path)


# ---- render time vs error ---------------------------------------------------------------------


def pareto_front(points: pd.DataFrame, x: str, y: str) -> pd.DataFrame:
    """Points no other point beats in both x and y (lower is better in both)."""
    pts = points.sort_values([x, y])
    best = math.inf
    keep = []
    for idx, r in pts.iterrows():
        if r[y] < best:
            keep.append(idx)
            best = r[y]
    return pts.loc[keep]


WRONG = "wrong answers"


def error_frame(results: Results) -> pd.DataFrame:
    """The timed ok rows with error counts (catalogue verdicts have no time), their display
    model name and WRONG = false misses + false hits + wrong primitives."""
    rows = results.measured_rows()
    df = rows[rows["status"] == "ok"].dropna(subset=["render_s_median", "false_misses", "false_hits"]).copy()
    df["model"] = df["model"].map(dict(model_order(results)))
    df[WRONG] = wrong_answers(df)
    df["structure"] = [label_of(a, p) for a, p in zip(df["accel"], df["param_dict"])]
    return df


def error_pareto(results: Results, path: Path) -> Path | Skipped:
    """Render time against wrong answers (false misses + false hits + wrong primitives vs
    the reference) for every timed row, per model, coloured by structure. Zero is the
    common case (watertight structures), so the y axis is symlog; each structure's Pareto
    front is dashed and the points nothing beats overall are ringed."""
    if not results.has_error_columns():
        return Skipped(
            "no camera render of this run has false_misses/false_hits values (the harness's "
            "reference comparison did not run on them; a ray-set run's wrong answers are in "
            "its ray-set table)"
        )
    df = error_frame(results)
    if df.empty:
        return Skipped("no ok row has both a render time and error counts")
    y = WRONG
    colours = Styles(df["structure"]).palette()
    fronts = pd.concat(
        [pareto_front(pts, "render_s_median", y) for _, pts in df.groupby(["model", "structure"])]
    )
    df["optimal"] = df.index.isin(
        pd.concat([pareto_front(sub, "render_s_median", y) for _, sub in df.groupby("model")]).index
    )
    zero = ": every row has 0 wrong answers" if (df[y] == 0).all() else ""
    title = (
        f"Render time vs wrong answers over every parameter set{zero} (dashed: each "
        "structure's Pareto front; ringed: optimal overall)"
    )
    return write_figure(path, error_pareto_spec(df, fronts, y, title, colours))


# ---- relative to BVH --------------------------------------------------------------------------


def relative_frame(results: Results, report_nums: pd.DataFrame) -> pd.DataFrame:
    picker = Picker(results)
    records = []
    bvh = picker.structure("bvh")
    for rm in REPORT_MODELS:
        ours = our_model(rm.key, picker.models)
        label = rm.label + ("\n(stand-in)" if rm.stand_in else "")
        den = picker.pick(ours, bvh.table_spec, preferred_variant(picker.variants([ours], bvh.table_spec)))
        for s in picker.structures():
            if s.key == "bvh":
                continue
            num = picker.pick(ours, s.table_spec, preferred_variant(picker.variants([ours], s.table_spec)))
            for phase, col, rcol in (
                ("build", "build_s_median", "build_s"),
                ("render", "render_s_median", "render_s"),
            ):
                r = ratio(num.value(col), den.value(col))
                if r is not None:
                    records.append(
                        {"model": label, "structure": s.label, "phase": phase, "source": "ours", "ratio": r}
                    )
                if s.report_accel:
                    r = ratio(
                        report_value(report_nums, rm.key, s.report_accel, "default", rcol),
                        report_value(report_nums, rm.key, "bvh", "default", rcol),
                    )
                    if r is not None:
                        records.append(
                            {
                                "model": label,
                                "structure": s.label,
                                "phase": phase,
                                "source": "report",
                                "ratio": r,
                            }
                        )
    return pd.DataFrame.from_records(records)


def relative_to_bvh(results: Results, report_nums: pd.DataFrame, path: Path) -> Path | Skipped:
    df = relative_frame(results, report_nums)
    if df.empty or not (df["source"] == "ours").any():
        return Skipped("no BVH (median) rows to divide by")
    setup()
    order = Styles(df["structure"]).order
    models = list(dict.fromkeys(df["model"]))
    g = sns.catplot(
        data=df,
        kind="point",
        x="model",
        y="ratio",
        hue="source",
        order=models,
        hue_order=["ours", "report"],
        palette=SOURCE_COLOURS,
        markers=["o", "X"],
        linestyles="none",
        dodge=0.3,
        row="structure",
        row_order=order,
        col="phase",
        height=2.2,
        aspect=2.6,
        sharey=False,
        errorbar=None,
    )
    g.set(yscale="log")
    for ax in g.axes.flat:
        ax.axhline(1, color="black", lw=0.8)
        lo, hi = ax.get_ylim()
        ax.set_ylim(min(lo, 0.8), max(hi, 1.25))
        plain_log_ticks(ax, "y")
        ax.tick_params(axis="x", labelsize=8)
    g.set_titles("{row_name}: {col_name} time")
    g.set_axis_labels("", "time / BVH (median)")
    g.figure.suptitle(
        "Time relative to BVH (median) on the same model (below 1 = faster "
        "than BVH): the comparison that survives a change of machine",
        y=1.01,
    )
    return save_figure(g, path)


FIGURES = {
    "build_vs_render": (
        "Build vs render time per structure and model (report defaults), medians with their CIs",
        lambda res, report_nums, p: build_vs_render(res, p),
    ),
    "relative_to_bvh": (
        "Build and render time relative to the median-split BVH, ours beside the report's",
        relative_to_bvh,
    ),
    "table2_sweeps": (
        "Table 2's kd-tree parameter sweeps on the bunny, each series relative to its first setting",
        table2_sweeps,
    ),
    "per_ray": (
        "Primitive tests and node visits per ray (primary + shadow)",
        lambda res, report_nums, p: per_ray(res, p),
    ),
    "error_pareto": (
        "Render time vs wrong answers (false misses + false hits + wrong "
        "primitives) against the reference, with the Pareto front",
        lambda res, report_nums, p: error_pareto(res, p),
    ),
}


def write_figures(results: Results, report_nums: pd.DataFrame, out_dir: Path) -> dict[str, Path | Skipped]:
    out = {}
    for name, (_, fn) in FIGURES.items():
        out[name] = fn(results, report_nums, out_dir / f"{name}.png")
    return out
