"""The ranking REPORT.md opens with, on crafted rows with known ratios: ablations and
baseline variants are never ranked among the structures and have a table of their own
(only when the run has them); the first table stays narrow however many scenes and ray
sets; a cell without a ratio has one mark."""

from __future__ import annotations

import math
import re

import pytest
from synthetic import row, write_csv

from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.outputs.report.ranking import APART_TITLE as APART
from accelbench_analysis.outputs.report.ranking import ranking_markdown, ranking_table
from accelbench_analysis.outputs.report.ranking_rows import Ratio, geomean, ratios

WBVH = {"width": "8", "leaf_test": "watertight", "node_test": "conservative", "threads": "1"}
MOELLER = dict(WBVH, leaf_test="moeller")
FMA = dict(WBVH, node_test="fma")
BVH = {"split": "median", "max_prims": "1", "max_depth": "50", "threads": "1"}
EMBREE = {"threads": "1", "quality": "medium", "robust": "false", "compact": "false", "max_isa": "auto"}
ROBUST = dict(EMBREE, robust="true")
RAY_SETS = ["primary", "shadow", "ao", "diffuse", "random"]

# (accel, params, label, render seconds): the ablations are the fastest of all, so a
# ranking that took them in would rank them first.
ROWS = [
    ("bvh", BVH, "BVH (median)", 2.0),
    ("wbvh", WBVH, "wide BVH (8, SIMD)", 1.0),
    ("wbvh", MOELLER, "wide BVH (8, SIMD, ablation moeller)", 0.8),
    ("wbvh", FMA, "wide BVH (8, SIMD, ablation fma)", 0.9),
    ("embree", EMBREE, "Embree", 1.25),
    ("embree", ROBUST, "Embree", 1.5),
]


def run_csv(path, rows, models=("stanford-bunny", "igea"), sets=("camera",), status=None):
    out = []
    for model in models:
        for rs in sets:
            for accel, params, label, seconds in rows:
                s = (status or {}).get((label, model), "ok")
                out.append(
                    row(
                        model,
                        accel,
                        params,
                        build=seconds / 10,
                        render=seconds,
                        status=s,
                        config="mine",
                        extra={"label": label, "ray_set": rs},
                    )
                )
    return load_results([write_csv(path, out, extra_columns=("label", "ray_set"))])


def first_table(lines: list[str]) -> list[list[str]]:
    start = next(i for i, line in enumerate(lines) if line.startswith("|"))
    end = next((i for i in range(start, len(lines)) if not lines[i].startswith("|")), len(lines))
    return [[c.strip() for c in line.strip("|").split(" | ")] for line in lines[start:end]]


def section(lines: list[str], title: str) -> list[str]:
    """The lines after the paragraph that opens with this bold title."""
    i = next(i for i, line in enumerate(lines) if line.startswith(f"**{title}.**"))
    return lines[i + 1 :]


def test_ablations_and_baseline_variants_are_never_ranked_and_have_their_table(tmp_path):
    lines = ranking_markdown(run_csv(tmp_path / "run.csv", ROWS))
    table = first_table(lines)
    ranked = [r[0] for r in table[2:]]
    assert ranked == ["wide BVH (8, SIMD)", "Embree", "BVH (median)"]
    assert [r[1] for r in table[2:]] == ["1", "2", "3"]
    apart = first_table(section(lines, APART))
    cells = {r[0]: r[1:] for r in apart[2:]}
    assert list(cells) == [
        "wide BVH (8, SIMD, ablation fma) ÷ wide BVH (8, SIMD)",
        "wide BVH (8, SIMD, ablation fma) ÷ Embree",
        "wide BVH (8, SIMD, ablation moeller) ÷ wide BVH (8, SIMD)",
        "wide BVH (8, SIMD, ablation moeller) ÷ Embree",
        "Embree (robust=true) ÷ Embree",
    ]
    # Two scenes, per-scene columns: 0.8 / 1.0 against its own, 0.8 / 1.25 against Embree
    # at its defaults (robust=false, preferred although both are measured everywhere).
    assert apart[0][1:] == [
        "trace: stanford-bunny · camera",
        "trace: igea · camera",
        "build: stanford-bunny",
        "build: igea",
    ]
    own, embree = (
        cells["wide BVH (8, SIMD, ablation moeller) ÷ wide BVH (8, SIMD)"],
        cells["wide BVH (8, SIMD, ablation moeller) ÷ Embree"],
    )
    # ± the larger side of the interval: 2% on each median, 0.8 * 1.02 / 0.98 = 0.833 (+4.1%).
    assert own[0] == "0.800 ±4.1%" and embree[0] == "0.640 ±4.1%"
    assert cells["Embree (robust=true) ÷ Embree"][0] == "1.20 ±4.1%"
    lead = next(line for line in lines if line.startswith("**Ablations"))
    assert "here node_test=fma, leaf_test=moeller" in lead


