"""The error columns: loading them (or their absence), the error rows and columns of every
table, and the error Pareto figure on zero and non-zero errors."""

import math

import matplotlib.image as mpimg
import numpy as np
import pytest
from synthetic import BVH, EMBREE, KD, LBVH, SAH, ZERO_ERRORS, case_row, realistic_rows, row, write_csv
from test_tables import cells_of, section_rows

from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.inputs.schema import ContractError, read_csv
from accelbench_analysis.mapping.errors import NOT_MEASURED
from accelbench_analysis.mapping.formatting import Section, to_latex, to_markdown
from accelbench_analysis.mapping.selection import STRUCTURE, Picker
from accelbench_analysis.outputs.figures import figures
from accelbench_analysis.outputs.report.tables import NOT_MEASURED_SECTION, model_table, table2

BUNNY = "stanford-bunny"


@pytest.fixture
def with_errors(tmp_path):
    rows = [
        row(
            BUNNY,
            "bvh",
            BVH,
            build=0.5,
            render=2.0,
            nodes=138901,
            prim_tests=1_000_000,
            errors={
                "false_misses": 3,
                "false_hits": 1,
                "prim_mismatches": 0,
                "nan_results": 0,
                "t_err_ulp_p50": 0.5,
                "t_err_ulp_max": 17,
                "peak_rss_bytes": 123 << 20,
            },
        ),
        # Measured, but no ray hit the same primitive as the reference: t error n/a.
        row(
            BUNNY,
            "lbvh",
            LBVH,
            build=1.0,
            render=2.2,
            nodes=138901,
            prim_tests=1_100_000,
            errors={"false_misses": 0, "false_hits": 0, "prim_mismatches": 2, "nan_results": 0},
        ),
        # The comparison did not run for this row.
        row(
            BUNNY, "kdtree", dict(KD, max_depth="29"), build=4.0, render=1.5, nodes=400000, prim_tests=300_000
        ),
        row(
            BUNNY,
            "kdtree",
            dict(KD, max_prims="10"),
            build=3.0,
            render=1.7,
            nodes=90000,
            prim_tests=600_000,
            config="table2",
            errors=dict(ZERO_ERRORS, false_misses=7),
        ),
        row(BUNNY, "bvh", SAH, build=1.2, render=1.0, nodes=40000, prim_tests=500_000, errors=ZERO_ERRORS),
        row(BUNNY, "embree", EMBREE, build=0.05, render=0.3, errors=ZERO_ERRORS),
        row("igea", "kdtree", KD, status="timeout", message="build exceeded 600 s"),
    ]
    return load_results([write_csv(tmp_path / "errors.csv", rows, with_errors=True)])


@pytest.fixture
def without_errors(tmp_path):
    rows = [
        row(BUNNY, "bvh", BVH, build=0.5, render=2.0, nodes=138901, prim_tests=10),
        row(
            BUNNY,
            "kdtree",
            dict(KD, max_prims="10"),
            build=3.0,
            render=1.7,
            nodes=9,
            prim_tests=6,
            config="table2",
        ),
    ]
    return load_results([write_csv(tmp_path / "old.csv", rows)])


# ---- loading ------------------------------------------------------------------------------


def test_new_columns_load_as_numbers_and_text(with_errors):
    bvh = with_errors.rows[with_errors.rows["accel"] == "bvh"].iloc[0]
    assert bvh["peak_rss_bytes"] == 123 << 20 and bvh["t_err_ulp_p50"] == 0.5
    assert (with_errors.rows["verdict"] == "").all()


def test_csv_without_the_new_columns_still_loads(without_errors):
    rows = without_errors.rows
    assert rows["peak_rss_bytes"].isna().all() and rows["false_misses"].isna().all()
    assert (rows["verdict"] == "").all() and (rows["verdict_counts"] == "").all()
    assert not without_errors.has_error_columns()


def test_verdict_rows_need_no_timings_and_unknown_verdicts_are_rejected(tmp_path):
    path = write_csv(
        tmp_path / "v.csv",
        [
            case_row("case-2a:translated", "bvh", {}, "FAIL", "leaks=1"),
            case_row("case-1a:sphere", "bvh", {}, "pass"),
        ],
        with_errors=True,
    )
    df = read_csv(path)
    assert list(df["verdict"]) == ["fail", "pass"]
    assert df["build_s_median"].isna().all() and df["repetitions"].isna().all()
    text = path.read_text().replace(",pass,", ",maybe,")
    path.write_text(text)
    with pytest.raises(
        ContractError, match=r"'verdict' must be pass, fail or empty; found \['maybe'\] on line 3 \(row 2\)"
    ):
        read_csv(path)


