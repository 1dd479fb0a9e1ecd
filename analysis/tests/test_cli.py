"""The command line end to end: outputs written, REPORT.md content, bad input rejected."""

import pytest
from synthetic import PROVENANCE, header

from accelbench_analysis.cli import main

EXPECTED = [
    "tables/table2.md",
    "tables/table2.tex",
    "tables/table4.md",
    "tables/table4.tex",
    "tables/table5.md",
    "tables/table5.tex",
    "tables/claims.md",
    "figures/build_vs_render.png",
    "figures/error_pareto.png",
    "report/report-tables.csv",
    "report/README.md",
    "REPORT.md",
]


@pytest.fixture(scope="module")
def everything(realistic_csv, tmp_path_factory):
    out = tmp_path_factory.mktemp("out")
    assert main(["all", str(realistic_csv), "--out", str(out)]) == 0
    return out


def test_all_writes_every_output(everything):
    for rel in EXPECTED:
        assert (everything / rel).stat().st_size > 0, rel


def test_report_md_states_provenance_stand_ins_and_regeneration(everything):
    text = (everything / "REPORT.md").read_text()
    assert PROVENANCE["git_sha"] in text and PROVENANCE["cpu"] in text
    assert "RelWithDebInfo" in text and "Embree 3.13.5" in text
    # which instruction set each side ran: ours compiled in (`isa`), Embree's picked at run time
    assert "**ISA:** our structures `sse2+sse4.2+avx+avx2+fma` (compiled for, `isa`); " in text
    assert "Embree's kernels `avx512` (its run-time choice, `embree_isa`)" in text
    assert "**Floating-point mode of the traces:** ftz_daz (" in text
    assert "procedural forest" in text and "procedural city" in text
    assert "Stanford dragon (871,414 triangles" in text and "happy-buddha-100k" in text
    assert "make reproduce-tables" in text
    for rel in ("tables/table4.md", "tables/claims.md", "figures/table2_sweeps.png"):
        assert f"]({rel})" in text
    assert "Warning" not in text


def test_claims_md_has_every_claim(everything):
    text = (everything / "tables" / "claims.md").read_text()
    for cid in ("5.1-b", "5.2-c", "5.3-a", "6-d"):
        assert f"| {cid} |" in text
    assert "do not support: 5.1-b, 5.1-k, 5.3-b" in text


def test_one_claims_summary_in_claims_md_report_md_and_the_page(everything):
    claims = (everything / "tables" / "claims.md").read_text().splitlines()
    start = next(i for i, x in enumerate(claims) if x.startswith("Our default renders are unshaded"))
    end = next(i for i, x in enumerate(claims) if x.startswith("| 6-"))  # the matrix's last rows
    block = "\n".join(claims[start:end])
    assert block in (everything / "REPORT.md").read_text()
    page = (everything / "index.html").read_text()
    for line in claims[start:end]:
        if line.startswith(("| holds |", "| within noise", "| not comparable |")):
            label, default, faithful = (c.strip() for c in line.strip("|").split("|"))
            html = f'<td>{label}</td>\n<td class="num">{default}</td>\n<td class="num">{faithful}</td>'
            assert html in page, label


def test_bad_csv_exits_2_naming_columns(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    cols = [c for c in header() if c not in ("render_s_ci_hi", "git_sha")]
    bad.write_text(",".join(cols) + "\n")
    assert main(["tables", str(bad), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "missing required columns: render_s_ci_hi, git_sha" in err
    assert not (tmp_path / "o").exists()


def test_check_prints_provenance(realistic_csv, capsys):
    assert main(["check", str(realistic_csv)]) == 0
    out = capsys.readouterr().out
    assert "provenance A: commit 0123456789ab" in out and "error columns present" in out
