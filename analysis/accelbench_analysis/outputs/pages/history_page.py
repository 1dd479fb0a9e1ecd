"""results/history/index.html: history.csv drawn per structure and model.

One figure shows the panel picked in its menu or in the table below it: render ("trace")
and build time as ratios to Embree's across commits in commit order, one line per
combination (parameters, ray set, image size), and the deterministic counts as steps, a
change from the previous commit marked. The latest regression check's verdict heads the
page and links to its history: the verdicts collected so far and the panels of the
combinations it measures. Every value is history.csv's."""

from __future__ import annotations

import html
import os
from pathlib import Path

import pandas as pd

from ..ci.history import COUNTS, Collected
from ..figures.interactive import SCHEMA, records
from .markdown_html import to_html
from .page import data_table, page, vega_figure, write_page

INDEX = "index.html"
PANEL_SEP = " · "
RATIO_TITLES = {
    "trace_ratio_to_embree": "Render time / Embree's (same model, same rays, same run)",
    "build_ratio_to_embree": "Build time / Embree's (same model, same run)",
}


def panel_of(df: pd.DataFrame) -> pd.Series:
    return df["model"] + PANEL_SEP + df["structure"]


def commit_axis() -> dict:
    return {
        "field": "commit",
        "type": "ordinal",
        "sort": {"field": "commit_order", "op": "min"},
        "title": "commit (in commit order)",
        "axis": {"labelAngle": -40},
    }


def tooltip(value_title: str) -> list[dict]:
    return [
        {"field": "commit", "type": "nominal"},
        {"field": "subject", "type": "nominal", "title": "commit subject"},
        {"field": "commit_date", "type": "nominal", "title": "committed"},
        {"field": "series", "type": "nominal", "title": "combination"},
        {"field": "value", "type": "quantitative", "title": value_title, "format": ",.4~g"},
        {"field": "n", "type": "quantitative", "title": "measurements (median)"},
        {"field": "min", "type": "quantitative", "format": ",.4~g"},
        {"field": "max", "type": "quantitative", "format": ",.4~g"},
        {"field": "configs", "type": "nominal"},
        {"field": "runs", "type": "nominal"},
    ]


def series_colour() -> dict:
    return {
        "field": "series",
        "type": "nominal",
        "title": "combination",
        "legend": {"orient": "bottom", "columns": 1, "symbolLimit": 16, "labelLimit": 520},
    }


def ratio_chart(measure: str) -> dict:
    return {
        "title": RATIO_TITLES[measure],
        "width": 760,
        "height": 200,
        "transform": [{"filter": f"datum.measure === '{measure}'"}],
        "mark": {"type": "line", "point": True},
        "encoding": {
            "x": commit_axis(),
            "y": {
                "field": "value",
                "type": "quantitative",
                "title": "ratio to Embree",
                "scale": {"zero": False},
            },
            "color": series_colour(),
            "tooltip": tooltip("ratio"),
        },
    }


def counts_chart() -> dict:
    x = commit_axis()
    y = {
        "field": "value",
        "type": "quantitative",
        "title": None,
        "scale": {"zero": False},
        "axis": {"labelExpr": "format(datum.value, '~s')"},
    }
    count_tip = tooltip("count") + [
        {"field": "step", "type": "nominal", "title": "changed from the previous commit"}
    ]
    return {
        "title": {
            "text": "Counts: steps, never trends (a marked point changed from the previous commit)",
            "anchor": "start",
        },
        "transform": [{"filter": {"field": "measure", "oneOf": COUNTS}}],
        "facet": {
            "row": {
                "field": "measure",
                "type": "nominal",
                "sort": COUNTS,
                "title": None,
                "header": {"labelAngle": 0, "labelAlign": "left", "labelOrient": "right"},
            }
        },
        "resolve": {"scale": {"y": "independent"}},
        "spec": {
            "width": 760,
            "height": 90,
            "layer": [
                {
                    "mark": {"type": "line", "interpolate": "step-after"},
                    "encoding": {"x": x, "y": y, "color": series_colour()},
                },
                {
                    "mark": {"type": "point", "filled": True, "size": 30},
                    "encoding": {"x": x, "y": y, "color": series_colour(), "tooltip": count_tip},
                },
                {
                    "transform": [{"filter": "datum.step"}],
                    "mark": {
                        "type": "point",
                        "shape": "triangle-up",
                        "size": 150,
                        "color": "#c0181b",
                        "filled": True,
                    },
                    "encoding": {"x": x, "y": y, "tooltip": count_tip},
                },
            ],
        },
    }