def test_case_rows_never_fill_a_report_cell(tmp_path):
    rows = [
        case_row(BUNNY, "bvh", BVH, "pass"),  # a verdict on a real model's name
        row(BUNNY, "bvh", dict(BVH, threads="2"), build=0.5, render=2.0),
    ]
    res = load_results([write_csv(tmp_path / "c.csv", rows, with_errors=True)])
    pick = Picker(res).pick(BUNNY, STRUCTURE["bvh"].spec)
    assert pick.ok and pick.row["verdict"] == "" and pick.row["build_s_median"] == 0.5


# ---- tables -------------------------------------------------------------------------------


def test_table4_error_rows(with_errors, report_nums):
    doc, rel = model_table(with_errors, report_nums, 4, [BUNNY, "igea"])
    misses = section_rows(doc, "False misses (primary rays, vs the reference)")
    by = {r[0]: r[1:] for r in misses}
    assert by["BVH (median)"] == ["3", "—", "—", "no row", "—", "—"]
    assert by["kd-tree"][:4] == [NOT_MEASURED, "—", "—", "timeout"]
    assert by["Embree"][0] == "0" and by["BVH (binned SAH)"][0] == "0"
    p50 = {r[0]: r[1] for r in section_rows(doc, "t error vs the reference, median (float ulps)")}
    assert p50["BVH (median)"] == "0.500" and p50["LBVH"] == "n/a"
    tmax = {r[0]: r[1] for r in section_rows(doc, "t error vs the reference, max (float ulps)")}
    assert tmax["BVH (median)"] == "17"
    assert section_rows(doc, "Wrong primitive (t differs by > 64 ulps)")[1][:2] == ["LBVH", "2"]
    # No row has image values: no image rows.
    assert not any(isinstance(r, Section) and "Image" in r.label for r in doc.rows)
    assert any("Errors are ours only" in n for n in doc.notes)
    md = to_markdown(doc)
    assert "| *False misses (primary rays, vs the reference)* |" in md
    assert "| BVH (median) | 3 | — | — | no row |" in md
    assert "False misses (primary rays, vs the reference)" in to_latex(doc)
    # The relative table: the four counts in one cell per structure and model.
    compact = {
        r[0]: r[1:]
        for r in section_rows(
            rel, "Errors vs the reference, ours (false misses / false hits / wrong prims / NaN)"
        )
    }
    assert compact["BVH (median)"][:2] == ["3 / 1 / 0 / 0", "—"]
    assert compact["LBVH"][0] == "0 / 0 / 2 / 0" and compact["kd-tree"][0] == NOT_MEASURED


def test_table2_error_columns(with_errors, report_nums):
    doc = table2(with_errors, report_nums)[0]
    assert doc.groups[-1] == ("Error vs the reference (ours; the report measured none)", 6)
    assert doc.header[-6:] == ["false misses", "false hits", "wrong prims", "NaN", "t ulp p50", "t ulp max"]
    assert cells_of(doc, "maxPrims=10")[-6:] == ["7", "0", "0", "0", "0", "1"]
    assert cells_of(doc, "maxPrims=1")[-6:] == [NOT_MEASURED] * 6  # the max_depth=29 row
    assert cells_of(doc, "maxPrims=100")[-6:] == ["no row"] * 6
    assert cells_of(doc, "Embree")[-6:] == ["0", "0", "0", "0", "0", "1"]
    md = to_markdown(doc)
    assert {ln.count("|") for ln in md.splitlines() if ln.startswith("|")} == {len(doc.header) + 1}


def test_tables_without_error_values_say_not_measured(without_errors, report_nums):
    doc, rel = model_table(without_errors, report_nums, 4, [BUNNY])
    assert any(isinstance(r, Section) and r.label == NOT_MEASURED_SECTION for r in doc.rows)
    assert any(isinstance(r, Section) and r.label == NOT_MEASURED_SECTION for r in rel.rows)
    assert any(n.startswith("Error against the reference: not measured.") for n in doc.notes)
    t2 = table2(without_errors, report_nums)[0]
    assert t2.header[-1] == "errors"
    assert cells_of(t2, "maxPrims=10")[-1] == NOT_MEASURED
    assert cells_of(t2, "maxPrims=100")[-1] == "no row"


