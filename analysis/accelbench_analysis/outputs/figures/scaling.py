"""Beyond the report: how time grows with the triangle count (configs/scaling.yaml)
and where in the image a structure spends its work (cost images from `accelbench render
--cost-out`)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker as mticker  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from ...inputs.schema import ContractError, Results, record_lines, scan_records, to_numbers  # noqa: E402
from ...mapping.selection import label_of  # noqa: E402
from ...mapping.styles import Styles  # noqa: E402
from .figures import DPI, plain_log_ticks  # noqa: E402
from .interactive import scaling_spec, write_spec  # noqa: E402

TIMES = {"build_s_median": "build", "render_s_median": "render"}
FAMILY_MARKERS = ["o", "s", "^", "D", "v"]


def scaling_frame(results: Results) -> pd.DataFrame:
    """ok rows as (family, size label, structure, triangles, build, render). The family is
    the model label before '@' (stanford-dragon@decimate=10000 -> stanford-dragon), so the
    sizes of one source model form one series."""
    rows = results.rows[results.rows["status"] == "ok"].copy()
    rows["structure"] = [label_of(a, p) for a, p in zip(rows["accel"], rows["param_dict"])]
    rows["family"] = rows["model"].str.split("@").str[0]
    keep = ["family", "model", "structure", "triangles", *TIMES]
    # One point per size and structure: two (other parameters, or one size measured twice)
    # would be fitted as if they were one series.
    twice = rows.duplicated(["model", "structure"], keep=False)
    if twice.any():
        shown = rows.loc[twice, ["model", "structure", "params", "source"]].head(4)
        raise ValueError(
            "more than one row of a structure on one model size, so a fit would mix them: "
            + "; ".join(f"{r.structure} on {r.model} [{r.params}] ({r.source})" for r in shown.itertuples())
        )
    return rows[keep].sort_values(["family", "structure", "triangles"]).reset_index(drop=True)


def fit_slopes(frame: pd.DataFrame) -> pd.DataFrame:
    """Least-squares slope of log(time) against log(triangles) per (family, structure,
    time): time ~ triangles^slope. Needs two sizes at least; n says how many."""
    out = []
    for (family, structure), g in frame.groupby(["family", "structure"], sort=True):
        for col, what in TIMES.items():
            ok = g[(g[col] > 0) & (g["triangles"] > 0)]
            if ok["triangles"].nunique() < 2:
                continue
            x, y = np.log10(ok["triangles"].astype(float)), np.log10(ok[col].astype(float))
            slope, intercept = np.polyfit(x, y, 1)
            out.append(
                {
                    "family": family,
                    "structure": structure,
                    "time": what,
                    "slope": float(slope),
                    "intercept": float(intercept),
                    "n": len(ok),
                    "min_triangles": int(ok["triangles"].min()),
                    "max_triangles": int(ok["triangles"].max()),
                }
            )
    return pd.DataFrame.from_records(
        out,
        columns=["family", "structure", "time", "slope", "intercept", "n", "min_triangles", "max_triangles"],
    )


def fit_lines(frame: pd.DataFrame, slopes: pd.DataFrame) -> pd.DataFrame:
    """Each fit drawn as in the figure: from the series' smallest to its largest size,
    (time, family, structure, triangles, seconds, slope) at both ends."""
    out = []
    column = {what: col for col, what in TIMES.items()}
    for _, f in slopes.iterrows():
        col = column[f["time"]]
        g = frame[
            (frame["structure"] == f["structure"]) & (frame["family"] == f["family"]) & (frame[col] > 0)
        ]
        for x in (float(g["triangles"].min()), float(g["triangles"].max())):
            out.append(
                {
                    "time": f["time"],
                    "family": f["family"],
                    "structure": f["structure"],
                    "triangles": x,
                    "seconds": 10 ** (f["intercept"] + f["slope"] * np.log10(x)),
                    "slope": f["slope"],
                }
            )
    return pd.DataFrame.from_records(
        out, columns=["time", "family", "structure", "triangles", "seconds", "slope"]
    )


def _triangles_tick(v: float, _pos) -> str:
    """10000 -> 10k, 1000000 -> 1M."""
    if v >= 1e6:
        return f"{v / 1e6:g}M"
    return f"{v / 1e3:g}k" if v >= 1e3 else f"{v:g}"


def scaling_figure(frame: pd.DataFrame, slopes: pd.DataFrame, path: Path) -> Path:
    """Build (left) and render (right) time against triangles, log-log: one colour per
    structure, one marker per source model, each series with its fitted line and slope
    (the interactive version beside it: the same points and lines)."""
    lines = fit_lines(frame, slopes)
    styles = Styles(frame["structure"])
    structures = styles.order
    families = sorted(frame["family"].unique())
    fig, axes = plt.subplots(1, 2, figsize=(12, 6.6), constrained_layout=True)
    for ax, (col, what) in zip(axes, TIMES.items()):
        for s in structures:
            colour = styles.colour(s)
            for k, fam in enumerate(families):
                g = frame[(frame["structure"] == s) & (frame["family"] == fam) & (frame[col] > 0)]
                if g.empty:
                    continue
                fit = lines[(lines["structure"] == s) & (lines["family"] == fam) & (lines["time"] == what)]
                label = f"{s}, {fam}"
                if not fit.empty:
                    ax.plot(fit["triangles"], fit["seconds"], "-", color=colour, lw=1.2, alpha=0.8)
                    label += f": slope {fit['slope'].iloc[0]:.2f}"
                ax.plot(
                    g["triangles"],
                    g[col],
                    FAMILY_MARKERS[k % len(FAMILY_MARKERS)],
                    color=colour,
                    ms=6,
                    mfc="white" if k else colour,
                    label=label,
                )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("triangles")
        ax.set_ylabel(f"{what} time, median (s)")
        ax.set_title(f"{what} time vs triangles (log-log; slope 1 = linear)")
        ax.grid(True, which="both", alpha=0.3)
        plain_log_ticks(ax, "y")
        ax.xaxis.set_major_formatter(mticker.FuncFormatter(_triangles_tick))
        # Below the axes: inside, the legend would hide the smallest sizes' points.
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, frameon=False)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI, metadata={"Software": None})
    plt.close(fig)
    points = frame.melt(
        id_vars=["family", "model", "structure", "triangles"],
        value_vars=list(TIMES),
        var_name="time",
        value_name="seconds",
    )
    points["time"] = points["time"].map(TIMES)
    write_spec(path, scaling_spec(points[points["seconds"] > 0], lines))
    return path


def slopes_markdown(slopes: pd.DataFrame, files: list[str]) -> str:
    """OUT/tables/scaling.md: one row per structure, build and render slopes per model."""
    families = sorted(slopes["family"].unique())
    head = ["structure"] + [f"{what} slope, {fam}" for fam in families for what in TIMES.values()]
    lines = [
        "# Scaling: time ~ triangles^slope",
        "",
        "Least-squares fit of log10(median time) against log10(triangles) over the sizes "
        "of each source model (dragon: OpenMesh quadric decimation; bunny: Loop "
        "subdivision). A slope of 1 is linear growth; n log n over 10k..1M triangles fits "
        "about 1.1. Render times are for a fixed image (the config's size), so they "
        "grow with the depth of the structure, not with the triangle count itself.",
        "",
        "Sizes per fit: "
        + "; ".join(
            f"{fam} {int(g['n'].max())} sizes, {int(g['min_triangles'].min()):,}–"
            f"{int(g['max_triangles'].max()):,} triangles"
            for fam, g in slopes.groupby("family")
        ),
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    for s in Styles(slopes["structure"]).order:
        cells = [s]
        for fam in families:
            for what in TIMES.values():
                f = slopes[(slopes["structure"] == s) & (slopes["family"] == fam) & (slopes["time"] == what)]
                cells.append(f"{f.iloc[0]['slope']:.2f}" if not f.empty else "–")
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Data: " + ", ".join(files), ""]
    return "\n".join(lines)


def write_scaling(results: Results, out: Path) -> list[Path]:
    frame = scaling_frame(results)
    slopes = fit_slopes(frame)
    if slopes.empty:
        raise ValueError("no structure has ok rows at two sizes of one model: nothing to fit")
    fig = scaling_figure(frame, slopes, out / "figures" / "scaling.png")
    table = out / "tables" / "scaling.md"
    table.parent.mkdir(parents=True, exist_ok=True)
    table.write_text(slopes_markdown(slopes, results.files))
    return [fig, table]


# ---- cost images --------------------------------------------------------------------------

COST_METRICS = {"node_visits": "node visits", "prim_tests": "triangle tests"}
CLIP_PERCENTILE = 99.5


def read_cost_csv(path: Path) -> dict[str, np.ndarray]:
    """A PREFIX-cost.csv of `accelbench render --cost-out` as one 2-D array per metric.
    Refuses (naming the file, line and column) a row cut short, a value that is not a
    finite count >= 0, a coordinate that is not an integer, and a pixel missing or twice."""
    path = Path(path)
    if not path.is_file():
        raise ContractError(f"{path}: no such file")
    starts = scan_records(path)
    df = pd.read_csv(path, dtype=str, keep_default_na=False)
    missing = {"x", "y", *COST_METRICS} - set(df.columns)
    if missing:
        raise ContractError(f"{path}: not a cost CSV (missing {', '.join(sorted(missing))})")
    if df.empty:
        raise ContractError(f"{path}: no pixels")
    problems = to_numbers(df, ["x", "y", *COST_METRICS], starts)
    for col in ("x", "y"):
        bad = df[col].isna() | (df[col] != df[col].round())
        if not problems and bad.any():
            problems.append(
                f"column {col!r} has values that are not pixel coordinates on {record_lines(starts, df.index[bad])}"
            )
    if problems:
        raise ContractError(f"{path}: " + "; ".join(problems))
    x, y = df["x"].astype(int).to_numpy(), df["y"].astype(int).to_numpy()
    w, h = int(x.max()) + 1, int(y.max()) + 1
    seen = pd.Series(y * w + x).duplicated()
    if seen.any():
        raise ContractError(
            f"{path}: pixel ({x[seen.idxmax()]}, {y[seen.idxmax()]}) a second time on "
            f"{record_lines(starts, seen.index[seen])}"
        )
    if len(df) != w * h:
        raise ContractError(f"{path}: {len(df)} rows for a {w}x{h} image")
    out = {}
    for m in COST_METRICS:
        img = np.full((h, w), np.nan)
        img[y, x] = df[m].to_numpy(dtype=float)
        out[m] = img
    return out


def cost_figure(model: str, shaded: Path | None, costs: dict[str, Path], path: Path) -> Path:
    """One row per metric (node visits, triangle tests): the shaded image, then one heatmap
    per structure on a scale shared by the row (clipped at the 99.5th percentile of all
    its pixels, so that a few extreme pixels do not wash the rest out), with a colour bar
    and each structure's mean per pixel."""
    data = {label: read_cost_csv(p) for label, p in costs.items()}
    shapes = {d["node_visits"].shape for d in data.values()}
    if len(shapes) != 1:
        raise ValueError(f"cost images of {model} differ in size: {sorted(shapes)}")
    cols = len(data) + (1 if shaded else 0)
    h, w = shapes.pop()
    panel = 3.4
    fig, axes = plt.subplots(
        len(COST_METRICS),
        cols,
        squeeze=False,
        constrained_layout=True,
        figsize=(panel * cols + 0.8, panel * h / w * len(COST_METRICS) + 0.9),
    )
    for r, (metric, name) in enumerate(COST_METRICS.items()):
        row = axes[r]
        c0 = 0
        if shaded:
            row[0].imshow(plt.imread(shaded))
            row[0].set_title(f"{model}\nshaded", fontsize=9)
            c0 = 1
        vmax = (
            float(np.percentile(np.concatenate([d[metric].ravel() for d in data.values()]), CLIP_PERCENTILE))
            or 1.0
        )
        im = None
        for k, (label, d) in enumerate(data.items()):
            ax = row[c0 + k]
            im = ax.imshow(d[metric], cmap="inferno", vmin=0, vmax=vmax, interpolation="nearest")
            ax.set_title(f"{label}\nmean {d[metric].mean():.1f} {name}/pixel", fontsize=9)
        for ax in row:
            ax.set_xticks([])
            ax.set_yticks([])
        bar = fig.colorbar(im, ax=list(row[c0:]), shrink=0.9, pad=0.01, extend="max")
        bar.set_label(f"{name} per pixel\n(primary + shadow ray)", fontsize=8)
    fig.suptitle(
        f"Traversal cost per pixel, {model}: brighter = more work "
        f"(scale shared per row, clipped at the {CLIP_PERCENTILE:g}th percentile)",
        fontsize=10,
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI, metadata={"Software": None})
    plt.close(fig)
    return path
