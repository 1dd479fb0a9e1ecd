"""Three ways: the report's number, this run's and the committed reference run's, per cell.

A user who runs `make reproduce-tables` on their machine wants to know at a glance whether
it reproduces ours (results/reference/, measured by the project on a known commit and
machine) and the report. For every cell of the report's Tables 2, 4 and 5 (model,
structure, setting; plus our extra structures, which have no report number), and each of
build time, render time, primitive tests and nodes: the three values and the ratios
this/report and this/reference. Counts are deterministic: this/reference = 1 says the same
trees and the same traversal work; a time ratio says how this machine compares with ours
(the report's machine and implementation were much slower, so this/report of a time
compares machines, not structures).

Cells are looked up exactly as the tables and claims look them up (claims.OurSource), in
this run's CSVs and in the reference run's CSVs of the same names.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from ...inputs.report_numbers import REPORT_MODEL, TABLE2_MODEL, TABLE4_MODELS, TABLE5_MODELS, report_value
from ...inputs.schema import Results
from ...mapping.formatting import fmt_count, fmt_sig, is_missing, md_table
from ...mapping.metrics import METRIC, ratio
from ...mapping.selection import Structure
from .claims import Missing, OurSource

TIME_METRICS = ["build", "render"]
COUNT_METRICS = ["prim_tests", "nodes"]
HEADER = ["model", "structure", "report", "this run", "reference run", "this/report", "this/reference"]


@dataclass
class ThreeWay:
    metric: str
    model: str  # the report's model label (our stand-in named where it is one)
    structure: str
    report: float | None
    this: float | None
    reference: float | None

    @property
    def this_over_report(self) -> float | None:
        return ratio(self.this, self.report)

    @property
    def this_over_reference(self) -> float | None:
        return ratio(self.this, self.reference)


def _cells(report_nums: pd.DataFrame, structures: list[Structure]) -> list[tuple[str, str, str, str]]:
    """(report model, structure key, setting, label) of every cell compared, table order."""
    out = [
        (TABLE2_MODEL, "kdtree", s, f"kd-tree {s}")
        for s in report_nums.loc[report_nums["table"] == 2, "setting"]
    ]
    for rm in TABLE4_MODELS + TABLE5_MODELS:
        out += [(rm, s.key, "default", s.label) for s in structures]
    return out


def _structures(*sources: OurSource | None) -> list[Structure]:
    """STRUCTURES, then every other structure either run measured, in order of appearance."""
    out: dict[str, Structure] = {}
    for src in sources:
        for s in src.picker.structures() if src is not None else []:
            out.setdefault(s.key, s)
    return list(out.values())


def _ours(src: OurSource | None, rm: str, structure: str, metric: str, setting: str) -> float | None:
    if src is None:
        return None
    try:
        return src.get(rm, structure, metric, setting)
    except Missing:
        return None


def three_way(this: Results, reference: Results | None, report_nums: pd.DataFrame) -> list[ThreeWay]:
    """Every cell where this run or the reference run has a number."""
    here = OurSource(this, report_nums)
    there = OurSource(reference, report_nums) if reference is not None else None
    structures = _structures(here, there)
    out = []
    for metric in TIME_METRICS + COUNT_METRICS:
        for rm, skey, setting, label in _cells(report_nums, structures):
            ours_model = here.model(rm)
            model = REPORT_MODEL[rm].label + (f" → {ours_model}" if REPORT_MODEL[rm].stand_in else "")
            s = next(s for s in structures if s.key == skey)
            rep = (
                report_value(report_nums, rm, s.report_accel, setting, METRIC[metric].report)
                if s.report_accel
                else None
            )
            row = ThreeWay(
                metric,
                model,
                label,
                rep,
                _ours(here, rm, skey, metric, setting),
                _ours(there, rm, skey, metric, setting),
            )
            if row.this is not None or row.reference is not None:
                out.append(row)
    return out


def _fmt(metric: str, v) -> str:
    if is_missing(v):
        return "—"
    return fmt_sig(v) if metric in TIME_METRICS else fmt_count(v)


def metric_table(rows: list[ThreeWay], metric: str) -> list[str]:
    body = [
        [
            r.model,
            r.structure,
            _fmt(metric, r.report),
            _fmt(metric, r.this),
            _fmt(metric, r.reference),
            fmt_sig(r.this_over_report),
            fmt_sig(r.this_over_reference),
        ]
        for r in rows
        if r.metric == metric
    ]
    return md_table(HEADER, body, align="ll") if body else []


def reference_text(reference: Results | None, reference_dir: Path | None) -> str:
    if reference is None:
        where = f" ({reference_dir}/csv has none of this run's CSVs)" if reference_dir else ""
        return f"No committed reference run to compare with{where}: its column is empty."
    g = reference.groups
    desc = "; ".join(
        f"commit {x.fields['git_sha'][:12]}"
        + (" (dirty)" if x.fields["git_dirty"] == "true" else "")
        + f" on {x.fields['cpu']}"
        for x in g
    )
    return (
        f"The reference run: `{reference_dir}` ({desc}; {', '.join(Path(f).name for f in reference.files)})."
    )


def comparison_markdown(
    rows: list[ThreeWay],
    this: Results,
    reference: Results | None,
    reference_dir: Path | None,
    metrics: list[str] | None = None,
) -> list[str]:
    """The three-way tables, one per metric (all four unless `metrics` says)."""
    out = [reference_text(reference, reference_dir), ""]
    labels = {
        "build": "Build time (s, median)",
        "render": "Render time (s, median)",
        "prim_tests": METRIC["prim_tests"].label,
        "nodes": METRIC["nodes"].label,
    }
    for m in metrics or TIME_METRICS + COUNT_METRICS:
        table = metric_table(rows, m)
        if table:
            out += [f"### {labels[m]}", ""] + table + [""]
    if not rows:
        out += ["No cell of the report's tables was measured in this run.", ""]
    return out


def write_comparison(
    rows: list[ThreeWay], this: Results, reference: Results | None, reference_dir: Path | None, out_dir: Path
) -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "comparison.md"
    text = [
        "# This run, the report and the committed reference run",
        "",
        "Per cell of the report's Tables 2, 4 and 5: the report's number, this run's, the "
        "committed reference run's, and the ratios this/report and this/reference. Counts "
        "are deterministic (this/reference 1 = the same trees and work); times compare "
        "machines (the report's was much slower, so read its ratio for orderings, not "
        "size).",
        "",
    ]
    path.write_text("\n".join(text + comparison_markdown(rows, this, reference, reference_dir)))
    return path
