"""Table builders on a small crafted CSV: exact cells, labels and notes."""

import re

import pytest
from synthetic import BVH, EMBREE, KD, LBVH, SAH, row, write_csv

from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.mapping.formatting import (
    Cell,
    Section,
    TableDoc,
    fmt_measure,
    fmt_sig,
    tex_escape,
    to_latex,
    to_markdown,
)
from accelbench_analysis.mapping.selection import AUTO, kd_auto_depths, param_matches
from accelbench_analysis.outputs.report.tables import model_table, table2


def cells_of(doc: TableDoc, label: str) -> list[str]:
    for r in doc.rows:
        if not isinstance(r, Section) and r[0].text == label:
            return [c.text for c in r[1:]]
    raise AssertionError(
        f"no row {label!r} in {doc.name}: {[r[0].text for r in doc.rows if not isinstance(r, Section)]}"
    )


def section_rows(doc: TableDoc, section: str) -> list[list[str]]:
    out, inside = [], False
    for r in doc.rows:
        if isinstance(r, Section):
            inside = r.label == section
        elif inside:
            out.append([c.text for c in r])
    return out


@pytest.fixture
def small(tmp_path):
    rows = [
        row("stanford-bunny", "bvh", BVH, build=0.5, render=2.0, nodes=138901, prim_tests=1_000_000),
        row("stanford-bunny", "lbvh", LBVH, build=1.0, render=2.2, nodes=138901, prim_tests=1_100_000),
        # max_depth=29 is the automatic depth for 69,451 triangles: it is the default kd-tree.
        row(
            "stanford-bunny",
            "kdtree",
            dict(KD, max_depth="29"),
            build=4.0,
            render=1.5,
            nodes=400000,
            prim_tests=300_000,
        ),
        row(
            "stanford-bunny",
            "kdtree",
            dict(KD, max_depth="28"),
            build=3.9,
            render=1.6,
            nodes=390000,
            prim_tests=310_000,
            config="table2",
        ),
        row("stanford-bunny", "bvh", SAH, build=1.2, render=1.0, nodes=40000, prim_tests=500_000),
        row("stanford-bunny", "embree", EMBREE, build=0.05, render=0.3),
        row("igea", "kdtree", KD, status="timeout", message="build exceeded 600 s"),
    ]
    return load_results([write_csv(tmp_path / "small.csv", rows)])


def test_table4_exact_cells(small, report_nums):
    doc, rel = model_table(small, report_nums, 4, ["stanford-bunny", "igea", "asian-dragon", "happy-buddha"])
    # #primitives as both triangles and vertices, against the report's single number.
    assert cells_of(doc, "#triangles (ours)")[:3] == ["69,451", "35,947", "1.93"]
    assert cells_of(doc, "#vertices (ours)")[:3] == ["35,947", "35,947", "1.00"]
    build = section_rows(doc, "Build time (s)")
    bvh = next(r for r in build if r[0] == "BVH (median)")
    assert bvh[1:4] == ["0.500 [0.490, 0.510]", "0.849", "0.589"]
    assert bvh[4:7] == ["no row", "2.74", "—"]
    kd = next(r for r in build if r[0] == "kd-tree")
    assert kd[1:4] == ["4.00 [3.92, 4.08]", "2.35", "1.71"]
    assert kd[4] == "timeout"
    nodes = section_rows(doc, "#nodes")
    assert next(r for r in nodes if r[0] == "BVH (median)")[1:4] == ["138,901", "71,893", "1.93"]
    assert next(r for r in nodes if r[0] == "Embree")[1:4] == ["n/a", "—", "—"]
    assert next(r for r in nodes if r[0] == "BVH (binned SAH)")[1:4] == ["40,000", "—", "—"]
    notes = " ".join(doc.notes)
    assert "kd-tree on igea: timeout: build exceeded 600 s." in notes
    assert "equals the VERTEX count for bunny 35,947" in notes
    assert "equal 2 x #Primitives - 1 on all 4 models" in notes
    assert "4 of its 12 values in this table lie below the 307,200 primary rays" in notes
    assert "Embree exposes no node or primitive-test counters" in notes
    assert "Stand-in: the Stanford dragon" in notes
    # Relative to BVH: LBVH build 1.0 / 0.5 = 2, report 1.272 / 0.849.
    lbvh = next(r for r in section_rows(rel, "Build time (s) / BVH (median) build time") if r[0] == "LBVH")
    assert lbvh[1:3] == ["2.00", "1.50"]


def test_traversal_modes_become_labelled_rows(tmp_path, report_nums):
    rows = [
        row(
            "stanford-bunny",
            "bvh",
            dict(BVH, traversal=t),
            build=0.5,
            render=r,
            nodes=138901,
            prim_tests=1000,
        )
        for t, r in (("ordered", 1.0), ("report", 1.5))
    ]
    doc = model_table(
        load_results([write_csv(tmp_path / "t.csv", rows)]), report_nums, 4, ["stanford-bunny"]
    )[0]
    render = section_rows(doc, "Render time (s)")
    assert [r[0] for r in render][:2] == [
        "BVH (median) [traversal=ordered]",
        "BVH (median) [traversal=report]",
    ]
    assert render[0][1].startswith("1.00 [") and render[1][1].startswith("1.50 [")
    assert any("[traversal=...] rows" in n for n in doc.notes)


