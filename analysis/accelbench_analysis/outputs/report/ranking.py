"""The answer a run gives first: each structure's trace and build time as a ratio to
Embree's in the same run, ranked (ranking_rows.py makes the ratios and says what each row
is).

The ranking holds the structures only: the table's declared variants and the baseline at
the setting every ratio divides by. Ablations and baseline variants follow it in a table of
their own ("what the guarantees cost"), each against its own structure and against Embree,
never ranked among the structures. A run of few scenes and ray sets shows one column per
scene and ray set; a wider one one column per ray set, the geometric mean over its scenes,
and tables/ranking.md has every scene and every setting. A structure measured at several
settings shows on each scene the setting it has a ratio on most widely."""

from __future__ import annotations

import re
from dataclasses import dataclass

import pandas as pd

from ...inputs.schema import Results, parse_params
from ...mapping.formatting import ci_label, md_table, note_item
from .ranking_rows import (
    ABLATION,
    BASELINE_VARIANT,
    NO_RATIO,
    STRUCTURE,
    Ratio,
    geomean,
    ratios,
    shown,
)

RANKING_DOC = "tables/ranking.md"
APART_TITLE = "Ablations and baseline variants: what the guarantees cost"
# Up to this many trace and build columns, one per scene and ray set; beyond, one per ray set.
SCENE_COLUMNS = 8


@dataclass(frozen=True)
class Column:
    title: str
    keys: tuple[str, ...]  # the workloads whose ratios it means (the models, for build)
    build: bool = False


@dataclass
class Series:
    """One table row: a name and its ratios by workload (trace) and by model (build)."""

    name: str
    trace: dict[str, Ratio]
    build: dict[str, Ratio]

    def cell(self, col: Column, short: bool = True) -> str:
        """The geometric mean of its ratios in the column (± form when short, else the
        interval's ends), "(k/n)" when it has a ratio on only k of the column's n keys."""
        source = self.build if col.build else self.trace
        got = [source[k] for k in col.keys if k in source and source[k].ok()]
        if not got:
            return NO_RATIO
        mean = geomean(got)
        partial = len(col.keys) > 1 and len(got) < len(col.keys)
        return (mean.short() if short else mean.text()) + (
            f" ({len(got)}/{len(col.keys)})" if partial else ""
        )


def _series(rows: pd.DataFrame, name: str, trace: str = "trace", build: str = "build") -> Series:
    """A row of a table from the shown rows of one name: build from each model's first workload."""
    by_model: dict[str, Ratio] = {}
    for x in rows.to_dict("records"):
        by_model.setdefault(x["model"], x[build])
    return Series(name, {x["workload"]: x[trace] for x in rows.to_dict("records")}, by_model)


def columns(r: pd.DataFrame) -> tuple[list[Column], bool]:
    """The tables' columns over the workloads with a ratio: per scene and ray set (and one
    build column per scene) when they are few, else one per ray set and one build column,
    each titled with its number of scenes. Returns the columns and whether per scene."""
    rated = r[(r["status"] == "ok") & r["has_baseline"]]
    workloads = list(dict.fromkeys(rated["workload"]))
    models = list(dict.fromkeys(rated["model"]))
    if len(workloads) + len(models) <= SCENE_COLUMNS:
        trace = [Column(f"trace: {w}", (w,)) for w in workloads]
        return trace + [Column(f"build: {m}", (m,), build=True) for m in models], True
    groups: dict[str, list[str]] = {}
    for w, g in zip(rated["workload"], rated["group"]):
        if w not in groups.setdefault(g, []):
            groups[g].append(w)
    trace = [Column(f"{g} ({len(ws)})", tuple(ws)) for g, ws in groups.items()]
    return trace + [Column(f"build ({len(models)})", tuple(models), build=True)], False


def ranked_series(r: pd.DataFrame) -> tuple[list[tuple[float, Series]], int, int]:
    """The structures (kind "structure"), ranked by the geometric mean of their trace ratios
    over the workloads every one of them has a ratio on (each over its own where they share
    none). Returns (score, series) best first, the number of those workloads and of all."""
    main = shown(r[r["kind"] == STRUCTURE])
    series = [_series(g, name) for name, g in main.groupby("structure", sort=False)]
    keys = [{w for w, t in s.trace.items() if t.ok()} for s in series]
    common = set.intersection(*keys) if keys else set()
    everything = set().union(*keys) if keys else set()
    scored = []
    for s, mine in zip(series, keys):
        score = geomean([s.trace[w] for w in (common or mine)]).value
        scored.append((score, s))
    scored.sort(key=lambda x: (not x[0] == x[0], x[0], x[1].name))
    return scored, len(common), len(everything)


