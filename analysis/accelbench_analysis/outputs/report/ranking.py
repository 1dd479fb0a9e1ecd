"""The answer a run gives first: per scene and ray set, each structure's trace and build
time as a ratio to Embree's in the same run, ranked.

Ratios, never seconds: a ratio to the baseline measured beside it on the same machine and
rays is what carries from one machine to another. A ratio's interval divides the two
medians' 95% intervals end by end (the row's low end by Embree's high end, and the other
way round), so it is wider than either, never narrower. Rows are the CSV's own `label`
(the registry's name for a structure and the parameters that make it one); a structure
measured at several other settings in the run is shown at the setting measured on the most
scenes and ray sets, and tables/ranking.md lists every setting."""

from __future__ import annotations

import math
from dataclasses import dataclass

import pandas as pd

from ...inputs.schema import RENDER_SETTING_COLUMNS, Results, parse_params
from ...mapping.formatting import fmt_sig, md_table, note_item

BASELINE = "embree"
RANKING_DOC = "tables/ranking.md"


@dataclass
class Ratio:
    value: float
    lo: float
    hi: float

    def text(self) -> str:
        if not self.value == self.value:
            return "—"
        if self.lo == self.lo and self.hi == self.hi:
            return f"{fmt_sig(self.value, 3)} [{fmt_sig(self.lo, 3)}–{fmt_sig(self.hi, 3)}]"
        return fmt_sig(self.value, 3)


def _ratio(row: pd.Series, base: pd.Series | None, measure: str) -> Ratio:
    if base is None:
        return Ratio(math.nan, math.nan, math.nan)
    m, b = row[f"{measure}_median"], base[f"{measure}_median"]
    if not (m > 0 and b > 0):
        return Ratio(math.nan, math.nan, math.nan)
    lo_r, hi_r = row[f"{measure}_ci_lo"], row[f"{measure}_ci_hi"]
    lo_b, hi_b = base[f"{measure}_ci_lo"], base[f"{measure}_ci_hi"]
    lo = lo_r / hi_b if lo_r > 0 and hi_b > 0 else math.nan
    hi = hi_r / lo_b if hi_r > 0 and lo_b > 0 else math.nan
    return Ratio(m / b, lo, hi)


def _workload(row: pd.Series) -> str:
    """The column a row's ratio goes in: its scene and ray set (and threads, when not 1)."""
    text = f"{row['model']} · {row.get('ray_set', '') or 'camera'}"
    threads = row.get("render_threads", math.nan)
    if threads == threads and float(threads) != 1:
        text += f" · {float(threads):g} threads"
    return text


def _structure(row: pd.Series) -> str:
    return row.get("label", "") or row["accel"]


def ratios(results: Results) -> pd.DataFrame:
    """One row per measured row of the run (catalogue cases aside): its workload, structure,
    parameters, status and both ratios to the Embree row of the same scene, rays and render
    settings (the first by parameters when there are several, as regress does)."""
    df = results.measured_rows().copy()
    if df.empty:
        return pd.DataFrame()
    settings = ["model", "ray_set", *RENDER_SETTING_COLUMNS]
    ok = df[df["status"] == "ok"]
    base: dict[tuple, pd.Series] = {}
    for _, e in ok[ok["accel"] == BASELINE].sort_values("params").iterrows():
        base.setdefault(tuple(str(e.get(c, "")) for c in settings), e)
    out = []
    for _, r in df.iterrows():
        e = base.get(tuple(str(r.get(c, "")) for c in settings)) if r["status"] == "ok" else None
        out.append(
            {
                "workload": _workload(r),
                "model": r["model"],
                "structure": _structure(r),
                "accel": r["accel"],
                "params": r["params"],
                "status": r["status"],
                "trace": _ratio(r, e, "render_s"),
                "build": _ratio(r, e, "build_s"),
                "has_baseline": e is not None,
            }
        )
    return pd.DataFrame(out)


