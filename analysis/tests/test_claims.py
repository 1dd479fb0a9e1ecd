"""Claim verdicts follow the data: the report's own numbers, then crafted changes that flip
each claim's verdict, then our side (missing rows, mixed provenance, traversal choice)."""

import math

import pytest
from synthetic import BVH, KD, LBVH, row, write_csv

from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.outputs.report.claims import (
    CLAIMS,
    FAILS,
    HOLDS,
    NOT_COMPARABLE,
    OurSource,
    ReportSource,
    approx,
    approx_range,
    evaluate,
)

CLAIM = {c.id: c for c in CLAIMS}
# What the report's own numbers say (computed by hand from report-tables.csv):
# 5.1-b: nodes 418,548 / 1,461 = 286x, not ~418x; 5.3-b: Trees 42.028/22.822 = 1.84x, not > 2x.
REPORT_FAILS = {"5.1-b", "5.3-b"}


def verdict(report_nums, claim_id):
    return evaluate(CLAIM[claim_id], ReportSource(report_nums))


def test_every_claim_on_the_report_numbers(report_nums):
    for c in CLAIMS:
        f = evaluate(c, ReportSource(report_nums))
        assert f.verdict == (FAILS if c.id in REPORT_FAILS else HOLDS), (c.id, f.evidence)


def setv(report_nums, model, accel, setting, column, value):
    sel = (
        (report_nums["model"] == model)
        & (report_nums["accelerator"] == accel)
        & (report_nums["setting"] == setting)
    )
    assert sel.sum() == 1
    report_nums.loc[sel, column] = value


def scale(report_nums, models, accel, column, factor, like=None):
    for m in models:
        src = like or accel
        base = report_nums.loc[
            (report_nums["model"] == m)
            & (report_nums["accelerator"] == src)
            & (report_nums["setting"] == "default"),
            column,
        ].iloc[0]
        setv(report_nums, m, accel, "default", column, base * factor)


B, I, D, H, T, C = "stanford-bunny", "igea", "asian-dragon", "happy-buddha", "trees", "sci-fi-city"  # noqa: E741 (the report's model initials)
K2 = (B, "kdtree")
FLIPS = {
    "5.1-a": lambda r: setv(r, *K2, "maxPrims=100", "build_s", 5.214),
    "5.1-b": lambda r: setv(r, *K2, "maxPrims=100", "nodes", 1000),
    "5.1-c": lambda r: setv(r, *K2, "maxPrims=100", "prim_tests", 1921710),
    "5.1-d": lambda r: setv(r, *K2, "maxPrims=100", "render_s", 20.845),
    "5.1-e": lambda r: (
        setv(r, *K2, "maxPrims=1", "build_s", 1.0),
        setv(r, *K2, "maxPrims=1", "render_s", 10.0),
    ),
    "5.1-f": lambda r: setv(r, *K2, "maxDepth=100", "render_s", 20.0),
    "5.1-g": lambda r: setv(r, *K2, "maxDepth=5", "render_s", 11.566),
    "5.1-h": lambda r: setv(r, *K2, "maxDepth=28", "render_s", 11.048),
    "5.1-i": lambda r: setv(r, *K2, "maxDepth=100", "nodes", 60000),
    "5.1-j": lambda r: setv(r, *K2, "maxDepth=100", "render_s", 5.0),
    "5.2-a": lambda r: setv(r, I, "bvh", "default", "build_s", 5.0),
    "5.2-b": lambda r: setv(r, I, "kdtree", "default", "build_s", 1.0),
    "5.2-c": lambda r: scale(r, [B, I, D, H], "lbvh", "build_s", 1.0, like="bvh"),
    "5.2-d": lambda r: scale(r, [I, D], "lbvh", "render_s", 2.0, like="bvh"),
    "5.2-e": lambda r: scale(r, [I, D], "lbvh", "build_s", 0.01),
    "5.2-f": lambda r: scale(r, [I, D], "kdtree", "build_s", 0.01),
    "5.2-g": lambda r: setv(r, I, "lbvh", "default", "nodes", 400000),
    "5.2-h": lambda r: setv(r, D, "kdtree", "default", "nodes", 2_000_000),
    "5.2-i": lambda r: setv(r, H, "kdtree", "default", "prim_tests", 4_000_000),
    "5.3-a": lambda r: setv(r, T, "bvh", "default", "render_s", 10.0),
    "5.3-b": lambda r: (
        setv(r, T, "bvh", "default", "render_s", 50.0),
        setv(r, T, "lbvh", "default", "render_s", 50.0),
    ),
    "5.3-c": lambda r: setv(r, T, "kdtree", "default", "build_s", 5.0),
    "5.3-d": lambda r: setv(r, C, "lbvh", "default", "render_s", 100.0),
    "5.3-e": lambda r: setv(r, C, "lbvh", "default", "render_s", 60.0),
    "5.3-f": lambda r: setv(r, C, "bvh", "default", "render_s", 10.0),
    "6-a": lambda r: scale(r, [B, I, D, H], "lbvh", "build_s", 0.01),
    "6-b": lambda r: scale(r, [I, D, H], "lbvh", "render_s", 2.0, like="bvh"),
    "6-c": lambda r: scale(r, [B, I, H], "kdtree", "render_s", 3.0, like="bvh"),
    "6-d": lambda r: setv(r, T, "kdtree", "default", "build_s", 1.0),
}