def test_table2_maps_settings_to_kdtree_parameters(tmp_path, report_nums):
    rows = [
        row(
            "stanford-bunny",
            "kdtree",
            dict(KD, max_prims=mp),
            build=1.0,
            render=2.0,
            nodes=n,
            prim_tests=t,
            config="table2",
        )
        for mp, n, t in (("1", 400000, 100), ("10", 20000, 1000), ("100", 1500, 10000))
    ]
    rows += [
        row(
            "stanford-bunny",
            "kdtree",
            dict(KD, max_prims="4", max_depth=d),
            build=0.5,
            render=float(d),
            nodes=int(d) * 10,
            prim_tests=5,
            config="table2",
        )
        for d in ("5", "10", "28", "100")
    ]
    # A stray row at another max_prims that covers only one depth must not be chosen.
    rows.append(
        row(
            "stanford-bunny",
            "kdtree",
            dict(KD, max_prims="2", max_depth="5"),
            build=9,
            render=9,
            nodes=1,
            prim_tests=1,
            config="table2",
        )
    )
    doc = table2(load_results([write_csv(tmp_path / "t2.csv", rows)]), report_nums)[0]
    mp10 = cells_of(doc, "maxPrims=10")
    assert mp10[0] == "max_prims=10, max_depth=auto"
    assert mp10[1:4] == ["20,000", "19,229", "1.04"]
    d28 = cells_of(doc, "maxDepth=28")
    assert d28[0] == "max_prims=4, max_depth=28"
    assert d28[1:4] == ["280", "44,852", "0.00624"]
    assert any("max_prims=4, the value our depth sweep was run with" in n for n in doc.notes)
    assert any("418,548 nodes) and its Table 4 kd-tree" in n for n in doc.notes)


def test_kd_auto_depth():
    assert kd_auto_depths(69451) == {29}
    assert kd_auto_depths(35947) == {28}  # the report's 28 from its vertex count
    assert param_matches({"max_depth": "auto"}, 69451, "max_depth", AUTO)
    assert param_matches({"max_depth": "29"}, 69451, "max_depth", AUTO)
    assert not param_matches({"max_depth": "28"}, 69451, "max_depth", AUTO)
    assert param_matches({}, 69451, "max_depth", "50")  # no such parameter: cannot differ


def test_mixed_provenance_tags_cells(tmp_path, report_nums):
    a = write_csv(tmp_path / "a.csv", [row("stanford-bunny", "bvh", BVH, build=0.5, render=2.0)])
    b = write_csv(
        tmp_path / "b.csv", [row("stanford-bunny", "lbvh", LBVH, build=1.0, render=2.0, git_sha="e" * 40)]
    )
    doc = model_table(load_results([a, b]), report_nums, 4, ["stanford-bunny"])[0]
    md = to_markdown(doc)
    assert md.count("> **Warning:** MIXED PROVENANCE") == 1
    assert "0.500 [0.490, 0.510] ⁽A⁾" in md and "1.00 [0.98, 1.02] ⁽B⁾" in md
    assert "\\textsuperscript{B}" in to_latex(doc)


def test_number_formatting():
    assert fmt_sig(0.000123456) == "0.000123"
    assert fmt_sig(9.996) == "10.0"
    assert fmt_sig(123456.7) == "123,457"
    assert fmt_sig(None) == "—"
    assert fmt_measure(1.2345, 1.2, 1.3) == "1.23 [1.20, 1.30]"
    assert fmt_measure(2.0, float("nan"), 2.1) == "2.00"


def test_markdown_and_latex_shapes():
    doc = TableDoc(
        "t",
        "T",
        "cap",
        [("G_1 & co", 2)],
        ["", "a", "b"],
        [Section("sec #1"), [Cell("x_1"), Cell("1"), Cell("2")]],
        notes=["n 50%"],
    )
    md = to_markdown(doc)
    table_lines = [ln for ln in md.splitlines() if ln.startswith("|")]
    assert {ln.count("|") for ln in table_lines} == {4}
    assert "| **G_1 & co** a | b |" in md
    tex = to_latex(doc)
    assert r"\multicolumn{2}{c}{G\_1 \& co}" in tex and r"\cmidrule(lr){2-3}" in tex
    assert r"\multicolumn{3}{l}{\textit{sec \#1}}" in tex and r"x\_1 & 1 & 2 \\" in tex
    assert r"n 50\%" in tex
    assert tex_escape("a→b ~") == r"a$\to$b \textasciitilde{}"
    assert re.search(r"\\begin\{tabular\}\{lrr\}", tex)
