"""Each claim's verdict at our defaults and at the faithful setting, its class where it does
not hold, its spread and its cause, all read off the factor matrix (claim_matrix.py); and
the one summary every output shows (claims.md, claims.csv, REPORT.md, index.html).

A verdict is `within noise` when its margin lies inside the spread measured on the
combinations it read (mapping/spread.py); `by construction` when the claim cannot fail for
any implementation of the report's description. A claim that does not hold gets a class:
`report-numbers` (the report's own numbers do not support it either), `stand-in` (decided
on models that stand in for the report's), `implementation` (our structures differ; the
matrix names the factor that flips it, or none).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import pandas as pd

from ...inputs.report_numbers import REPORT_MODEL, TABLE4_MODELS
from ...inputs.schema import Results
from ...mapping.formatting import fmt_sig, md_escape
from ...mapping.settings import DEFAULT, FAITHFUL, SETTINGS
from ...mapping.spread import Spread
from .claim_checks import short
from .claim_matrix import (
    BY_CONSTRUCTION,
    MATRIX_LEGEND,
    WITHIN_NOISE,
    Matrix,
    cause_text,
    matrix_markdown,
    within_noise,
)
from .claims import FAILS, HOLDS, NOT_COMPARABLE, Claim, Finding, Missing

VERDICTS = (HOLDS, FAILS, WITHIN_NOISE, BY_CONSTRUCTION, NOT_COMPARABLE)
CLASSES = ("implementation", "report-numbers", "stand-in")
# Claims comparing the kd-tree with the BVH across model sizes: the metric whose kd/BVH
# ratio shows whether a larger model of ours would cross where the report's does.
SIZE_TRENDS = {"5.2-h": "nodes", "5.2-i": "prim_tests"}


@dataclass
class Judgement:
    """One claim at one setting."""

    verdict: str
    evidence: str
    cls: str = ""
    reason: str = ""
    spread: Spread = field(default_factory=lambda: Spread(0.0, ""))


@dataclass
class ClaimVerdicts:
    claim: Claim
    report: Finding
    at: dict[str, Judgement]
    cause: str

    def csv_row(self) -> dict[str, str]:
        d, f = self.at[DEFAULT], self.at[FAITHFUL]
        return {
            "claim": self.claim.id,
            "text": self.claim.text,
            "report_value": self.report.evidence,
            "our_value": d.evidence,
            "verdict": d.verdict,
            "class": d.cls,
            "reason": d.reason,
            "spread": f"{d.spread.value:.3f}",
            "faithful_value": f.evidence,
            "faithful_verdict": f.verdict,
            "faithful_class": f.cls,
            "faithful_reason": f.reason,
            "faithful_spread": f"{f.spread.value:.3f}",
            "cause": self.cause,
        }


CSV_COLUMNS = tuple(
    "claim text report_value our_value verdict class reason spread faithful_value faithful_verdict "
    "faithful_class faithful_reason faithful_spread cause".split()
)


def size_crossing(src, metric: str) -> tuple[bool, str]:
    """Whether any Table 4 model of ours has the kd-tree below the BVH in `metric` (the
    crossing the report's large models show), and the ratios by model size."""
    parts, below = [], False
    sized = []
    for m in TABLE4_MODELS:
        try:
            sized.append((src.primitives(m), m, src.get(m, "kdtree", metric) / src.get(m, "bvh", metric)))
        except (Missing, ZeroDivisionError):
            continue
    for n, m, r in sorted(sized):
        below |= r < 1
        parts.append(f"{short(m)} ({fmt_sig(n)} triangles) {fmt_sig(r)}")
    return below, ", ".join(parts)


def failing_class(c: Claim, report: Finding, matrix: Matrix, setting: str) -> tuple[str, str]:
    """The class of a claim that does not hold at `setting`, and why."""
    cell = matrix.cells[c.id][setting]
    if report.verdict == FAILS:
        return "report-numbers", f"the report's own numbers do not support it either: {report.evidence}"
    src = matrix.sources[setting]
    if c.id in SIZE_TRENDS:
        crosses, trend = size_crossing(src, SIZE_TRENDS[c.id])
        if not crosses:
            return "implementation", (
                f"kd-tree/BVH {SIZE_TRENDS[c.id]} stays ≥ 1 on every model of ours, real and stand-in: "
                f"{trend}; no size of ours crosses"
            )
    used = cell.models_read & set(c.decisive) if c.decisive else cell.models_read
    subs = sorted(m for m in used if m in REPORT_MODEL and REPORT_MODEL[m].stand_in)
    if subs and len(subs) == len(used):
        return "stand-in", "decided on stand-in models (" + ", ".join(
            f"{short(m)} → {src.model(m)}" for m in subs
        ) + ")"
    return "implementation", cause_text(matrix, c.id)


def judge(
    c: Claim, report: Finding, matrix: Matrix, results: Results, setting: str, run: Results | None = None
) -> Judgement:
    cell = matrix.cells[c.id][setting]
    ev = cell.finding.evidence
    if cell.verdict == NOT_COMPARABLE:
        return Judgement(NOT_COMPARABLE, ev)
    inside, spread = within_noise(matrix, results, c, setting, run)
    if inside:
        return Judgement(
            WITHIN_NOISE, ev, "", f"{cell.verdict} by a margin inside the measured spread {spread}", spread
        )
    if cell.verdict == HOLDS:
        if c.by_construction:
            return Judgement(BY_CONSTRUCTION, ev, "", f"cannot fail: {c.by_construction}", spread)
        note = (
            f"the report's own numbers do not support it: {report.evidence}"
            if report.verdict == FAILS
            else ""
        )
        return Judgement(HOLDS, ev, "report-numbers" if note else "", note, spread)
    cls, why = failing_class(c, report, matrix, setting)
    variant = next((s for s in SETTINGS if s.by_construction), None)
    if variant and matrix.verdict(c.id, variant.name) == HOLDS:
        why += f"; holds at {variant.name}, which cannot fail ({variant.by_construction}): not a reproduction"
    return Judgement(FAILS, ev, cls, why, spread)


def judge_all(
    claims: list[Claim],
    reports: dict[str, Finding],
    matrix: Matrix,
    results: Results,
    run: Results | None = None,
) -> list[ClaimVerdicts]:
    """Every claim at default and faithful; `run`, every row of the run, gives the spread's
    floor (claim_spread)."""
    return [
        ClaimVerdicts(
            c,
            reports[c.id],
            {s: judge(c, reports[c.id], matrix, results, s, run) for s in (DEFAULT, FAITHFUL)},
            cause_text(matrix, c.id),
        )
        for c in claims
    ]


def counts(rows: list[ClaimVerdicts], setting: str) -> dict[str, int]:
    """The summary's counts at one setting: every verdict, and the classes of those that do
    not hold (they add up to the number of claims)."""
    out = {v: sum(r.at[setting].verdict == v for r in rows) for v in VERDICTS}
    for k in CLASSES:
        out[f"{FAILS}: {k}"] = sum(r.at[setting].verdict == FAILS and r.at[setting].cls == k for r in rows)
    return out


SUMMARY_ROWS = (
    (HOLDS, HOLDS),
    (f"{FAILS}: implementation", "does not hold: our implementation"),
    (f"{FAILS}: report-numbers", "does not hold: not in the report's own numbers either"),
    (f"{FAILS}: stand-in", "does not hold: decided on stand-in models"),
    (WITHIN_NOISE, "within noise (margin inside the measured spread)"),
    (BY_CONSTRUCTION, "by construction (cannot fail)"),
    (NOT_COMPARABLE, "not comparable"),
)


def summary_markdown(rows: list[ClaimVerdicts]) -> list[str]:
    """The one summary: the counts at default and faithful (each column adds up to the
    number of claims), then the factor matrix. REPORT.md, claims.md and the page show
    exactly these lines; claims.csv has the per-claim verdicts they count."""
    d, f = counts(rows, DEFAULT), counts(rows, FAITHFUL)
    out = [
        f"{len(rows)} claims, each judged at our defaults and at the faithful setting "
        "(configs/faithful.yaml: every reading of the report at once).",
        "",
        "| verdict | default | faithful |",
        "|:---|---:|---:|",
    ]
    out += [f"| {label} | {d[key]} | {f[key]} |" for key, label in SUMMARY_ROWS]
    out += [f"| **claims** | **{len(rows)}** | **{len(rows)}** |", ""]
    return out


def claims_table(rows: list[ClaimVerdicts]) -> list[str]:
    head = "| # | claim | report's data | default | faithful | class (faithful) | spread | cause | reason (faithful) |"
    out = [head, "|:---|:---|:---|:---|:---|:---|---:|:---|:---|"]
    for r in rows:
        d, f = r.at[DEFAULT], r.at[FAITHFUL]
        out.append(
            f"| {r.claim.id} | {md_escape(r.claim.text)} | {r.report.verdict}: {md_escape(r.report.evidence)} | "
            f"{d.verdict} | **{f.verdict}**: {md_escape(f.evidence)} | {f.cls} | {f.spread.value:.0%} | "
            f"{md_escape(r.cause)} | {md_escape(f.reason)} |"
        )
    return out


def summary_with_matrix(rows: list[ClaimVerdicts], matrix: Matrix) -> list[str]:
    return summary_markdown(rows) + [f"The matrix ({MATRIX_LEGEND}):", ""] + matrix_markdown(matrix)


def verdicts_frame(rows: list[ClaimVerdicts]) -> pd.DataFrame:
    return pd.DataFrame([r.csv_row() for r in rows], columns=list(CSV_COLUMNS))


TABLE2_METRICS = (
    ("nodes", "#nodes"),
    ("prim_tests", "#int. tests"),
    ("build", "build (s)"),
    ("render", "render (s)"),
)


def table2_side_by_side(report_src, matrix: Matrix) -> list[str]:
    """The report's Table 2 beside ours at the faithful setting, row by row (kd-tree on the
    bunny; ours at N = 35,947 with every reading of the report)."""
    from .cost_model import SWEEPS

    ours = matrix.sources[FAITHFUL]
    head = "| setting | " + " | ".join(f"{label} report | ours" for _, label in TABLE2_METRICS) + " |"
    out = [head, "|:---|" + "---:|---:|" * len(TABLE2_METRICS)]
    for setting in sum(SWEEPS.values(), ()):
        cells = []
        for metric, _ in TABLE2_METRICS:
            for src in (report_src, ours):
                try:
                    cells.append(fmt_sig(src.get("stanford-bunny", "kdtree", metric, setting)))
                except Missing:
                    cells.append("—")
        out.append(f"| {setting} | " + " | ".join(cells) + " |")
    return out