def history_spec(hist: pd.DataFrame, panels: list[str]) -> dict:
    """One view, its panel picked by the `panel` parameter (the menu, or page.js from the
    table). What repeats over a combination's measures (its panel, series, configs, runs)
    and a commit's rows (its order, date, subject) is inlined once and looked up, which
    keeps the page a fraction of history.csv's size; min and max only where n > 1."""
    commits = hist.drop_duplicates("commit")[["commit", "commit_order", "commit_date", "subject"]]
    rows = hist.assign(panel=panel_of(hist))
    combo = ["panel", "series", "commit", "configs", "runs"]
    combos = rows[combo].drop_duplicates().reset_index(drop=True)
    combos["c"] = combos.index
    rows = rows.merge(combos, on=combo)
    several = rows["n"] > 1
    rows["min"], rows["max"] = rows["min"].where(several), rows["max"].where(several)
    rows["step"] = rows["step"].where(rows["step"])
    values = [
        {k: v for k, v in r.items() if v is not None}
        for r in records(rows, ["c", "measure", "value", "n", "min", "max", "step"])
    ]
    return {
        "$schema": SCHEMA,
        "params": [
            {
                "name": "panel",
                "value": panels[0],
                "bind": {"input": "select", "options": panels, "name": "model · structure: "},
            }
        ],
        "data": {"values": values},
        "transform": [
            {
                "lookup": "c",
                "from": {"data": {"values": records(combos, list(combos))}, "key": "c", "fields": combo},
            },
            {"filter": "datum.panel === panel"},
            {
                "lookup": "commit",
                "from": {
                    "data": {"values": records(commits, list(commits))},
                    "key": "commit",
                    "fields": ["commit_order", "commit_date", "subject"],
                },
            },
        ],
        "vconcat": [
            ratio_chart("trace_ratio_to_embree"),
            ratio_chart("build_ratio_to_embree"),
            counts_chart(),
        ],
        "resolve": {"scale": {"color": "shared"}},
    }


def panel_link(panel: str, text: str | None = None) -> str:
    return f'<a href="#panel-figures" data-panel="{html.escape(panel)}">{html.escape(text or panel)}</a>'


def overview_table(hist: pd.DataFrame) -> str:
    """One row per structure and model: its combinations, commits, latest commit, steps."""
    rows = []
    for panel, g in hist.assign(panel=panel_of(hist)).groupby("panel", sort=True):
        steps = g[g["step"]]
        last = g.loc[g["commit_order"].idxmax(), "commit"]
        rows.append(
            "<tr>"
            f"<td>{panel_link(panel, g['model'].iloc[0])}</td><td>{html.escape(g['structure'].iloc[0])}</td>"
            f'<td class="num">{g["series"].nunique()}</td><td class="num">{g["commit"].nunique()}</td>'
            f"<td>{html.escape(last)}</td>"
            f'<td class="num">{len(steps)}</td>'
            f"<td>{html.escape(', '.join(sorted(set(steps['measure'] + ' at ' + steps['commit']))))}</td>"
            "</tr>"
        )
    return data_table(
        ["model", "structure", "combinations", "commits", "last commit", "count steps", "where"], rows
    )


def verdict_class(verdict: str) -> str:
    return {"PASS": "pass", "FAIL": "fail"}.get(verdict, "other")


def regress_section(c: Collected, out: Path) -> list[str]:
    parts = ['<h2 id="regress">The regression check</h2>']
    if c.latest is None:
        return parts + ["<p>No regression check on this machine yet (<code>make regress</code>).</p>"]
    rel = os.path.relpath(c.latest.report.resolve(), out.resolve())
    ci = c.history[c.history["runs"].str.contains("runs/regress", regex=False)]
    panels = sorted(set(panel_of(ci))) if not ci.empty else []
    parts.append(
        f'<p>Latest: <span class="verdict {verdict_class(c.latest.verdict)}">{html.escape(c.latest.verdict)}</span> '
        f"for commit {html.escape(c.latest.commit)}, measured {html.escape(c.latest.measured)} "
        f'(<a href="{html.escape(rel)}">its report</a>).</p>'
    )
    if panels:
        parts.append(
            "<p>Its combinations across commits: " + ", ".join(panel_link(p) for p in panels) + ".</p>"
        )
    rows = [
        f"<tr><td>{html.escape(r.commit)}</td><td>{html.escape(r.measured)}</td>"
        f'<td><span class="verdict {verdict_class(r.verdict)}">{html.escape(r.verdict)}</span></td>'
        f"<td>{html.escape(r.report)}</td></tr>"
        for r in c.verdicts.iloc[::-1].itertuples()
    ]
    parts.append("<h3>Verdicts collected so far, newest first</h3>")
    parts.append(data_table(["commit", "measured", "verdict", "report"], rows))
    parts.append(
        '<details class="included"><summary>The latest report</summary>'
        + to_html(c.latest.text, shift=2, prefix="regress-")
        + "</details>"
    )
    return parts


