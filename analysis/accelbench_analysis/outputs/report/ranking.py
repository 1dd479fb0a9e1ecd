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

    def cell(self, col: Column) -> str:
        source = self.build if col.build else self.trace
        got = [source[k] for k in col.keys if k in source and source[k].ok()]
        if not got:
            return NO_RATIO
        partial = len(col.keys) > 1 and len(got) < len(col.keys)
        return geomean(got).text() + (f" ({len(got)}/{len(col.keys)})" if partial else "")


def _series(rows: pd.DataFrame, name: str, trace: str = "trace", build: str = "build") -> Series:
    """A row of a table from the shown rows of one name: build from each model's first workload."""
    by_model: dict[str, Ratio] = {}
    for _, x in rows.iterrows():
        by_model.setdefault(x["model"], x[build])
    return Series(name, {w: x[trace] for w, x in zip(rows["workload"], rows.to_dict("records"))}, by_model)


def columns(r: pd.DataFrame) -> tuple[list[Column], bool]:
    """The tables' columns over the workloads with a ratio: per scene and ray set (and one
    build column per scene) when they are few, else one per ray set and one build column.
    Returns the columns and whether they are per scene."""
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
    trace = [Column(f"{g} ({_scenes(len(ws))})", tuple(ws)) for g, ws in groups.items()]
    return trace + [Column(f"build ({_scenes(len(models))})", tuple(models), build=True)], False


def _scenes(n: int) -> str:
    return f"{n} scene" + ("s" if n != 1 else "")


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


def apart_series(r: pd.DataFrame) -> list[tuple[Series, str]]:
    """The ablations and baseline variants: per setting one row against its own structure
    (ablations only) and one against Embree; with what the setting changes."""
    rows = shown(r[r["kind"].isin([ABLATION, BASELINE_VARIANT])]).sort_values(
        ["kind", "structure"], kind="stable"
    )
    out = []
    for name, g in rows.groupby("structure", sort=False):
        first = g.iloc[0]
        changes = f"{name}: {first['changes'] or 'no parameter'}"
        if first["kind"] == ABLATION:
            changes += f" (its structure: {first['of']})"
            out.append((_series(g, f"{name} ÷ {first['of']}", "own_trace", "own_build"), changes))
        out.append((_series(g, f"{name} ÷ Embree"), changes))
    return out


def ranking_table(r: pd.DataFrame) -> tuple[list[str], list[list[str]], list[str], str]:
    """The first table: header, rows (structure, rank, a cell per column), notes and the
    sentence saying what it ranks by."""
    cols, per_scene = columns(r)
    scored, common, total = ranked_series(r)
    rows = [
        [s.name, str(i + 1) if v == v else NO_RATIO, *[s.cell(c) for c in cols]]
        for i, (v, s) in enumerate(scored)
    ]
    basis = (
        f"the {common} scene and ray set pairs on which every structure has a ratio"
        + (f" (of {total} with a ratio)" if common < total else "")
        if common
        else "each one's own scene and ray set pairs (no pair has a ratio of every structure)"
    )
    notes = [_legend(rows, per_scene, cols)]
    notes += _settings_note(r)
    notes += _left_out_notes(r)
    return ["structure", "rank", *[c.title for c in cols]], rows, notes, basis


def _legend(rows: list[list[str]], per_scene: bool, cols: list[Column]) -> str:
    text = f"{NO_RATIO}: no ratio (not measured there beside an Embree row)"
    if not per_scene:
        text += (
            "; a cell is the geometric mean of the structure's ratios on the column's scenes, its "
            f"interval the mean of their interval ends (every scene: {RANKING_DOC})"
        )
        if any("/" in c and c.endswith(")") for row in rows for c in row[2:]):
            text += "; (k/n): over the k of the column's n scenes it has a ratio on"
    return text + "."


def _settings_note(r: pd.DataFrame) -> list[str]:
    """The structures measured at several settings, and which one a cell shows."""
    rated = r[(r["kind"] == STRUCTURE) & (r["status"] == "ok") & r["has_baseline"]]
    settings = rated.groupby("structure", sort=False)["params"].nunique()
    several = settings[settings > 1]
    if several.empty:
        return []
    counts = ", ".join(f"{name} {n}" for name, n in several.items())
    return [
        f"Measured at several settings ({counts}): each ratio is of the setting with a ratio on "
        f"the most scenes and ray sets, of those measured on that one (every setting: {RANKING_DOC})."
    ]


