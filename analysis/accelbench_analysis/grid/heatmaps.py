"""The grid search's heatmaps: the objective over each pair of varied parameters (minimum
over the others), with the report's and pbrt's published default settings marked, one PNG
per model and pair."""

from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..inputs.schema import normalise_value
from ..mapping.formatting import fmt_sig
from ..mapping.selection import kd_auto_depth_pbrt, kd_auto_depth_report
from .grid_config import FINAL, PARAM_COL, PASS_COL

if TYPE_CHECKING:
    from .grid import GridAnalysis

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


def number_or_none(text: str) -> float | None:
    try:
        f = float(text)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def axis_order(texts) -> list[str]:
    """Distinct values, numerically sorted when all are numbers, else in order of appearance."""
    values = list(dict.fromkeys(texts))
    if all(number_or_none(v) is not None for v in values):
        return sorted(values, key=number_or_none)
    return values


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
    v, nums = number_or_none(text), [number_or_none(x) for x in axis_values]
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

    from ..outputs.figures.figures import save_figure, setup

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