def sources_table(c: Collected, out: Path, results: Path) -> str:
    rows = []
    g = c.rows.groupby(["kind", "run"], as_index=False).agg(
        commits=("git_sha", lambda v: ", ".join(sorted({s[:7] for s in v}))),
        rows=("file", "size"),
        first=("timestamp", "min"),
        last=("timestamp", "max"),
    )
    for r in g.sort_values("last", ascending=False).itertuples():
        page_path = results / r.run / INDEX
        name = html.escape(r.run)
        if page_path.is_file():
            name = f'<a href="{html.escape(os.path.relpath(page_path, out))}">{name}</a>'
        elif not (results / r.run).exists():
            name += ' <span class="muted">(gone; kept in collected.csv)</span>'
        rows.append(
            f"<tr><td>{html.escape(r.kind)}</td><td>{name}</td><td>{html.escape(r.commits)}</td>"
            f'<td class="num">{r.rows}</td><td>{html.escape(r.first)}</td><td>{html.escape(r.last)}</td></tr>'
        )
    return data_table(["kind", "run", "commits", "rows", "first measured", "last measured"], rows)


def history_page_html(c: Collected, out: Path, results: Path) -> str:
    hist = c.history
    body = ["<h1>accelbench: every measurement on this machine across commits</h1>"]
    if c.latest is not None:
        body.append(
            f'<p>Latest regression check: <a href="#regress"><span class="verdict '
            f'{verdict_class(c.latest.verdict)}">{html.escape(c.latest.verdict)}</span></a> '
            f'(commit {html.escape(c.latest.commit)}); <a href="#regress">its history</a>.</p>'
        )
    n_commits = hist["commit"].nunique() if not hist.empty else 0
    body.append(
        f"<p>{len(c.rows):,} measured rows from {c.rows['run'].nunique() if not c.rows.empty else 0} runs, "
        f'{n_commits} commits; {len(hist):,} rows in <a href="history.csv">history.csv</a> (one per commit, '
        "combination and measure: the median over that commit's runs). Ratios and times are trends; counts "
        "are exact, so a change is a step at one commit.</p>"
    )
    body += [f"<blockquote>{html.escape(n)}</blockquote>" for n in c.notes]
    nav = [
        ("panel-figures", "Across commits"),
        ("panels", "Structures and models"),
        ("regress", "Regression check"),
        ("sources", "Runs collected"),
    ]
    charts = False
    if hist.empty:
        body.append(
            "<p>No run on this machine yet: <code>make reproduce-tables</code>, <code>make regress</code>.</p>"
        )
    else:
        ratios = hist[hist["measure"].isin(["trace_ratio_to_embree", "build_ratio_to_embree"] + COUNTS)]
        panels = sorted(set(panel_of(ratios)))
        body += [
            '<h2 id="panel-figures">Across commits</h2>',
            "<p>Pick a structure and model in the menu, or in the table below the figure. Hover a "
            "point for its commit, combination (parameters, ray set, image size) and value.</p>",
            vega_figure(history_spec(ratios, panels), "history.csv"),
        ]
        body += ['<h2 id="panels">Structures and models</h2>', overview_table(ratios)]
        charts = True
    body += regress_section(c, out)
    body += (
        ['<h2 id="sources">Runs collected</h2>', sources_table(c, out, results)] if not c.rows.empty else []
    )
    return page(
        "accelbench history",
        "\n".join(body),
        nav=nav,
        charts=charts,
        note=f'Written by <code>make history</code>; <a href="{html.escape(os.path.relpath(results / INDEX, out))}">'
        "all runs</a>.",
    )


def write_history_page(c: Collected, out: Path, results: Path) -> Path:
    return write_page(out / INDEX, history_page_html(c, out, results))