def _left_out_notes(r: pd.DataFrame) -> list[str]:
    """What has no ratio and why: scenes without an Embree row, rows that did not finish."""
    notes = []
    if not r["has_baseline"].any():
        return [
            "No Embree row in this run: no ratio can be formed (add `embree` to the config's accelerators)."
        ]
    rated = set(r.loc[r["has_baseline"], "workload"])
    lacking = [w for w in dict.fromkeys(r["workload"]) if w not in rated]
    if lacking:
        notes.append(
            f"No Embree row on {', '.join(lacking)}: no ratio there ({RANKING_DOC} lists their rows)."
        )
    beside = r[(r["status"] == "ok") & ~r["has_baseline"] & r["workload"].isin(rated)]
    if len(beside):
        configs = ", ".join(f"{c}: {n}" for c, n in beside["config"].value_counts(sort=False).items())
        notes.append(
            f"{len(beside)} rows at render settings no Embree row was measured at ({configs}) have "
            f"no ratio ({RANKING_DOC} lists them)."
        )
    skipped = int((r["status"] == "skipped").sum())
    failed = r[~r["status"].isin(["ok", "skipped"])]
    if len(failed):
        named = ", ".join(
            f"{x['structure']} on {x['workload']}: {x['status']}" for _, x in failed.head(6).iterrows()
        )
        more = f" and {len(failed) - 6} more" if len(failed) > 6 else ""
        notes.append(f"Did not finish: {named}{more} ({RANKING_DOC} has their messages).")
    if skipped:
        notes.append(
            f"{skipped} row{'s' if skipped != 1 else ''} skipped by their configs (each says why in its `message`) are not measurements."
        )
    return notes


def _coverage(r: pd.DataFrame) -> str:
    return ci_label(r.loc[r["status"] == "ok", "ci_coverage"]) if "ci_coverage" in r else "CI"


def ranking_markdown(results: Results) -> list[str]:
    """The section REPORT.md opens with: the ranking, then the ablations and variants."""
    r = ratios(results)
    if r.empty:
        return ["## Ranking against Embree", "", "This run measured no structure on a scene."]
    header, table, notes, basis = ranking_table(r)
    per_scene = header[2].startswith("trace: ")
    what = (
        "per scene and ray set (`trace: SCENE · RAYS`) and its build time per scene (`build: SCENE`)"
        if per_scene
        else "per ray set, as the geometric mean over the scenes, and its build time over the scenes"
    )
    out = [
        "## Ranking against Embree",
        "",
        f"Each structure's trace time {what}, divided by Embree's beside it in this run, with the "
        f"ratio's interval ({_coverage(r)} of each median, divided end by end); below 1 is faster than "
        f"Embree. Ranked by the geometric mean of the trace ratios over {basis}.",
        "",
        *md_table(header, table, align="lr"),
        "",
        *[note_item(n) for n in notes],
    ]
    return out + apart_markdown(r)


def apart_markdown(r: pd.DataFrame) -> list[str]:
    """The ablations and baseline variants beside the ranking; nothing when the run has none."""
    series = apart_series(r)
    if not series:
        return []
    cols, _ = columns(r[r["kind"].isin([ABLATION, BASELINE_VARIANT])])
    rows = [[s.name, *[s.cell(c) for c in cols]] for s, _ in series]
    changes = list(dict.fromkeys(c for _, c in series))
    return [
        "",
        "### Ablations and baseline variants: what the guarantees cost",
        "",
        "Not ranked: settings that are not structures of their own. An ablation is a structure at a "
        "setting its label marks as not the structure (a test without the guarantee of its default), "
        "shown against its structure beside it and against Embree; a baseline variant is Embree at "
        "another of its settings than the one every ratio divides by. Ratios and means as above.",
        "",
        *md_table(["setting ÷ what", *[c.title for c in cols]], rows, align="l"),
        "",
        note_item(
            "What each changes: " + "; ".join(changes) + " (`accelbench list` describes every parameter)."
        ),
    ]


def scene_tables(r: pd.DataFrame) -> list[str]:
    """tables/ranking.md's first part: per ray set, the ranked structures (then the ablations
    and variants) with one column per scene; then the build times per scene."""
    scored, _, _ = ranked_series(r)
    series = [s for _, s in scored] + [s for s, _ in apart_series(r)]
    rated = r[(r["status"] == "ok") & r["has_baseline"]]
    out = []
    for group, g in rated.groupby("group", sort=False):
        cols = [Column(m, (w,)) for m, w in dict.fromkeys(zip(g["model"], g["workload"]))]
        rows = [[s.name, *[s.cell(c) for c in cols]] for s in series]
        rows = [row for row in rows if any(c != NO_RATIO for c in row[1:])]
        out += [f"## {group}: trace time ÷ Embree's, per scene", ""]
        out += md_table(["structure", *[c.title for c in cols]], rows)
        out.append("")
    cols = [Column(m, (m,), build=True) for m in dict.fromkeys(rated["model"])]
    out += ["## Build time ÷ Embree's, per scene", ""]
    out += md_table(
        ["structure", *[c.title for c in cols]], [[s.name, *[s.cell(c) for c in cols]] for s in series]
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
        out += md_table(header, rows, align="lll") + [""]
    return "\n".join(out)


def _why_none(x: pd.Series) -> str:
    if x["status"] != "ok":
        return f"{x['status']}: {x['message']}" if x["message"] else x["status"]
    return "" if x["has_baseline"] else "no Embree row at its render settings"
