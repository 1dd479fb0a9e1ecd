"""Ray-set and thread-scaling outputs on crafted rows with known answers, and
`all` on a mix of old and new CSVs: the report's tables stay what they were."""

from __future__ import annotations

import json

import pandas as pd
import pytest
from synthetic import BVH, EMBREE, KD, case_row, row, write_csv, write_reps

from accelbench_analysis.cli import main
from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.outputs.figures.workloads import (
    catalogue_leaks,
    ranking,
    ray_set_markdown,
    ray_set_rows,
    ray_set_table,
    thread_scaling_rows,
    without_thread_scaling,
)

# Render seconds per (structure, set) for 1e6 rays: Mrays/s = 1 / seconds. The kd-tree
# beats the BVH on ao rays only, so the order changes there and nowhere else.
SECONDS = {
    ("bvh", "primary"): 0.5,
    ("kdtree", "primary"): 1.0,
    ("embree", "primary"): 0.25,
    ("bvh", "ao"): 2.0,
    ("kdtree", "ao"): 1.0,
    ("embree", "ao"): 0.5,
}
ACCELS = {"bvh": BVH, "kdtree": KD, "embree": EMBREE}


def ray_set_row(accel: str, params: dict, seconds: float, ray_set: str, threads: int = 1) -> dict:
    """One row of a ray-set run on the bunny: 1e6 rays of `ray_set` in `seconds`."""
    return row(
        "stanford-bunny",
        accel,
        params,
        build=0.1,
        render=seconds,
        config="ray-sets",
        rays=1_000_000,
        shadow_rays=0,
        render_threads=str(threads),
        extra={"ray_set": ray_set, "ray_set_hash": f"{ray_set:0>16}"},
    )


def ray_set_csv(path):
    rows = [ray_set_row(accel, ACCELS[accel], s, rs) for (accel, rs), s in SECONDS.items()]
    return write_csv(path, rows, with_errors=True, extra_columns=("ray_set", "ray_set_hash"))


# Wall seconds per (structure, threads); CPU time = wall x threads (busy threads).
WALL = {("bvh", 1): 1.0, ("bvh", 2): 0.625, ("embree", 1): 0.4, ("embree", 2): 0.2}
# Build wall seconds: both build on the thread count (their `threads` parameter follows it).
BUILD = {("bvh", 1): 0.3, ("bvh", 2): 0.16, ("embree", 1): 0.2, ("embree", 2): 0.125}


def thread_csv(path):
    rows = []
    for (accel, t), s in WALL.items():
        params = dict(ACCELS[accel], threads=str(t))
        rows.append(
            row(
                "stanford-bunny",
                accel,
                params,
                build=BUILD[(accel, t)],
                render=s,
                config="thread-scaling",
                render_threads=str(t),
                extra={"ray_set": "camera", "render_cpu_s_median": s * t},
            )
        )
    return write_csv(path, rows, with_errors=True, extra_columns=("ray_set", "render_cpu_s_median"))


def test_old_csvs_load_as_camera_rows(realistic):
    assert set(realistic.rows["ray_set"]) == {"camera"}
    assert without_thread_scaling(realistic) == (realistic, [])


def test_ratio_to_embree_per_set(tmp_path):
    rows = ray_set_rows(load_results([ray_set_csv(tmp_path / "rs.csv")]))
    assert list(rows["ray_set"].cat.categories) == ["primary", "ao"]
    t = ray_set_table(rows).set_index(["structure", "ray_set"])
    assert t.loc[("BVH (median)", "primary"), "mrays_per_s"] == pytest.approx(2.0)
    assert t.loc[("BVH (median)", "primary"), "ratio_to_embree"] == pytest.approx(0.5)
    assert t.loc[("kd-tree", "ao"), "ratio_to_embree"] == pytest.approx(0.5)
    assert t.loc[("BVH (median)", "ao"), "ratio_to_embree"] == pytest.approx(0.25)
    assert t.loc[("Embree", "ao"), "ratio_to_embree"] == pytest.approx(1.0)