def _shown_setting(r: pd.DataFrame) -> pd.DataFrame:
    """Per structure and workload, one row: of the structure's settings measured there, the
    one measured on the most workloads in the run (ties: the first parameters text), so a
    structure keeps one setting wherever it can."""
    reach = r.groupby(["structure", "params"])["workload"].nunique().rename("reach").reset_index()
    ordered = r.merge(reach, on=["structure", "params"]).sort_values(
        ["structure", "workload", "reach", "params"], ascending=[True, True, False, True]
    )
    return ordered.drop_duplicates(["structure", "workload"]).drop(columns="reach")


def _geomean(values: list[float]) -> float:
    v = [x for x in values if x == x and x > 0]
    return math.exp(sum(math.log(x) for x in v) / len(v)) if v else math.nan


def ranking_table(r: pd.DataFrame) -> tuple[list[str], list[list[str]], list[str]]:
    """The first table: structures ranked by the geometric mean of their trace ratios, one
    trace column per workload and one build column per scene. Returns header, rows and
    notes (settings not shown, rows without a ratio)."""
    shown = _shown_setting(r)
    workloads = list(dict.fromkeys(r["workload"]))
    models = list(dict.fromkeys(r["model"]))
    rows = []
    for structure, g in shown.groupby("structure", sort=False):
        trace = {w: x["trace"].iloc[0] for w, x in g.groupby("workload")}
        build = {m: x["build"].iloc[0] for m, x in g.groupby("model")}
        score = _geomean([t.value for t in trace.values()])
        status = {w: x["status"].iloc[0] for w, x in g.groupby("workload")}
        cells = [
            trace[w].text() if w in trace and status[w] == "ok" else status.get(w, "not measured")
            for w in workloads
        ]
        cells += [build[m].text() if m in build else "not measured" for m in models]
        rows.append((score, structure, cells))
    rows.sort(key=lambda x: (not x[0] == x[0], x[0], x[1]))
    header = [
        "structure",
        "rank",
        *[f"trace: {w}" for w in workloads],
        *[f"build: {m}" for m in models],
    ]
    table = [[name, str(i + 1) if s == s else "—", *cells] for i, (s, name, cells) in enumerate(rows)]
    notes = []
    settings = r.groupby("structure", sort=False)["params"].nunique()
    several = settings[settings > 1]
    if not several.empty:
        notes.append(
            "Measured at several settings: "
            + ", ".join(f"{name} {n}" for name, n in several.items())
            + "; each cell shows, of those measured there, the one measured most widely (every "
            f"setting: {RANKING_DOC}, under More of this run)."
        )
    if not r["has_baseline"].any():
        notes.append(
            "No Embree row in this run: no ratio can be formed (add `embree` to the config's accelerators)."
        )
    return header, table, notes


def ranking_markdown(results: Results) -> list[str]:
    """The section REPORT.md opens with."""
    r = ratios(results)
    if r.empty:
        return ["## Ranking against Embree", "", "This run measured no structure on a scene."]
    header, table, notes = ranking_table(r)
    return [
        "## Ranking against Embree",
        "",
        "Each structure's trace time (per scene and ray set: `trace: SCENE · RAYS`) and build "
        "time (per scene: `build: SCENE`) divided by Embree's in this run, with the 95% interval "
        "of the ratio; below 1 is faster than Embree. Ranked by the geometric mean of the trace "
        "ratios.",
        "",
        *md_table(header, table, align="lr"),
        "",
        *[note_item(n) for n in notes],
    ]


def full_ranking_markdown(results: Results) -> str:
    """tables/ranking.md: every setting of every structure, per workload, ranked."""
    r = ratios(results)
    out = ["# Every structure and setting against Embree", ""]
    if r.empty:
        return "\n".join(out + ["This run measured no structure on a scene.", ""])
    for workload, g in r.groupby("workload", sort=False):
        g = g.assign(key=[t.value for t in g["trace"]]).sort_values(["key", "structure"], na_position="last")
        out += [f"## {workload}", ""]
        rows = [
            [
                x["structure"],
                ", ".join(f"{k}={v}" for k, v in parse_params(x["params"]).items()),
                x["trace"].text() if x["status"] == "ok" else x["status"],
                x["build"].text() if x["status"] == "ok" else "",
            ]
            for _, x in g.iterrows()
        ]
        out += md_table(["structure", "parameters", "trace ×Embree", "build ×Embree"], rows, align="ll") + [
            ""
        ]
    return "\n".join(out)
