"""Classes and the one summary on crafted CSVs: the report's own numbers, a size trend that
never crosses, and counts that add up and agree with claims.csv."""

from __future__ import annotations

from synthetic import BVH, KD, LBVH, row, write_csv

from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.outputs.report.claim_matrix import evaluate_matrix
from accelbench_analysis.outputs.report.claim_verdicts import (
    FAILS,
    HOLDS,
    SUMMARY_ROWS,
    counts,
    judge_all,
    summary_markdown,
    verdicts_frame,
)
from accelbench_analysis.outputs.report.claims import CLAIMS, ReportSource, evaluate

CLAIM = {c.id: c for c in CLAIMS}


def judged(tmp_path, report_nums, rows, ids):
    res = load_results([write_csv(tmp_path / "t.csv", rows)])
    claims = [CLAIM[i] for i in ids]
    m = evaluate_matrix(res, report_nums, claims)
    reports = {c.id: evaluate(c, ReportSource(report_nums)) for c in claims}
    return {r.claim.id: r for r in judge_all(claims, reports, m, res)}


def test_report_numbers_when_the_reports_own_table_does_not_support_it(tmp_path, report_nums):
    # 5.1-b: maxPrims 1 -> 100 cuts #nodes ~418x; the report's own table gives 286x.
    rows = [
        row("stanford-bunny", "kdtree", dict(KD, max_prims=mp), nodes=n, config="table2")
        for mp, n in (("1", 600_000), ("10", 80_000), ("100", 4_000))
    ]
    b = judged(tmp_path, report_nums, rows, ["5.1-b"])["5.1-b"].at["default"]
    assert (b.verdict, b.cls) == (FAILS, "report-numbers")
    assert "286x" in b.reason


def test_a_size_trend_that_never_crosses_is_not_decided_by_stand_ins(tmp_path, report_nums):
    # 5.2-h: kd-tree fewer nodes than the BVH on the large models. Ours has more on every
    # model, the report's own bunny and Igea included: no larger stand-in would cross.
    rows = []
    for m, n in (
        ("stanford-bunny", 69_451),
        ("igea", 268_686),
        ("happy-buddha-100k", 100_000),
        ("stanford-dragon", 871_414),
    ):
        rows += [
            row(m, "bvh", BVH, nodes=2 * n - 1),
            row(m, "lbvh", LBVH, nodes=2 * n - 1),
            row(m, "kdtree", KD, nodes=5 * n),
        ]
    h = judged(tmp_path, report_nums, rows, ["5.2-h"])["5.2-h"].at["default"]
    assert (h.verdict, h.cls) == (FAILS, "implementation")
    assert "no size of ours crosses" in h.reason
    # One model of ours where the kd-tree has fewer nodes: the crossing is there, and the
    # large model (the dragon, a stand-in) decides the claim.
    rows[-4] = row("happy-buddha-100k", "kdtree", KD, nodes=100_000)
    h = judged(tmp_path, report_nums, rows, ["5.2-h"])["5.2-h"].at["default"]
    assert (h.verdict, h.cls) == (FAILS, "stand-in")


def test_the_summary_counts_add_up_and_agree_with_claims_csv(tmp_path, report_nums):
    rows = []
    for m, f in (("stanford-bunny", 1.0), ("igea", 4.0), ("stanford-dragon", 12), ("happy-buddha-100k", 2)):
        rows += [
            row(m, "bvh", BVH, build=0.1 * f, render=1.0 * f, nodes=1000, prim_tests=500),
            row(m, "lbvh", LBVH, build=0.2 * f, render=1.05 * f, nodes=1000, prim_tests=520),
            row(m, "kdtree", KD, build=0.9 * f, render=0.8 * f, nodes=5000, prim_tests=300),
        ]
    verdicts = list(judged(tmp_path, report_nums, rows, [c.id for c in CLAIMS]).values())
    csv = verdicts_frame(verdicts)
    for setting, column in (("default", "verdict"), ("faithful", "faithful_verdict")):
        n = counts(verdicts, setting)
        assert sum(n[k] for k, _ in SUMMARY_ROWS) == len(CLAIMS)
        for key, _ in SUMMARY_ROWS:
            verdict, _, cls = key.partition(": ")
            sel = csv[column] == verdict
            if cls:
                sel &= csv["class" if setting == "default" else "faithful_class"] == cls
            assert int(sel.sum()) == n[key], (setting, key)
    assert counts(verdicts, "default")[HOLDS] > 0
    text = "\n".join(summary_markdown(verdicts))
    assert f"| **claims** | **{len(CLAIMS)}** | **{len(CLAIMS)}** |" in text