def test_ratio_to_embree_only_within_one_workload(tmp_path):
    """Embree at 1 and 2 render threads: each row is divided by Embree's row of its own
    thread count, never by the median of both (which made Embree 1.43x of itself)."""
    rows = []
    for threads, seconds in ((1, 0.5), (2, 0.25)):
        for accel, params, s in (
            ("bvh", BVH, 2 * seconds),
            ("embree", dict(EMBREE, threads=str(threads)), seconds),
        ):
            rows.append(ray_set_row(accel, params, s, "primary", threads))
    path = write_csv(tmp_path / "rs.csv", rows, with_errors=True, extra_columns=("ray_set", "ray_set_hash"))
    t = ray_set_table(ray_set_rows(load_results([path])))
    assert set(t["panel"]) == {"stanford-bunny (render_threads=1)", "stanford-bunny (render_threads=2)"}
    assert list(t.loc[t["structure"] == "Embree", "ratio_to_embree"]) == [1.0, 1.0]
    assert list(t.loc[t["structure"] == "BVH (median)", "ratio_to_embree"]) == [0.5, 0.5]
    # Two Embree rows of one workload: the one at Embree's defaults divides.
    rows.append(ray_set_row("embree", dict(EMBREE, quality="high"), 0.1, "primary"))
    path = write_csv(tmp_path / "rs2.csv", rows, with_errors=True, extra_columns=("ray_set", "ray_set_hash"))
    t = ray_set_table(ray_set_rows(load_results([path])))
    one = t[t["workload"] == "render_threads=1"].set_index("structure")["ratio_to_embree"]
    assert one["BVH (median)"] == pytest.approx(0.5) and one["Embree [quality=medium]"] == pytest.approx(1.0)


def test_ray_sets_at_several_thread_counts_are_said_to_be_in_the_ray_set_table(tmp_path):
    """Ray-set rows of a config with several render thread counts are left out of the
    report's tables as thread-scaling rows, and the note says where they are: the ray-set
    table (a section per thread count), not the thread-scaling table, which takes camera
    rows only and has none of them."""
    rows = [
        ray_set_row(accel, params, 0.5 / threads, rs, threads)
        for threads in (1, 2)
        for rs in ("primary", "shadow")
        for accel, params in (("bvh", BVH), ("embree", dict(EMBREE, threads=str(threads))))
    ]
    path = write_csv(tmp_path / "rs.csv", rows, with_errors=True, extra_columns=("ray_set", "ray_set_hash"))
    results = load_results([path])
    assert thread_scaling_rows(results).empty
    _, notes = without_thread_scaling(results)
    assert len(notes) == 1 and "8 rows of ray sets in tables/ray_sets.md" in notes[0]
    assert "thread_scaling.md" not in notes[0]
    # Camera rows of a thread-scaling run are where the note says, too.
    _, notes = without_thread_scaling(load_results([thread_csv(tmp_path / "ts.csv")]))
    assert "4 rows of camera rays in tables/thread_scaling.md" in notes[0]


def test_ranking_marks_where_the_order_changes(tmp_path):
    rows = ray_set_rows(load_results([ray_set_csv(tmp_path / "rs.csv")]))
    r = ranking(rows).set_index(["structure", "ray_set"])
    assert [r.loc[(s, "primary"), "rank"] for s in ("Embree", "BVH (median)", "kd-tree")] == [1, 2, 3]
    assert [r.loc[(s, "ao"), "rank"] for s in ("Embree", "kd-tree", "BVH (median)")] == [1, 2, 3]
    assert not r.loc[("Embree", "ao"), "changed"]
    assert r.loc[("kd-tree", "ao"), "changed"] and r.loc[("BVH (median)", "ao"), "changed"]
    assert not r.xs("primary", level="ray_set")["changed"].any()


def test_thread_scaling_speedup_and_efficiency(tmp_path):
    ts = thread_scaling_rows(load_results([thread_csv(tmp_path / "ts.csv")]))
    t = ts.set_index(["structure", "render_threads"])
    assert t.loc[("BVH (median)", 2), "speedup"] == pytest.approx(1.6)
    assert t.loc[("BVH (median)", 2), "efficiency"] == pytest.approx(0.8)
    assert t.loc[("Embree", 2), "speedup"] == pytest.approx(2.0)
    assert t.loc[("Embree", 2), "efficiency"] == pytest.approx(1.0)
    assert t.loc[("BVH (median)", 1), "speedup"] == pytest.approx(1.0)
    assert t.loc[("BVH (median)", 2), "cpu_per_wall"] == pytest.approx(2.0)
    # The build beside the render: its own speedup over the 1-thread build.
    assert t.loc[("BVH (median)", 2), "build_speedup"] == pytest.approx(1.875)
    assert t.loc[("Embree", 2), "build_speedup"] == pytest.approx(1.6)
    assert t.loc[("BVH (median)", 1), "build_speedup"] == pytest.approx(1.0)
    # A build thread count is a parameter that follows the render threads: still one
    # structure per accelerator, not one per count.
    assert set(ts["structure"]) == {"BVH (median)", "Embree"}