def test_the_ablations_own_structure_is_the_row_beside_it(tmp_path):
    """The ratio to its own structure is taken on the same scene and rays, never across."""
    rows = [r for r in ROWS if r[2] != "wide BVH (8, SIMD, ablation fma)"]
    results = run_csv(tmp_path / "run.csv", rows, models=("igea",), sets=("camera", "ao"))
    r = ratios(results)
    moeller = r[r["structure"] == "wide BVH (8, SIMD, ablation moeller)"]
    assert list(moeller["kind"]) == ["ablation"] * 2
    assert all(math.isclose(t.value, 0.8) for t in moeller["own_trace"])
    assert all(math.isclose(t.value, 0.64) for t in moeller["trace"])
    assert set(r.loc[r["params"].str.contains("robust=true"), "kind"]) == {"baseline variant"}


def test_a_run_without_ablations_or_variants_has_no_such_table(tmp_path):
    rows = [r for r in ROWS if "ablation" not in r[2] and r[1] is not ROBUST]
    lines = ranking_markdown(run_csv(tmp_path / "run.csv", rows))
    assert not any("guarantees" in line or "ablation" in line.lower() for line in lines)
    assert [r[0] for r in first_table(lines)[2:]] == ["wide BVH (8, SIMD)", "Embree", "BVH (median)"]


def test_the_first_table_stays_narrow_for_many_scenes_and_ray_sets(tmp_path):
    models = [f"scene-{i}" for i in range(12)]
    results = run_csv(tmp_path / "run.csv", ROWS, models=models, sets=("camera", *RAY_SETS))
    header, table, notes, _ = ranking_table(ratios(results))
    assert header == ["structure", "rank", "camera (12)", *[f"{s} (12)" for s in RAY_SETS], "build (12)"]
    assert all(len(r) == len(header) for r in table)
    lines = ranking_markdown(results)
    apart = first_table(section(lines, APART))
    assert len(apart[0]) == 1 + 6 + 1
    # Per ray set, the geometric mean of equal ratios is that ratio.
    wide = next(r for r in table if r[0] == "wide BVH (8, SIMD)")
    assert all(c == "0.800 ±4.1%" for c in wide[2:8])


def test_a_cell_without_a_ratio_has_one_mark_and_the_notes_say_why(tmp_path):
    rows = [r for r in ROWS if "ablation" not in r[2] and r[1] is not ROBUST]
    status = {("BVH (median)", "igea"): "skipped", ("wide BVH (8, SIMD)", "igea"): "timeout"}
    lines = ranking_markdown(run_csv(tmp_path / "run.csv", rows, status=status))
    table = first_table(lines)
    cells = {r[0]: r[2:] for r in table[2:]}
    assert cells["BVH (median)"][1] == "—" and cells["wide BVH (8, SIMD)"][1] == "—"
    assert not any(re.search(r"skipped|timeout|not measured", c) for r in table for c in r)
    text = "\n".join(lines)
    assert "Did not finish: wide BVH (8, SIMD) on igea · camera: timeout" in text
    assert "No ratio: 1 row skipped by their configs" in text


def test_the_mean_of_ratios_takes_the_mean_of_their_interval_ends():
    m = geomean([Ratio(2.0, 1.0, 4.0), Ratio(8.0, 4.0, 16.0), Ratio(math.nan, math.nan, math.nan)])
    assert m.value == pytest.approx(4.0) and m.lo == pytest.approx(2.0) and m.hi == pytest.approx(8.0)
    assert m.text() == "4.00 [2.00–8.00]" and m.short() == "4.00 ±100%"
    assert geomean([]).text() == "—" == geomean([]).short()
    # ± the larger side, in per cent rounded up: never narrower than the interval.
    assert Ratio(1.0, 0.95, 1.012).short() == "1.00 ±5.0%"
    assert Ratio(0.5, 0.49, 0.5004).short() == "0.500 ±2.0%"
    assert Ratio(2.0, 1.9, 2.246).short() == "2.00 ±13%"
