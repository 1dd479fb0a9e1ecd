"""One palette for every figure (mapping/styles.py): a structure the analysis does not know
still appears in the tables and figures, each with a colour no other structure has."""

from synthetic import BVH, KD, LBVH, row, write_csv

from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.mapping.selection import Picker, label_of
from accelbench_analysis.mapping.styles import Styles, accel_styles
from accelbench_analysis.outputs.figures.figures import structure_frame
from accelbench_analysis.outputs.report.comparison import three_way
from accelbench_analysis.outputs.report.tables import build_tables, to_markdown

WBVH8 = {"width": "8"}
WBVH4 = {"width": "4"}


def run_with_unknown(tmp_path):
    rows = []
    for m in ("stanford-bunny", "igea"):
        rows += [
            row(m, "bvh", BVH, build=0.1, render=1.0, nodes=1001, prim_tests=10),
            row(m, "lbvh", LBVH, build=0.05, render=1.1, nodes=1001, prim_tests=11),
            row(m, "kdtree", KD, build=0.9, render=0.8, nodes=5000, prim_tests=8),
            row(m, "wbvh", WBVH8, build=0.2, render=0.3, nodes=300, prim_tests=9),
            row(m, "wbvh", WBVH4, build=0.2, render=0.35, nodes=400, prim_tests=9),
            row(m, "octree", {}, build=0.3, render=0.9, nodes=700, prim_tests=12),
        ]
    return load_results([write_csv(tmp_path / "run.csv", rows)])


def test_an_unknown_structure_is_in_every_table_and_figure_with_its_own_colour(tmp_path, report_nums):
    results = run_with_unknown(tmp_path)
    assert "octree" in [s.label for s in Picker(results).structures()]
    tables = build_tables(results, report_nums)
    assert "octree" in "\n".join(to_markdown(d) for d in tables["table4"])
    # The three-way comparison (comparison.md, REPORT.md) too, with its own numbers.
    octree = [r for r in three_way(results, None, report_nums) if r.structure == "octree"]
    assert {(r.metric, r.this) for r in octree if r.model.startswith("Stanford bunny")} >= {
        ("build", 0.3),
        ("render", 0.9),
        ("nodes", 700),
    }
    frame = structure_frame(results)
    labels = set(frame["structure"])
    assert {"octree", "wide BVH (8, SIMD)", "wide BVH (4, SIMD)"} <= labels
    palette = Styles(frame["structure"]).palette()
    assert len(set(palette.values())) == len(palette)  # no two structures share a colour
    assert "#000000" not in palette.values() and "black" not in palette.values()
    order, colours = accel_styles(["octree", "wbvh", "bvh", "embree"])
    assert order[:2] == ["bvh", "wbvh"] and len(set(colours.values())) == 4


def test_known_structures_keep_their_colour_whatever_else_is_drawn():
    alone = Styles(["wide BVH (4, SIMD)"]).palette()
    crowded = Styles(["octree", "BVH (median)", "wide BVH (4, SIMD)", "x", "Embree"]).palette()
    assert alone["wide BVH (4, SIMD)"] == crowded["wide BVH (4, SIMD)"]
    assert len(set(Styles([f"s{i}" for i in range(40)]).palette().values())) == 40


def test_labels_follow_the_identity_parameters():
    assert label_of("wbvh", {"width": "4"}) == "wide BVH (4, SIMD)"
    assert label_of("wbvh", {"width": "8"}) == "wide BVH (8, SIMD)"
    assert label_of("bvh", {"split": "sah", "max_prims": "4"}) == "BVH (binned SAH)"
    assert label_of("octree", {}) == "octree"