def apart_series(r: pd.DataFrame) -> tuple[list[Series], list[str]]:
    """The ablations and baseline variants: per setting one row against its own structure
    (ablations only) and one against Embree; and what each ablation changes."""
    rows = shown(r[r["kind"].isin([ABLATION, BASELINE_VARIANT])]).sort_values(
        ["kind", "structure"], kind="stable"
    )
    series, changes = [], []
    for name, g in rows.groupby("structure", sort=False):
        first = g.iloc[0]
        if first["kind"] == ABLATION:
            changes.append(first["changes"] or f"{name}: no parameter")
            series.append(_series(g, f"{name} ÷ {first['of']}", "own_trace", "own_build"))
        series.append(_series(g, f"{name} ÷ Embree"))
    return series, changes


def ranking_table(r: pd.DataFrame) -> tuple[list[str], list[list[str]], list[str], str]:
    """The first table: header, rows (structure, rank, a cell per column), notes and the
    sentence saying what it ranks by."""
    cols, _ = columns(r)
    scored, common, total = ranked_series(r)
    rows = [
        [s.name, str(i + 1) if v == v else NO_RATIO, *[s.cell(c) for c in cols]]
        for i, (v, s) in enumerate(scored)
    ]
    basis = (
        f"the {common} scene and ray set pairs every structure has a ratio on"
        + (f" (of {total})" if common < total else "")
        if common
        else "each one's own scene and ray set pairs (no pair has a ratio of every structure)"
    )
    notes = _legend(rows) + _settings_note(r) + _left_out_notes(r)
    return ["structure", "rank", *[c.title for c in cols]], rows, notes, basis


def _legend(rows: list[list[str]]) -> list[str]:
    """The marks a table's cells use, said only when some cell uses them."""
    cells = [c for row in rows for c in row[2:]]
    marks = []
    if NO_RATIO in cells:
        marks.append(f"{NO_RATIO}: no ratio (not measured there beside an Embree row)")
    if any(re.search(r"\(\d+/\d+\)$", c) for c in cells):
        marks.append("(k/n): the mean over the k of the column's n scenes it has a ratio on")
    return ["; ".join(marks) + "."] if marks else []


def _settings_note(r: pd.DataFrame) -> list[str]:
    """The structures measured at several settings, and which one a cell shows."""
    rated = r[(r["kind"] == STRUCTURE) & (r["status"] == "ok") & r["has_baseline"]]
    settings = rated.groupby("structure", sort=False)["params"].nunique()
    several = settings[settings > 1]
    if several.empty:
        return []
    counts = ", ".join(f"{name} {n}" for name, n in several.items())
    return [
        f"Several settings ({counts}): on each scene and ray set, the ratio is of the setting with a "
        f"ratio on the most of them (all: {RANKING_DOC})."
    ]


def _left_out_notes(r: pd.DataFrame) -> list[str]:
    """What has no ratio and why, in one note: scenes without an Embree row, rows at render
    settings Embree was not measured at, rows skipped by their configs; and those that did
    not finish, named (a failure is a finding)."""
    if not r["has_baseline"].any():
        return [
            "No Embree row in this run: no ratio can be formed (add `embree` to the config's accelerators)."
        ]
    rated = set(r.loc[r["has_baseline"], "workload"])
    parts = []
    lacking = r[~r["workload"].isin(rated)].drop_duplicates("workload")
    if len(lacking):
        where = "; ".join(
            f"{group} rays of {', '.join(g['model'])}" for group, g in lacking.groupby("group", sort=False)
        )
        parts.append(f"no Embree row on {where}")
    beside = r[(r["status"] == "ok") & ~r["has_baseline"] & r["workload"].isin(rated)]
    if len(beside):
        configs = ", ".join(f"{c}: {n}" for c, n in beside["config"].value_counts(sort=False).items())
        parts.append(f"{_n(len(beside), 'row')} at render settings without an Embree row ({configs})")
    skipped = int((r["status"] == "skipped").sum())
    if skipped:
        parts.append(f"{_n(skipped, 'row')} skipped by their configs")
    notes = [f"No ratio: {'; '.join(parts)} (all in {RANKING_DOC})."] if parts else []
    failed = r[~r["status"].isin(["ok", "skipped"])]
    if len(failed):
        named = ", ".join(
            f"{x['structure']} on {x['workload']}: {x['status']}" for _, x in failed.head(6).iterrows()
        )
        more = f" and {len(failed) - 6} more" if len(failed) > 6 else ""
        notes.append(f"Did not finish: {named}{more} ({RANKING_DOC} has their messages).")
    return notes


def _n(count: int, what: str) -> str:
    return f"{count} {what}" + ("s" if count != 1 else "")