def test_thread_scaling_table_and_figure_show_the_build(tmp_path):
    out = tmp_path / "out"
    assert main(["all", str(thread_csv(tmp_path / "ts.csv")), "--out", str(out)]) == 0
    md = (out / "tables" / "thread_scaling.md").read_text()
    assert "| build ms | build speedup |" in md
    assert "| BVH (median) | 2 | 160.00 | 1.88 | 625.00 |" in md
    csv = pd.read_csv(out / "tables" / "thread_scaling.csv")
    assert {"build_s_median", "build_speedup"} <= set(csv.columns)
    spec = json.loads((out / "figures" / "thread_scaling.vl.json").read_text())
    by = {(v["structure"], v["measure"], v["render_threads"]): v["speedup"] for v in spec["data"]["values"]}
    assert by[("BVH (median)", "build", 2)] == pytest.approx(1.875)
    assert by[("BVH (median)", "render", 2)] == pytest.approx(1.6)


def test_all_writes_and_links_them_and_keeps_the_tables(realistic_csv, tmp_path):
    alone, mixed = tmp_path / "alone", tmp_path / "mixed"
    assert main(["all", str(realistic_csv), "--out", str(alone)]) == 0
    assert (
        main(
            [
                "all",
                str(realistic_csv),
                str(ray_set_csv(tmp_path / "rs.csv")),
                str(thread_csv(tmp_path / "ts.csv")),
                "--out",
                str(mixed),
            ]
        )
        == 0
    )
    for rel in (
        "tables/ray_sets.md",
        "tables/ray_sets.csv",
        "tables/ray_set_ranking.md",
        "figures/ray_sets.png",
        "tables/thread_scaling.md",
        "tables/thread_scaling.csv",
        "figures/thread_scaling.png",
    ):
        assert (mixed / rel).stat().st_size > 0, rel
        assert not (alone / rel).exists(), rel
    for rel in ("tables/table2.md", "tables/table4.md", "tables/table5.md"):
        assert (mixed / rel).read_text() == (alone / rel).read_text(), rel
    report = (mixed / "REPORT.md").read_text()
    beyond = report[report.index("## More of this run") :]
    for rel in (
        "tables/ray_sets.md",
        "tables/ray_set_ranking.md",
        "figures/ray_sets.png",
        "tables/thread_scaling.md",
        "figures/thread_scaling.png",
    ):
        assert f"]({rel})" in beyond, rel
    ranking_md = (mixed / "tables" / "ray_set_ranking.md").read_text()
    assert "Order changes in: ao." in ranking_md and "2*" in ranking_md


def test_the_ray_set_table_shows_each_structures_catalogue_leaks_beside_its_speed(tmp_path):
    """With the catalogue's rows in the input, each structure's leaks (failed and tolerated,
    summed over the cases) stand beside its Mrays/s; a structure the catalogue did not run
    gets "-"; without catalogue rows the column is not there."""
    rays = [
        ray_set_row(accel, params, s, "ao")
        for accel, params, s in (("bvh", BVH, 1.0), ("kdtree", KD, 2.0), ("embree", EMBREE, 0.5))
    ]
    cases = [
        case_row("case-1:closed-meshes", "bvh", BVH, "pass", "leaks=0 false_hits=0 rays=120"),
        case_row("case-3b:scaled", "bvh", BVH, "pass", "leaks=0 leaks_tolerated=40 rays=120"),
        case_row("case-3b:scaled", "embree", EMBREE, "FAIL", "leaks=120 false_hits=0 rays=120"),
        case_row("case-3c:scaled", "embree", EMBREE, "FAIL", "leaks=7 false_hits=0 rays=120"),
    ]
    cols = ("ray_set", "ray_set_hash")
    plain = load_results([write_csv(tmp_path / "rs.csv", rays, with_errors=True, extra_columns=cols)])
    assert catalogue_leaks(plain) == {}
    assert "catalogue leaks" not in ray_set_markdown(
        ray_set_table(ray_set_rows(plain), catalogue_leaks(plain))
    )
    both = load_results([write_csv(tmp_path / "all.csv", rays + cases, with_errors=True, extra_columns=cols)])
    t = ray_set_table(ray_set_rows(both), catalogue_leaks(both)).set_index("structure")["catalogue_leaks"]
    assert t["BVH (median)"] == 40 and t["Embree"] == 127 and pd.isna(t["kd-tree"])
    md = ray_set_markdown(ray_set_table(ray_set_rows(both), catalogue_leaks(both)))
    assert "| ao | catalogue leaks |" in md
    assert [line.split("|")[-2].strip() for line in md.splitlines() if line.startswith("| kd-tree")] == ["-"]