def test_every_claim_has_a_flip():
    assert set(FLIPS) == set(CLAIM)


@pytest.mark.parametrize("claim_id", sorted(FLIPS))
def test_crafted_change_flips_the_verdict(report_nums, claim_id):
    before = verdict(report_nums, claim_id).verdict
    changed = report_nums.copy()
    FLIPS[claim_id](changed)
    after = evaluate(CLAIM[claim_id], ReportSource(changed))
    assert {before, after.verdict} == {HOLDS, FAILS}, after.evidence


def test_missing_number_is_not_comparable(report_nums):
    cut = report_nums[~((report_nums["model"] == "trees") & (report_nums["accelerator"] == "kdtree"))]
    f = evaluate(CLAIM["5.3-a"], ReportSource(cut))
    assert f.verdict == NOT_COMPARABLE and "kdtree" in f.evidence and "trees" in f.evidence


def test_failed_premise_is_not_comparable(report_nums):
    changed = report_nums.copy()
    changed.loc[changed["model"] == "sci-fi-city", "primitives"] = 200000
    f = evaluate(CLAIM["5.3-f"], ReportSource(changed))
    assert f.verdict == NOT_COMPARABLE and "premise" in f.evidence


def test_approx_tolerance():
    lo, hi = approx_range(1.2)
    assert math.isclose(lo, 1.2 * math.exp(-0.5 * math.log(1.2)))
    assert approx(1.13, 1.2) and not approx(1.05, 1.2) and not approx(1.0, 1.2)
    assert approx(1.72, 2) and not approx(1.55, 2) and not approx(2.6, 2)
    assert not approx(286, 418) and approx(400, 418)


# ---- our side ------------------------------------------------------------------------------


def ours(tmp_path, rows, report_nums, name="o.csv", more=()):
    res = load_results([write_csv(tmp_path / name, rows)] + list(more))
    return OurSource(res, report_nums)


def bunny_igea_rows(**prov):
    out = []
    for m, f in (("stanford-bunny", 1.0), ("igea", 4.0), ("stanford-dragon", 12), ("happy-buddha-100k", 2)):
        out += [
            row(m, "bvh", BVH, build=0.1 * f, render=1.0 * f, **prov),
            row(m, "lbvh", LBVH, build=0.2 * f, render=1.05 * f, **prov),
            row(m, "kdtree", KD, build=0.9 * f, render=0.8 * f, **prov),
        ]
    return out


def test_ours_holds_and_fails(tmp_path, report_nums):
    src = ours(tmp_path, bunny_igea_rows(), report_nums)
    assert evaluate(CLAIM["5.2-a"], src).verdict == HOLDS
    assert evaluate(CLAIM["5.2-c"], src).verdict == HOLDS  # LBVH/BVH build exactly 2
    assert evaluate(CLAIM["5.2-f"], src).verdict == HOLDS
    rows = bunny_igea_rows()
    rows[1] = row("stanford-bunny", "lbvh", LBVH, build=0.05, render=1.0)  # LBVH fastest on the bunny
    f = evaluate(CLAIM["5.2-a"], ours(tmp_path, rows, report_nums, "o2.csv"))
    assert f.verdict == FAILS and "bunny ✗" in f.evidence


def test_ours_missing_row_names_the_reason(tmp_path, report_nums):
    rows = bunny_igea_rows()
    rows[2] = row("stanford-bunny", "kdtree", KD, status="timeout", message="600 s")
    f = evaluate(CLAIM["5.2-b"], ours(tmp_path, rows, report_nums))
    assert f.verdict == NOT_COMPARABLE and "timeout" in f.evidence and "stanford-bunny" in f.evidence


def test_ours_mixed_provenance_is_not_comparable(tmp_path, report_nums):
    rows = bunny_igea_rows()
    other = write_csv(
        tmp_path / "other.csv",
        [row("igea", "kdtree", dict(KD, threads="2"), build=9, render=9, cpu="Other CPU")],
    )
    src = ours(
        tmp_path, rows[:5] + rows[6:], report_nums, more=[other]
    )  # Igea's kd-tree only from the other machine
    f = evaluate(CLAIM["5.2-a"], src)
    assert f.verdict == NOT_COMPARABLE and "provenance groups (A, B)" in f.evidence
    # A claim that touches only one machine's rows is still judged.
    assert evaluate(CLAIM["5.2-c"], src).verdict == HOLDS


def test_ours_prefers_report_traversal(tmp_path, report_nums):
    rows = bunny_igea_rows()
    rows[0] = row("stanford-bunny", "bvh", dict(BVH, traversal="ordered"), build=0.1, render=0.5)
    rows.append(row("stanford-bunny", "bvh", dict(BVH, traversal="report"), build=0.1, render=2.0))
    src = ours(tmp_path, rows, report_nums)
    assert src.get("stanford-bunny", "bvh", "render") == 2.0
    assert src.variants_used == {"report"}