def test_image_metrics_appear_when_measured(tmp_path, report_nums):
    errs = dict(ZERO_ERRORS, image_rmse=0.0123, hole_pixels=4)
    res = load_results(
        [
            write_csv(
                tmp_path / "img.csv",
                [
                    row(BUNNY, "bvh", BVH, build=0.5, render=2.0, errors=errs),
                    row(BUNNY, "lbvh", LBVH, build=0.5, render=2.0, errors=ZERO_ERRORS),
                    row(BUNNY, "bvh", SAH, build=0.5, render=1.0, errors=errs),
                ],
                with_errors=True,
            )
        ]
    )
    doc = model_table(res, report_nums, 4, [BUNNY])[0]
    rmse = {r[0]: r[1] for r in section_rows(doc, "Image RMSE vs the reference image")}
    assert rmse["BVH (median)"] == "0.0123" and rmse["LBVH"] == "n/a"
    holes = {r[0]: r[1] for r in section_rows(doc, "Hole pixels vs the reference image")}
    assert holes["BVH (median)"] == "4"
    t2 = table2(res, report_nums)[0]  # the binned-SAH BVH is its only row with values
    assert t2.header[-2:] == ["image RMSE", "hole pixels"]
    assert cells_of(t2, "BVH (binned SAH)")[-2:] == ["0.0123", "4"]


# ---- the Pareto figure ----------------------------------------------------------------------


def test_error_frame_sums_wrong_answers_and_leaves_out_case_rows(with_errors, tmp_path):
    df = figures.error_frame(with_errors)
    wrong = dict(zip(df["accel"] + ":" + df["params"].str[:9], df[figures.WRONG]))
    assert wrong["bvh:split=med"] == 4 and wrong["lbvh:max_prims"] == 2
    assert "kdtree" in set(df["accel"])  # the max_prims=10 row; the auto-depth one has no errors
    assert len(df) == 5
    rows = [
        case_row("case-1a:sphere", "bvh", BVH, "pass"),
        row(BUNNY, "bvh", BVH, build=0.5, render=2.0, errors=ZERO_ERRORS),
    ]
    res = load_results([write_csv(tmp_path / "c.csv", rows, with_errors=True)])
    assert list(figures.error_frame(res)["model"]) == [BUNNY]


def _all_zero(rows):
    for r in rows:
        r["errors"] = dict(ZERO_ERRORS)
    return rows


@pytest.mark.parametrize("zero", [True, False], ids=["all-zero", "non-zero"])
def test_error_pareto_draws(zero, tmp_path):
    rows = realistic_rows(seed=3)
    if zero:
        rows = _all_zero(rows)
    res = load_results([write_csv(tmp_path / "p.csv", rows, with_errors=True)])
    df = figures.error_frame(res)
    assert (df[figures.WRONG].max() == 0) == zero
    path = figures.error_pareto(res, tmp_path / "p.png")
    assert not isinstance(path, figures.Skipped), path
    img = mpimg.imread(path)
    assert img.shape[0] > 300 and img[..., :3].std() > 0.05
    assert not math.isnan(float(np.asarray(img).mean()))


def test_harness_column_order_loads(tmp_path, report_nums):
    """The committed table4 run with the error, memory and verdict columns where the harness
    writes them (after `instructions`, before `width`), filled: the errors reach Table 4."""
    import csv
    from pathlib import Path

    from accelbench_analysis.inputs.schema import ERROR_MEMORY_VERDICT_COLUMNS

    src = Path(__file__).resolve().parents[2] / "results" / "reference" / "csv" / "table4.csv"
    rows = list(csv.reader(src.open(newline="")))
    # Whatever the committed run has in these columns, replace it with known values.
    keep = [i for i, c in enumerate(rows[0]) if c not in ERROR_MEMORY_VERDICT_COLUMNS]
    rows = [[r[i] for i in keep] for r in rows]
    head = rows[0]
    at = head.index("instructions") + 1
    status = head.index("status")
    filled = ["4", "0", "1", "0", "3", "0", "", "", str(200 << 20), "", ""]
    rows = [head[:at] + ERROR_MEMORY_VERDICT_COLUMNS + head[at:]] + [
        r[:at] + (filled if r[status] == "ok" else [""] * len(filled)) + r[at:] for r in rows[1:]
    ]
    path = tmp_path / "table4.csv"
    csv.writer(path.open("w", newline="")).writerows(rows)
    res = load_results([path])
    assert res.has_error_columns() and res.case_rows().empty
    doc = model_table(res, report_nums, 4, ["stanford-bunny"])[0]
    misses = section_rows(doc, "False misses (primary rays, vs the reference)")
    assert misses and all(r[1] == "4" for r in misses if r[1] not in ("no row", "timeout", "error"))
    assert any(r[1] == "4" for r in misses)
