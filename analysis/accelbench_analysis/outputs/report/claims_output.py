"""The claims' files: tables/claims.md, claims.csv, claims_factors.csv, the heat map, and
the cost model's; and the claims' part of REPORT.md. Every one shows the same summary
(claim_verdicts.summary_markdown) made from the same verdicts."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from ...inputs.schema import Results
from ...mapping.formatting import md_escape
from ...mapping.settings import DEFAULT, FAITHFUL, SETTING
from .claim_matrix import (
    Cell,
    Matrix,
    evaluate_matrix,
    flipping_factors,
    mark_noise,
    setting_source,
    write_matrix,
)
from .claim_verdicts import (
    ClaimVerdicts,
    claims_table,
    judge_all,
    summary_with_matrix,
    table2_side_by_side,
    verdicts_frame,
)
from .claims import CLAIMS, FAILS, HOLDS, Missing, ReportSource, evaluate, tolerance_text
from .cost_model import cost_model_lines, fit_all, pooled_residuals, write_cost_model


@dataclass
class ClaimsResult:
    """What the claims wrote and found, for REPORT.md."""

    rows: list[ClaimVerdicts]
    matrix: Matrix
    reference: dict[str, Cell] | None = None  # the reference run's default cells, noise judged

    def machine_dependent(self) -> list[str]:
        """The claims that hold at default in one run and not in the other, each verdict
        outside its own run's measured noise."""
        if self.reference is None:
            return []
        return [
            r.claim.id
            for r in self.rows
            if {r.at[DEFAULT].verdict, self.reference[r.claim.id].shown} == {HOLDS, FAILS}
        ]


def plain_statements(result: ClaimsResult) -> list[str]:
    """What a reader must know before any verdict: the default renders are unshaded, and
    which claims hold only with the report's hit-list traversal."""
    traversal = [
        r.claim.id for r in result.rows if "traversal=ordered" in flipping_factors(result.matrix, r.claim.id)
    ]
    shading = [
        r.claim.id for r in result.rows if "shading off" in flipping_factors(result.matrix, r.claim.id)
    ]
    return [
        "Our default renders are unshaded (tracing timed alone); the faithful setting renders with "
        "Phong shading and a shadow ray per hit, as the report did. "
        + (f"Claims whose faithful verdict flips with shading off: {', '.join(shading)}. " if shading else "")
        + (
            "Claims whose faithful verdict needs the report's hit-list traversal (its Algorithm 1; "
            f"ordered traversal flips them): {', '.join(traversal)}."
            if traversal
            else "No claim's faithful verdict depends on the hit-list traversal."
        ),
        "",
    ]


def claims_markdown(result: ClaimsResult, results: Results, report_src: ReportSource) -> str:
    out = ["# The report's claims, checked", ""]
    out += [f"> **Warning:** {md_escape(w)}\n" for w in results.warnings]
    out += plain_statements(result) + summary_with_matrix(result.rows, result.matrix) + [""]
    out += [
        "Settings: "
        + "; ".join(
            f"**{s.name}**: {s.factor or 'every reading of the report'}"
            + (f" ({s.evidence})" if s.evidence else "")
            for s in SETTING.values()
        )
        + ". The faithful setting's readings and their evidence: configs/faithful.yaml, docs/decisions.md.",
        "",
        tolerance_text(),
        "",
    ]
    unsupported = [r.claim.id for r in result.rows if r.report.verdict == FAILS]
    out += [f"The report's own numbers do not support: {', '.join(unsupported) or 'none'}.", ""]
    dependent = result.machine_dependent()
    if result.reference is not None:
        out += [
            "Machine-dependent (holds at default on one run, not on the committed reference run, "
            "each outside its run's noise): " + (", ".join(dependent) if dependent else "none") + ".",
            "",
        ]
    out += ["## Every claim", ""] + claims_table(result.rows)
    out += ["", "## Table 2 at the faithful setting, beside the report's", ""]
    out += table2_side_by_side(report_src, result.matrix)
    return "\n".join(out) + "\n"


def write_cost_model_files(results: Results, report_nums: pd.DataFrame, out_dir: Path) -> None:
    """tables/cost_model.csv and cost_model.md: each of Table 2's sweeps fitted on its own,
    the report's and ours at the faithful setting (shading on: our floor is measured)."""
    report_fits = fit_all(ReportSource(report_nums), Missing)
    our_fits = fit_all(setting_source(results, report_nums, SETTING[FAITHFUL]), Missing)
    if not report_fits:
        return
    write_cost_model(report_fits, our_fits, out_dir)
    pooled = pooled_residuals(ReportSource(report_nums), Missing)
    text = ["# A cost model of render time", ""] + cost_model_lines(report_fits, our_fits, pooled)
    (out_dir / "cost_model.md").write_text("\n".join(text) + "\n")


def write_claims(
    results: Results,
    report_nums: pd.DataFrame,
    out_dir: Path,
    reference: Results | None = None,
    run: Results | None = None,
    reference_run: Results | None = None,
) -> tuple[Path, ClaimsResult]:
    """tables/claims.md, claims.csv, claims_factors.csv (+ figures/claims_factors.png beside
    the tables directory) and the cost model's files. `run`: every row of the run, whose
    widest gap is the floor of every claim's spread (default: `results`); `reference_run`
    the same for the reference run's verdicts (default: `reference`)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    report_src = ReportSource(report_nums)
    matrix = evaluate_matrix(results, report_nums)
    mark_noise(matrix, results, run)
    reports = {c.id: evaluate(c, report_src) for c in CLAIMS}
    rows = judge_all(CLAIMS, reports, matrix, results, run)
    ref = None
    if reference is not None:  # its default verdicts, judged for noise on its own run
        ref_matrix = evaluate_matrix(reference, report_nums, settings=(SETTING[DEFAULT],))
        mark_noise(ref_matrix, reference, reference_run)
        ref = {c.id: ref_matrix.cells[c.id][DEFAULT] for c in CLAIMS}
    result = ClaimsResult(rows, matrix, ref)
    write_matrix(matrix, out_dir, out_dir.parent / "figures")
    verdicts_frame(rows).to_csv(out_dir / "claims.csv", index=False)
    write_cost_model_files(results, report_nums, out_dir)
    path = out_dir / "claims.md"
    path.write_text(claims_markdown(result, results, report_src))
    return path, result
