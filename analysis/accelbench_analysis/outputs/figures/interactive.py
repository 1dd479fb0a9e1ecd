"""The Vega-Lite specifications of the figures where hovering helps (build vs render,
scaling, error vs time, ray sets, thread scaling), written as figures/NAME.vl.json, which
a run's index.html draws; write_figure renders the PNG from the same specification.

Each spec is made by the figure's own writer from its frame, with the frame's rows
inlined as the spec's data, and nothing is computed here beyond display labels. Colours
come from one palette in the structure table's order (mapping/styles.py)."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import vl_convert

from ...mapping.formatting import ci_label
from ...mapping.styles import Styles

SCHEMA = "https://vega.github.io/schema/vega-lite/v6.json"
SPEC_SUFFIX = ".vl.json"
PANEL = {"width": 240, "height": 190}
PNG_SCALE = 1.5  # pixels per Vega-Lite pixel in the PNGs


def spec_path(png: Path) -> Path:
    return png.with_name(png.stem + SPEC_SUFFIX)


def write_spec(png: Path, spec: dict) -> Path:
    """figures/NAME.vl.json beside figures/NAME.png."""
    path = spec_path(png)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(spec, separators=(",", ":"), allow_nan=False))
    return path


def write_figure(png: Path, spec: dict) -> Path:
    """A figure once: its Vega-Lite specification (figures/NAME.vl.json, which the pages
    embed) and figures/NAME.png rendered from it by vl-convert (REPORT.md's), so the two
    cannot differ in data, order, colour or label."""
    write_spec(png, spec)
    png.write_bytes(vl_convert.vegalite_to_png(spec, scale=PNG_SCALE))
    return png


def records(df: pd.DataFrame, columns: list[str]) -> list[dict]:
    """The rows as JSON objects (NaN as null); newlines in labels become spaces."""
    out = df[[c for c in columns if c in df.columns]].copy()
    for c in out.columns:
        if out[c].dtype == object:
            out[c] = out[c].map(lambda v: v.replace("\n", " ") if isinstance(v, str) else v)
    return json.loads(out.to_json(orient="records"))


def colour(field: str, palette: dict[str, str], title: str | None = None) -> dict:
    """The PNG's colours: `palette` maps each value of `field`, in legend order, to its colour."""
    return {
        "field": field,
        "type": "nominal",
        "title": title or field,
        "scale": {"domain": list(palette), "range": list(palette.values())},
    }


def number(field: str, title: str, fmt: str = ".3~g") -> dict:
    return {"field": field, "type": "quantitative", "title": title, "format": fmt}


def legend_pick(field: str) -> tuple[list[dict], dict]:
    """A legend click picks out one value of `field` (the others fade): params, opacity."""
    params = [{"name": "pick", "select": {"type": "point", "fields": [field]}, "bind": "legend"}]
    return params, {"condition": {"param": "pick", "value": 0.9}, "value": 0.12}


def picked_layer(
    mark: dict, x: dict, y: dict, colours: dict, tooltip: list, keep: str | None = None, **more
) -> dict:
    """The layer a legend click picks from: coloured (`colours`: the colour encoding), the
    other values faded, a tooltip on each mark; `keep` filters the data's rows first."""
    params, opacity = legend_pick(colours["field"])
    layer = {
        "params": params,
        "mark": mark,
        "encoding": {"x": x, "y": y, "color": colours, "opacity": opacity, "tooltip": tooltip, **more},
    }
    if keep:
        layer["transform"] = [{"filter": keep}]
    return layer


def log(field: str, title: str) -> dict:
    # The data's own extent, a few pixels inside the frame (a "nice" log domain rounds to
    # whole decades and can leave most of the panel empty).
    return {
        "field": field,
        "type": "quantitative",
        "title": title,
        "scale": {"type": "log", "nice": False, "padding": 10},
    }


def unique(values) -> list:
    return list(dict.fromkeys(v.replace("\n", " ") if isinstance(v, str) else v for v in values))


def build_vs_render_spec(df: pd.DataFrame, title: str) -> dict:
    """structure_frame's rows (figures.build_vs_render): one point per structure and model,
    its CIs as rules, labelled with the coverage they have."""
    x = log("build_s_median", f"build time (s, median, {ci_label(df['ci_coverage'])})")
    y = log("render_s_median", "render time (s)")
    col = colour("structure", Styles(df["structure"]).palette())
    _, opacity = legend_pick("structure")
    tooltip = [
        {"field": "model", "type": "nominal"},
        {"field": "structure", "type": "nominal"},
        {"field": "traversal", "type": "nominal"},
        {"field": "params", "type": "nominal"},
        number("build_s_median", "build (s)"),
        number("build_s_ci_lo", "build CI low"),
        number("build_s_ci_hi", "build CI high"),
        number("render_s_median", "render (s)"),
        number("render_s_ci_lo", "render CI low"),
        number("render_s_ci_hi", "render CI high"),
        number("prim_tests", "primitive tests", ",d"),
        number("node_visits", "node visits", ",d"),
    ]
    return {
        "$schema": SCHEMA,
        "title": title,
        "data": {"values": records(df, [c for c in df.columns if c != "structure_key"])},
        "facet": {"field": "model", "type": "nominal", "sort": unique(df["model"]), "title": None},
        "columns": 3,
        "spec": {
            **PANEL,
            "layer": [
                {
                    "mark": {"type": "rule", "opacity": 0.7},
                    "encoding": {
                        "x": {**x, "field": "build_s_ci_lo"},
                        "x2": {"field": "build_s_ci_hi"},
                        "y": y,
                        "color": col,
                        "opacity": opacity,
                    },
                },
                {
                    "mark": {"type": "rule", "opacity": 0.7},
                    "encoding": {
                        "x": x,
                        "y": {**y, "field": "render_s_ci_lo"},
                        "y2": {"field": "render_s_ci_hi"},
                        "color": col,
                        "opacity": opacity,
                    },
                },
                picked_layer(
                    {"type": "point", "filled": True, "size": 70},
                    x,
                    y,
                    col,
                    tooltip,
                    shape={"field": "traversal", "type": "nominal"},
                ),
            ],
        },
    }


def scaling_spec(points: pd.DataFrame, lines: pd.DataFrame) -> dict:
    """scaling_frame's rows and the fitted lines of the figure (scaling.fit_lines), both
    long over `time` (build, render)."""
    data = pd.concat([points.assign(kind="measured"), lines.assign(kind="fit")], ignore_index=True)
    cols = ["kind", "time", "family", "model", "structure", "triangles", "seconds", "slope"]
    col = colour("structure", Styles(data["structure"]).palette())
    _, opacity = legend_pick("structure")
    x = {**log("triangles", "triangles"), "axis": {"format": "~s"}}
    y = log("seconds", "time, median (s)")
    fit_tip = [
        {"field": "structure", "type": "nominal"},
        {"field": "family", "type": "nominal", "title": "model"},
        number("slope", "fitted slope", ".2f"),
    ]
    point_tip = [
        {"field": "structure", "type": "nominal"},
        {"field": "model", "type": "nominal"},
        number("triangles", "triangles", ",d"),
        number("seconds", "time (s)"),
    ]
    return {
        "$schema": SCHEMA,
        "title": "Build and render time against triangles (log-log; lines: least-squares fits)",
        "data": {"values": records(data, cols)},
        "facet": {"field": "time", "type": "nominal", "sort": ["build", "render"], "title": None},
        "resolve": {"scale": {"y": "independent"}},
        "spec": {
            "width": 380,
            "height": 300,
            "layer": [
                {
                    "transform": [{"filter": "datum.kind == 'fit'"}],
                    "mark": {"type": "line", "strokeWidth": 1.4},
                    "encoding": {
                        "x": x,
                        "y": y,
                        "color": col,
                        "detail": {"field": "family", "type": "nominal"},
                        "opacity": opacity,
                        "tooltip": fit_tip,
                    },
                },
                picked_layer(
                    {"type": "point", "filled": True, "size": 60},
                    x,
                    y,
                    col,
                    point_tip,
                    keep="datum.kind == 'measured'",
                    shape={"field": "family", "type": "nominal", "title": "source model"},
                ),
            ],
        },
    }


def error_pareto_spec(
    points: pd.DataFrame, fronts: pd.DataFrame, wrong: str, title: str, colours: dict[str, str]
) -> dict:
    """error_frame's rows (figures.error_pareto) with `optimal` marking the points nothing
    beats, and each structure's Pareto front as dashed steps; colours per structure (the
    structure table's label and colour, as in every figure)."""
    data = pd.concat([points.assign(kind="row"), fronts.assign(kind="front")], ignore_index=True)
    data = data.rename(columns={wrong: "wrong"})
    cols = [
        "kind",
        "model",
        "structure",
        "accel",
        "params",
        "render_s_median",
        "wrong",
        "false_misses",
        "false_hits",
        "prim_mismatches",
        "nan_results",
        "optimal",
    ]
    col = colour("structure", colours, "structure")
    _, opacity = legend_pick("structure")
    x = log("render_s_median", "render time (s, median)")
    y = {
        "field": "wrong",
        "type": "quantitative",
        "title": "false misses + false hits + wrong primitives",
        "scale": {"type": "symlog", "constant": 1},
    }
    tooltip = [
        {"field": "model", "type": "nominal"},
        {"field": "structure", "type": "nominal"},
        {"field": "accel", "type": "nominal", "title": "accelerator"},
        {"field": "params", "type": "nominal"},
        number("render_s_median", "render (s)"),
        number("wrong", "wrong answers", ",d"),
        number("false_misses", "false misses", ",d"),
        number("false_hits", "false hits", ",d"),
        number("prim_mismatches", "wrong primitives", ",d"),
        number("nan_results", "NaN results", ",d"),
        {"field": "optimal", "type": "nominal", "title": "optimal overall"},
    ]
    return {
        "$schema": SCHEMA,
        "title": title,
        "data": {"values": records(data, cols)},
        "facet": {"field": "model", "type": "nominal", "sort": unique(points["model"]), "title": None},
        "columns": 3,
        "resolve": {"scale": {"x": "independent"}},
        "spec": {
            **PANEL,
            "layer": [
                {
                    "transform": [{"filter": "datum.kind == 'front'"}],
                    "mark": {"type": "line", "interpolate": "step-after", "strokeDash": [4, 3]},
                    "encoding": {"x": x, "y": y, "color": col, "opacity": opacity},
                },
                {
                    "transform": [{"filter": "datum.kind == 'row' && datum.optimal"}],
                    "mark": {"type": "point", "size": 160, "color": "black", "strokeWidth": 1.2},
                    "encoding": {"x": x, "y": y},
                },
                picked_layer(
                    {"type": "point", "filled": True, "size": 45},
                    x,
                    y,
                    col,
                    tooltip,
                    keep="datum.kind == 'row'",
                ),
            ],
        },
    }


def ray_sets_spec(table: pd.DataFrame, sets: list[str], palette: dict[str, str]) -> dict:
    """ray_set_table's rows (tables/ray_sets.md): Mrays/s per set, structure and model."""
    table = table.assign(ray_set=table["ray_set"].astype(str))
    tooltip = [
        {"field": "model", "type": "nominal"},
        {"field": "structure", "type": "nominal"},
        {"field": "ray_set", "type": "nominal", "title": "ray set"},
        number("mrays_per_s", "Mrays/s"),
        number("ratio_to_embree", "ratio to Embree"),
        number("ratio_to_embree_worse_process", "ratio to Embree, worse process"),
        number("embree_mrays_per_s", "Embree Mrays/s"),
        number("rays", "rays", ",d"),
        number("false_misses", "false misses", ",d"),
        number("false_hits", "false hits", ",d"),
    ]
    return {
        "$schema": SCHEMA,
        "title": "Mrays/s per ray set, structure and model",
        "data": {"values": records(table, list(table.columns))},
        # A panel per model and workload (thread count, image): bars of two workloads never share one.
        "facet": {"field": "panel", "type": "nominal", "title": None},
        "columns": 2,
        "resolve": {"scale": {"y": "independent"}},
        "spec": {
            "width": 380,
            "height": 220,
            **picked_layer(
                {"type": "bar"},
                {"field": "ray_set", "type": "nominal", "sort": sets, "title": "ray set"},
                {"field": "mrays_per_s", "type": "quantitative", "title": "Mrays/s"},
                colour("structure", palette),
                tooltip,
                xOffset={"field": "structure", "type": "nominal", "sort": list(palette)},
            ),
        },
    }


def thread_scaling_spec(rows: pd.DataFrame, palette: dict[str, str]) -> dict:
    """workloads.thread_scaling_long's rows: the build's and the render's speedup over one
    thread, a row of panels each."""
    top = float(rows["render_threads"].max())
    x = {
        "field": "render_threads",
        "type": "quantitative",
        "title": "threads",
        "scale": {"zero": False},
        "axis": {"tickMinStep": 1},
    }
    y = {
        "field": "speedup",
        "type": "quantitative",
        "title": "speedup over 1 thread",
        "scale": {"zero": False},
    }
    tooltip = [
        {"field": "structure", "type": "nominal"},
        {"field": "measure", "type": "nominal"},
        {"field": "render_threads", "type": "quantitative", "title": "threads"},
        number("wall_s", "wall (s)"),
        number("speedup", "speedup", ".2f"),
    ]
    return {
        "$schema": SCHEMA,
        "title": "Thread scaling of the build and the render (dashed: ideal)",
        "data": {"values": records(rows, list(rows.columns))},
        "facet": {
            "row": {"field": "measure", "type": "nominal", "title": None, "sort": ["build", "render"]},
            "column": {"field": "model", "type": "nominal", "title": None},
        },
        "spec": {
            **PANEL,
            "layer": [
                {
                    "mark": {"type": "rule", "strokeDash": [4, 3], "color": "grey"},
                    "encoding": {
                        "x": {"datum": 1},
                        "y": {"datum": 1},
                        "x2": {"datum": top},
                        "y2": {"datum": top},
                    },
                },
                picked_layer({"type": "line", "point": True}, x, y, colour("structure", palette), tooltip),
            ],
        },
    }


def peers_spec(table: pd.DataFrame, sets: list[str], palette: dict[str, str]) -> dict:
    """report.peers.peer_table's ok rows: each structure's trace time over Embree's per ray
    set, a panel per model (log scale; the rule at 1 is Embree), the shape saying where the
    structure comes from (ours, Embree, a plugin)."""
    data = table.assign(origin=table["from"].map(lambda f: "plugin" if f.startswith("plugin") else f))
    x = {"field": "ray_set", "type": "nominal", "sort": sets, "title": "ray set", "axis": {"labelAngle": 0}}
    y = {**log("trace_ratio", "trace time / Embree's (log)"), "axis": {"format": ".2~f"}}
    tooltip = [
        {"field": "model", "type": "nominal"},
        {"field": "structure", "type": "nominal"},
        {"field": "from", "type": "nominal"},
        {"field": "ray_set", "type": "nominal", "title": "ray set"},
        number("trace_ratio", "trace / Embree", ".3f"),
        number("rank", "rank in the set", "d"),
        number("build_ratio", "build / Embree", ".3f"),
        number("false_misses", "false misses", ",d"),
        number("false_hits", "false hits", ",d"),
        number("prim_mismatches", "wrong primitives", ",d"),
    ]
    return {
        "$schema": SCHEMA,
        "title": "Trace time against Embree per ray set: ours, Embree and the plugins' structures",
        "data": {"values": records(data, list(data.columns))},
        "facet": {"field": "panel", "type": "nominal", "sort": unique(table["panel"]), "title": None},
        "columns": 3,
        "spec": {
            **PANEL,
            "layer": [
                {
                    "mark": {"type": "rule", "strokeDash": [4, 3], "color": "grey"},
                    "encoding": {"y": {"datum": 1}},
                },
                picked_layer(
                    {"type": "line", "point": {"filled": True, "size": 50}},
                    x,
                    y,
                    colour("structure", palette),
                    tooltip,
                    # Ours and Embree solid, the plugins' structures dashed.
                    strokeDash={
                        "field": "origin",
                        "type": "nominal",
                        "title": "from",
                        "scale": {"domain": ["ours", "Embree", "plugin"], "range": [[1, 0], [1, 0], [5, 3]]},
                    },
                ),
            ],
        },
    }