# Render seconds of each repetition per process: Embree 10% slower than the BVH in process 1
# and 10% faster in process 2, so the pooled medians are equal (ratio 1.00) and the
# BVH's worse process has Embree / BVH = 0.90. The kd-tree is never timed with Embree.
PROCESS_SECONDS = {
    "bvh": {1: (0.99, 1.0, 1.01), 2: (0.99, 1.0, 1.01)},
    "embree": {1: (1.09, 1.1, 1.11), 2: (0.89, 0.9, 0.91)},
    "kdtree": {1: (1.0, 1.0, 1.0), 2: (3.0, 3.0, 3.0)},
}


def interleaved_run(tmp_path, interleaved: bool, column: bool = True):
    """A ray-set run on `ao` in two processes, its .reps.csv beside it; with `interleaved`
    the BVH and Embree were timed alternately (each names the other in `timed_with`), else
    every row was timed alone; without `column` the file has no `timed_with` at all."""
    combos = {"bvh": "c-bvh", "embree": "c-embree", "kdtree": "c-kd"}
    pair = {"bvh": "c-embree", "embree": "c-bvh"}
    rows = []
    for accel, per_process in PROCESS_SECONDS.items():
        median = float(pd.Series([s for p in per_process.values() for s in p]).median())
        r = ray_set_row(accel, ACCELS[accel], median, "ao")
        together = pair.get(accel, "") if interleaved else ""
        r["extra"].update(combo_id=combos[accel], timed_with=together)
        rows.append(r)
    cols = ("ray_set", "ray_set_hash", "combo_id") + (("timed_with",) if column else ())
    path = write_csv(tmp_path / "rs.csv", rows, with_errors=True, extra_columns=cols)
    reps = [
        (r, k + 1 + 3 * (p - 1), s, p)
        for r in rows
        for p, seconds in PROCESS_SECONDS[r["accel"]].items()
        for k, s in enumerate(seconds)
    ]
    write_reps(tmp_path / "rs.reps.csv", reps)
    results = load_results([path])
    assert not results.warnings  # the summaries' medians are their repetitions'
    return results, ray_set_table(ray_set_rows(results), reps=results.reps).set_index("structure")


def test_the_worse_process_ratio_of_rows_timed_alternately(tmp_path):
    """Per process, Embree's median over the BVH's, both timed turn by turn there: 1.10 in
    process 1, 0.90 in process 2; the column is the worse, 0.90, beside the pooled 1.00."""
    results, t = interleaved_run(tmp_path, interleaved=True)
    assert set(results.rows["timed_with"]) == {"c-embree", "c-bvh", ""}
    assert t.loc["BVH (median)", "ratio_to_embree"] == pytest.approx(1.0)
    assert t.loc["BVH (median)", "ratio_to_embree_worse_process"] == pytest.approx(0.9)
    assert t.loc["Embree", "ratio_to_embree_worse_process"] == pytest.approx(1.0)
    # Timed alone, though its repetitions name processes: no per-process ratio.
    assert pd.isna(t.loc["kd-tree", "ratio_to_embree_worse_process"])
    md = ray_set_markdown(t.reset_index())
    assert "| BVH (median) | 1 (1.00x; worse process 0.90x) |" in md
    assert "| kd-tree | 0.5 (0.50x) |" in md
    assert "| Embree | 1 (1.00x) |" in md  # its own worse process is 1 by definition
    assert "the smallest of them" in md


@pytest.mark.parametrize("column", [True, False], ids=["timed-alone", "no-timed_with-column"])
def test_rows_timed_apart_have_no_worse_process_ratio(tmp_path, column):
    """The same repetitions, but the rows timed in separate processes (an empty
    `timed_with`, or a file from before the column): two medians timed apart are not read as
    one process's ratio."""
    results, t = interleaved_run(tmp_path, interleaved=False, column=column)
    assert set(results.rows["timed_with"]) == {""}
    assert t["ratio_to_embree_worse_process"].isna().all()
    assert t.loc["BVH (median)", "ratio_to_embree"] == pytest.approx(1.0)
    assert "worse process " not in ray_set_markdown(t.reset_index())