def _coverage(r: pd.DataFrame) -> str:
    return ci_label(r.loc[r["status"] == "ok", "ci_coverage"]) if "ci_coverage" in r else "CI"


def ranking_markdown(results: Results) -> list[str]:
    """The section REPORT.md opens with: the ranking, then the ablations and variants."""
    r = ratios(results)
    if r.empty:
        return ["## Ranking against Embree", "", "This run measured no structure on a scene."]
    header, table, notes, basis = ranking_table(r)
    what = (
        "per scene and ray set (`trace: SCENE · RAYS`) and per scene (`build: SCENE`)"
        if any(h.startswith(("trace: ", "build: ")) for h in header[2:])
        else "per ray set, the geometric mean over the column's (n) scenes"
    )
    out = [
        "## Ranking against Embree",
        "",
        f"Trace and build time {what}, as ratios to Embree's in this run (below 1: faster); ±: the "
        f"larger side of the ratio's interval ({_coverage(r)} medians divided end by end). Ranked by "
        f"the mean trace ratio over {basis}.",
        "",
        *md_table(header, table, align="lr"),
        "",
        *[note_item(n) for n in notes],
    ]
    return out + apart_markdown(r)


def apart_markdown(r: pd.DataFrame) -> list[str]:
    """The ablations and baseline variants beside the ranking; nothing when the run has none."""
    series, changes = apart_series(r)
    if not series:
        return []
    cols, _ = columns(r[r["kind"].isin([ABLATION, BASELINE_VARIANT])])
    rows = [[s.name, *[s.cell(c) for c in cols]] for s in series]
    said = f" (here {', '.join(changes)})" if changes else ""
    return [
        "",
        f"**{APART_TITLE}.** Not ranked: each ablation{said} against its structure beside it and "
        "against Embree; each baseline variant (Embree at another setting) against Embree.",
        "",
        *md_table(["setting ÷ what", *[c.title for c in cols]], rows, align="l"),
    ]


def scene_tables(r: pd.DataFrame) -> list[str]:
    """tables/ranking.md's first part: per ray set, the ranked structures (then the ablations
    and variants) with one column per scene; then the build times per scene."""
    scored, _, _ = ranked_series(r)
    series = [s for _, s in scored] + apart_series(r)[0]
    rated = r[(r["status"] == "ok") & r["has_baseline"]]
    out = []
    for group, g in rated.groupby("group", sort=False):
        cols = [Column(m, (w,)) for m, w in dict.fromkeys(zip(g["model"], g["workload"]))]
        rows = [[s.name, *[s.cell(c, short=False) for c in cols]] for s in series]
        rows = [row for row in rows if any(c != NO_RATIO for c in row[1:])]
        out += [f"## {group}: trace time ÷ Embree's, per scene", ""]
        out += md_table(["structure", *[c.title for c in cols]], rows)
        out.append("")
    cols = [Column(m, (m,), build=True) for m in dict.fromkeys(rated["model"])]
    out += ["## Build time ÷ Embree's, per scene", ""]
    out += md_table(
        ["structure", *[c.title for c in cols]],
        [[s.name, *[s.cell(c, short=False) for c in cols]] for s in series],
    )
    return out + [""]


def full_ranking_markdown(results: Results) -> str:
    """tables/ranking.md: every scene, then every setting of every structure per scene and
    ray set, ranked."""
    r = ratios(results)
    out = ["# Every structure and setting against Embree", ""]
    if r.empty:
        return "\n".join(out + ["This run measured no structure on a scene.", ""])
    out += [
        f"Ratios to Embree's row beside each ({_coverage(r)} intervals divided end by end); "
        f"{NO_RATIO}: no ratio. Ablations and baseline variants are named with what they are divided by.",
        "",
    ]
    out += scene_tables(r)
    out += ["## Every setting", ""]
    for workload, g in r.groupby("workload", sort=False):
        g = g.assign(key=[t.value for t in g["trace"]]).sort_values(["key", "structure"], na_position="last")
        out += [f"### {workload}", ""]
        rows = [
            [
                x["structure"],
                x["kind"],
                ", ".join(f"{k}={v}" for k, v in parse_params(x["params"]).items()),
                x["trace"].text(),
                x["build"].text(),
                _why_none(x),
            ]
            for _, x in g.iterrows()
        ]
        header = ["structure", "kind", "parameters", "trace ÷ Embree", "build ÷ Embree", "no ratio because"]
        out += md_table(header, rows, align="lllrrl") + [""]
    return "\n".join(out)


def _why_none(x: pd.Series) -> str:
    if x["status"] != "ok":
        return f"{x['status']}: {x['message']}" if x["message"] else x["status"]
    return "" if x["has_baseline"] else "no Embree row at its render settings"
