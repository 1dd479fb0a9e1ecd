"""The report's tables take exactly the rows of their workload (camera rays, one render
thread, one image per model) and say what they left out or cannot find."""

from __future__ import annotations

from synthetic import BVH, EMBREE, row, write_csv

from accelbench_analysis.cli import main
from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.mapping.selection import report_rows

EXTRA = ("ray_set", "ray_set_hash", "image_width", "image_height", "spp")


def bvh_row(render: float, *, ray_set="camera", threads=1, image=(640, 480), config="table4", stamp="1"):
    return row(
        "stanford-bunny",
        "bvh",
        BVH,
        build=0.1,
        render=render,
        config=config,
        render_threads=str(threads),
        timestamp=f"2024-01-0{stamp}T00:00:00Z",
        extra={
            "ray_set": ray_set,
            "ray_set_hash": "0" * 16,
            "image_width": image[0],
            "image_height": image[1],
            "spp": 1,
        },
    )


def bvh_render_cell(out) -> str:
    """Our render time of the median BVH on the bunny in Table 4 (its first sub-column)."""
    text = (out / "tables" / "table4.md").read_text()
    render = text[text.index("*Render time (s)*") :]
    line = next(line for line in render.splitlines() if line.startswith("| BVH (median) |"))
    return line.split("|")[2].strip()


def run_tables(tmp_path, rows, capsys) -> tuple[str, str]:
    csv = write_csv(tmp_path / "run.csv", rows, with_errors=True, extra_columns=EXTRA)
    out = tmp_path / "out"
    assert main(["tables", str(csv), "--out", str(out)]) == 0
    return bvh_render_cell(out), (out / "tables" / "table4.md").read_text() + capsys.readouterr().err


def test_a_csv_of_ray_sets_only_fills_no_table_cell(tmp_path, capsys):
    # Before: the shadow set's 9 s stood in Table 4 as the BVH's render time.
    cell, said = run_tables(
        tmp_path,
        [
            bvh_row(9.0, ray_set="shadow", config="ray-sets"),
            bvh_row(1.0, ray_set="primary", config="ray-sets"),
        ],
        capsys,
    )
    assert cell == "no row"
    assert "no row is of the report's workload" in said
    assert "2 rows of ray sets (1 shadow, 1 primary)" in said


def test_rows_on_more_threads_are_left_out_even_when_newer(tmp_path, capsys):
    cell, said = run_tables(
        tmp_path, [bvh_row(1.0), bvh_row(0.25, threads=4, config="fast", stamp="2")], capsys
    )
    assert cell.startswith("1.00 ")
    assert "1 rows rendered on more than one thread (1 4 threads)" in said


def test_one_image_per_model_the_reports_where_there_is_one(tmp_path, capsys):
    cell, said = run_tables(
        tmp_path, [bvh_row(1.0), bvh_row(0.25, image=(320, 240), config="quick", stamp="2")], capsys
    )
    assert cell.startswith("1.00 ")
    assert "left out on stanford-bunny: 1 rows at another image (1 320x240)" in said
    # Only a smaller image: used, and every table says so.
    cell, said = run_tables(tmp_path, [bvh_row(0.25, image=(320, 240), config="quick")], capsys)
    assert cell.startswith("0.250 ")
    assert "stanford-bunny has no row at the report's 640x480: its cells are 320x240 renders" in said


def test_ablations_keep_their_own_image(tmp_path):
    rows = [bvh_row(1.0), bvh_row(0.5, image=(160, 120), config="ablations")]
    results = load_results([write_csv(tmp_path / "run.csv", rows, with_errors=True, extra_columns=EXTRA)])
    kept, notes = report_rows(results, own_image=results.rows["config"] == "ablations")
    assert len(kept.rows) == 2 and notes == []
    embree = row("stanford-bunny", "embree", EMBREE, build=0.1, render=0.5, extra={"ray_set": "ao"})
    results = load_results([write_csv(tmp_path / "ao.csv", [embree], extra_columns=("ray_set",))])
    kept, notes = report_rows(results)
    assert kept.rows.empty and kept.warnings[-1].startswith("no row is of the report's workload")
