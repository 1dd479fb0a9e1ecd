"""robustness.md from a crafted configs/robustness.yaml run: verdict cells, failures, the
stiff-parameter rows, and the command line."""

import pytest
from synthetic import EMBREE_LEAKS, realistic_rows, robustness_rows, write_csv

from accelbench_analysis.cli import main
from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.outputs.report.robustness import case_sort_key, robustness_markdown


@pytest.fixture(scope="module")
def robust_csv(tmp_path_factory):
    return write_csv(
        tmp_path_factory.mktemp("robust") / "robustness.csv", robustness_rows(), with_errors=True
    )


@pytest.fixture(scope="module")
def text(robust_csv):
    return robustness_markdown(load_results([robust_csv]))


def section(text: str, title: str) -> list[str]:
    body = text.split(f"## {title}\n", 1)[1].split("\n## ", 1)[0]
    return [ln for ln in body.splitlines() if ln.startswith("|")]


def table(lines: list[str]) -> list[list[str]]:
    return [[c.strip() for c in ln.strip("|").split(" | ")] for ln in lines]


def test_verdict_table_cells(text):
    rows = table(section(text, "Verdicts per case and accelerator setting"))
    header = rows[0]
    # Embree's robust flag varies between its case rows: two columns; the others do not vary.
    assert header == [
        "case",
        "name",
        "brute_force",
        "bvh",
        "lbvh",
        "kdtree",
        "embree robust=false",
        "embree robust=true",
        "reference",
    ]
    cells = {r[0]: dict(zip(header, r)) for r in rows[2:]}
    assert [r[0] for r in rows[2:-1]] == ["1a", "2a", "14a"]
    assert cells["2a"]["embree robust=false"] == "**FAIL**"
    assert cells["2a"]["embree robust=true"] == "pass"
    assert cells["14a"]["kdtree"] == "error"
    assert cells["1a"]["name"] == "closed-sphere-vertex-rays"
    assert all(cells["1a"][c] == "pass" for c in header[2:])
    totals = rows[-1]
    assert totals[1] == "**not passed**" and totals[2:] == ["0", "0", "0", "1", "1", "0", "0"]
    assert "3 cases x 7 accelerator settings: 19 pass, 1 FAIL, 1 did not complete" in text


def test_failures_list_counts_and_messages(text):
    rows = table(section(text, "Failures")[2:])
    assert [(r[0], r[2], r[3]) for r in rows] == [
        ("2a", "embree robust=false", "FAIL"),
        ("14a", "kdtree", "error"),
    ]
    assert rows[0][4] == EMBREE_LEAKS
    assert "3 rays leaked through vertices at 1.5e5 \\| see case 2" in text
    assert rows[1][5] == "scene rejected: NaN vertex in face 3"


def test_timed_rows(text):
    lines = section(text, "Stiff parameters (timed rows)")
    header = table(lines[:1])[0]
    assert header[:9] == [
        "model",
        "accelerator",
        "status",
        "build (s)",
        "render (s)",
        "nodes",
        "max depth",
        "memory (MiB)",
        "peak RSS (MiB)",
    ]
    assert header[9:15] == ["false misses", "false hits", "wrong prims", "NaN", "t ulp p50", "t ulp max"]
    rows = {r[1]: dict(zip(header, r)) for r in table(lines[2:])}
    kd = rows["kdtree max_depth=100"]
    assert (kd["nodes"], kd["max depth"], kd["peak RSS (MiB)"]) == ("4,000,000", "100", "900")
    assert kd["memory (MiB)"] == "122"  # 4e6 nodes x 32 bytes
    assert (kd["false misses"], kd["t ulp max"]) == ("0", "1")
    assert rows["bvh max_depth=1"]["render (s)"] == "40.0"
    assert rows["embree robust=true"]["nodes"] == "—"
    # One lbvh row: all its parameters label it; the refusal's message is shown.
    lbvh = rows["lbvh bits=1"]
    assert lbvh["status"] == "**error**" and lbvh["build (s)"] == "—"
    assert lbvh["message"].startswith("lbvh: bits=1 is below the minimum 2")
    assert not any(r.startswith("| case-") for r in lines)


def test_case_order_is_numeric():
    models = ["case-14a:x", "case-2b:y", "case-10:z", "case-2a:w", "case-1a:v"]
    assert sorted(models, key=case_sort_key) == [
        "case-1a:v",
        "case-2a:w",
        "case-2b:y",
        "case-10:z",
        "case-14a:x",
    ]


def test_without_case_rows_says_so(tmp_path):
    res = load_results([write_csv(tmp_path / "t.csv", realistic_rows()[:3], with_errors=True)])
    text = robustness_markdown(res)
    assert "No catalogue case rows" in text and "None (no case rows)." in text


def test_cli_robustness_and_all(robust_csv, tmp_path):
    out = tmp_path / "out"
    assert main(["robustness", "--csv", str(robust_csv), "--out", str(out)]) == 0
    assert "**FAIL**" in (out / "robustness.md").read_text()
    assert main(["all", str(robust_csv), "--out", str(tmp_path / "all")]) == 0
    assert (tmp_path / "all" / "tables" / "robustness.md").is_file()
    assert "](tables/robustness.md)" in (tmp_path / "all" / "REPORT.md").read_text()
    assert main(["robustness", "--csv", str(tmp_path / "missing.csv"), "--out", str(out)]) == 2
