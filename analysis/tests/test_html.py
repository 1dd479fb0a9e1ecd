"""The HTML pages' content without a browser: a run's index.html shows every table and
figure of its directory with the analysis's own numbers, the interactive figures carry
the frames the PNGs were drawn from, and `history` collects runs across commits (git's
order, count steps, kept when a run directory goes) with the regression check's verdict."""

from __future__ import annotations

import html
import json
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import pandas as pd
import pytest
from synthetic import BVH, EMBREE, row, write_csv

from accelbench_analysis.cli import main
from accelbench_analysis.outputs.figures.figures import structure_frame
from accelbench_analysis.outputs.pages.markdown_html import to_html

SPECS = ["build_vs_render", "error_pareto", "scaling", "ray_sets", "thread_scaling"]


class Elements(HTMLParser):
    """Every start tag's attributes, in order."""

    def __init__(self, text: str):
        super().__init__()
        self.tags: list[tuple[str, dict]] = []
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))

    def attr(self, name: str, tag: str | None = None) -> list[str]:
        return [a[name] for t, a in self.tags if name in a and (tag is None or t == tag)]


@pytest.fixture(scope="module")
def page(analysed_run):
    return (analysed_run / "index.html").read_text()


def test_every_table_and_figure_of_the_run_is_on_its_page_once(analysed_run, page):
    el = Elements(page)
    shown = el.attr("data-source")
    docs = sorted(f"tables/{p.name}" for p in (analysed_run / "tables").glob("*.md"))
    pngs = sorted(f"figures/{p.name}" for p in (analysed_run / "figures").glob("*.png"))
    assert "tables/ray_sets.md" in docs and "figures/cost-stanford-bunny.png" in pngs
    for d in docs:
        assert shown.count(d) == 1, d
    for p in pngs:
        assert el.attr("data-source", "img").count(p) == 1, p
    images = [s for s in el.attr("src", "img")]
    assert len(images) == len(pngs) and all(s.startswith("data:image/png;base64,") for s in images)
    for name in SPECS:
        assert (analysed_run / "figures" / f"{name}.vl.json").is_file(), name
        assert f"figures/{name}.vl.json" in el.attr("data-source", "div"), name


def test_the_page_follows_report_md_and_its_links_stay_on_the_page_or_in_the_run(analysed_run, page):
    el = Elements(page)
    ids = set(el.attr("id"))
    report = (analysed_run / "REPORT.md").read_text()
    for heading in re.findall(r"^## (.+)$", report, re.M):
        assert re.sub(r"[^a-z0-9]+", "-", heading.lower()).strip("-") in ids, heading
    for href in el.attr("href"):
        assert not href.startswith(("http:", "https:", "//")), href
        if href.startswith("#"):
            assert href[1:] in ids, href
        else:
            assert not href.endswith(".md") or href == "REPORT.md", f"{href} should be shown on the page"
            assert (analysed_run / href).exists(), href
    assert not [s for s in el.attr("src") if not s.startswith("data:")]


def test_the_tables_text_is_the_analysis_text(analysed_run, page):
    """Every plain cell (no Markdown markup) of Tables 4 and 5, the claims, the ray sets and
    thread scaling appears on the page as the Markdown wrote it: the page computes nothing."""
    for name in ("table4.md", "table5.md", "claims.md", "ray_sets.md", "thread_scaling.md"):
        cells = [
            c.strip()
            for line in (analysed_run / "tables" / name).read_text().splitlines()
            if line.startswith("|") and not re.match(r"^\|[-:| ]+\|$", line)
            for c in line.strip("|").split(" | ")
        ]
        plain = [c for c in cells if c and not re.search(r"[*`_\\]|\]\(", c)]
        assert len([c for c in plain if re.match(r"[\d.]", c)]) > 5, name
        for c in plain:
            assert html.escape(c, quote=False) in page, (name, c)


def test_interactive_build_vs_render_carries_the_png_frame(analysed_run, realistic):
    spec = json.loads((analysed_run / "figures" / "build_vs_render.vl.json").read_text())
    points = {
        (v["model"], v["structure"], v["traversal"]): v["render_s_median"] for v in spec["data"]["values"]
    }
    frame = structure_frame(realistic)
    want = {
        (m.replace("\n", " "), s, t): r
        for m, s, t, r in zip(
            frame["model"], frame["structure"], frame["traversal"], frame["render_s_median"]
        )
    }
    assert points == pytest.approx(want)
    assert {"params", "build_s_ci_lo", "render_s_ci_hi"} <= set(spec["data"]["values"][0])


def test_section_rows_start_their_own_tbody():
    text = "| what | a | b |\n|:---|---:|---:|\n| *Build* | | |\n| x | 1 | 2 |\n| *Render* | | |\n| y | 3 | 4 |\n"
    out = to_html(text)
    assert out.count("<tbody>") == 2 and out.count('class="section"') == 2
    assert '<td colspan="3"><em>Build</em></td>' in out
    assert '<td class="num">3</td>' in out and 'class="data"' in out


def test_html_command_rewrites_a_run_page(analysed_run, capsys):
    page = analysed_run / "index.html"
    before = page.read_text()
    page.unlink()
    assert main(["html", str(analysed_run)]) == 0
    assert page.read_text() == before


# ---- history -----------------------------------------------------------------------------------


def git(repo: Path, *args: str) -> str:
    return subprocess.run(
        ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@example.com", *args],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()


def two_commits(tmp_path: Path) -> tuple[Path, str, str]:
    repo = tmp_path / "repo"
    repo.mkdir()
    git(repo, "init", "-q")
    git(repo, "commit", "-q", "--allow-empty", "-m", "first change")
    first = git(repo, "rev-parse", "HEAD")
    git(repo, "commit", "-q", "--allow-empty", "-m", "second change")
    return repo, first, git(repo, "rev-parse", "HEAD")


def bvh_and_embree(sha: str, stamp: str, nodes: int, render: float, config: str = "table4") -> list[dict]:
    prov = {"git_sha": sha, "timestamp": stamp}
    return [
        row(
            "stanford-bunny",
            "bvh",
            BVH,
            build=0.2,
            render=render,
            nodes=nodes,
            prim_tests=5000,
            config=config,
            **prov,
        ),
        row("stanford-bunny", "embree", EMBREE, build=0.1, render=0.5, nodes=40, config=config, **prov),
    ]


def write_inputs(results_csv: Path) -> None:
    """The record of inputs a run writes beside its results (NAME.inputs.csv): not a results file."""
    results_csv.with_name(results_csv.name[:-4] + ".inputs.csv").write_text(
        "kind,sha256,name\nconfig," + "0" * 64 + ",x\n"
    )


def main_run(results: Path, name: str, rows: list[dict], started: str) -> Path:
    d = results / "runs" / name
    (d / "csv").mkdir(parents=True)
    write_csv(d / "csv" / "table4.csv", rows)
    write_inputs(d / "csv" / "table4.csv")
    meta = {
        "job": {"configs": ["table4.yaml"], "tag": ""},
        "started": started,
        "complete": True,
        "provenance": {"git_sha": rows[0]["prov"]["git_sha"], "git_dirty": "false"},
    }
    (d / "run.json").write_text(json.dumps(meta))
    return d


@pytest.fixture
def machine(tmp_path):
    """results/ with two main-job runs, the committed reference run and a regression check;
    the second commit's run measured first (its timestamps are earlier), so only git's
    order puts the commits right."""
    repo, first, second = two_commits(tmp_path)
    results = tmp_path / "results"
    main_run(
        results,
        "20240102T000000Z-first",
        bvh_and_embree(first, "2024-01-02T00:00:00Z", 100, 1.0),
        "2024-01-02",
    )
    main_run(
        results,
        "20240101T000000Z-second",
        bvh_and_embree(second, "2024-01-01T00:00:00Z", 120, 1.5),
        "2024-01-01",
    )
    (results / "reference" / "csv").mkdir(parents=True)
    write_csv(
        results / "reference" / "csv" / "table4.csv", bvh_and_embree(first, "2024-01-03T00:00:00Z", 100, 2.0)
    )
    regress = results / "runs" / "regress"
    regress.mkdir()
    write_csv(regress / "run-1.csv", bvh_and_embree(second, "2024-01-04T00:00:00Z", 120, 1.5, config="ci"))
    write_inputs(regress / "run-1.csv")
    (regress / "report-1.md").write_text("# Regression check: FAIL\n\n- tier 1 failed\n")
    return repo, results, first, second


def run_history(repo: Path, results: Path) -> pd.DataFrame:
    assert main(["history", "--results", str(results), "--repo", str(repo)]) == 0
    return pd.read_csv(results / "history" / "history.csv", dtype={"commit": str})


def test_history_one_row_per_commit_combination_and_measure(machine):
    repo, results, first, second = machine
    h = run_history(repo, results)
    assert not h.duplicated(["commit", "model", "accel", "params", "image_width", "measure"]).any()
    bvh = h[(h["accel"] == "bvh")].set_index(["commit", "measure"])
    # The first commit: run + reference, median of 1.0/0.5 and 2.0/0.5; two rows behind it.
    assert bvh.loc[(first[:7], "trace_ratio_to_embree"), "value"] == pytest.approx(3.0)
    assert bvh.loc[(first[:7], "trace_ratio_to_embree"), "n"] == 2
    assert bvh.loc[(first[:7], "build_ratio_to_embree"), "value"] == pytest.approx(2.0)
    assert bvh.loc[(second[:7], "trace_ratio_to_embree"), "value"] == pytest.approx(3.0)
    assert (
        bvh.loc[(second[:7], "trace_ratio_to_embree"), "runs"] == "runs/20240101T000000Z-second;runs/regress"
    )
    # git's order, though the second commit was measured first
    order = h.drop_duplicates("commit").set_index("commit")["commit_order"]
    assert order[first[:7]] < order[second[:7]]
    assert set(h["subject"]) == {"first change", "second change"}


def test_a_count_that_changes_is_a_step_at_that_commit_only(machine):
    repo, results, first, second = machine
    h = run_history(repo, results)
    steps = h[h["step"]]
    assert set(zip(steps["accel"], steps["measure"], steps["commit"])) == {
        ("bvh", "nodes", second[:7]),
        ("bvh", "leaves", second[:7]),
        ("bvh", "memory_bytes", second[:7]),
    }
    # ratios and times are trends, never steps
    assert not h[h["measure"].str.contains("ratio|_s$")]["step"].any()


def test_history_keeps_runs_whose_directory_is_gone(machine):
    repo, results, first, second = machine
    before = run_history(repo, results)
    shutil.rmtree(results / "runs" / "20240102T000000Z-first")
    after = run_history(repo, results)
    pd.testing.assert_frame_equal(before, after)
    page = (results / "history" / "index.html").read_text()
    assert "(gone; kept in collected.csv)" in page


def test_history_page_heads_with_the_regress_verdict_linking_its_history(machine):
    repo, results, first, second = machine
    run_history(repo, results)
    page = (results / "history" / "index.html").read_text()
    el = Elements(page)
    assert '<span class="verdict fail">FAIL</span>' in page
    assert "#regress" in el.attr("href") and "regress" in el.attr("id")
    assert "../runs/regress/report-1.md" in el.attr("href")
    assert "stanford-bunny · BVH (median)" in el.attr("data-panel")
    verdicts = pd.read_csv(results / "history" / "regress.csv", dtype=str)
    assert list(verdicts["verdict"]) == ["FAIL"] and list(verdicts["commit"]) == [second[:7]]


def test_runs_page_lists_runs_newest_first_with_commits(machine):
    repo, results, first, second = machine
    run_history(repo, results)
    text = (results / "index.html").read_text()
    order = [text.index(n) for n in ("runs/regress", "20240102T000000Z-first", "20240101T000000Z-second")]
    assert order == sorted(order)
    assert first[:7] in text and second[:7] in text and "history/index.html" in text


def test_the_files_beside_a_results_file_are_not_results_of_their_own(machine):
    """NAME.inputs.csv beside a run's and the regression check's results: neither collected
    (nor "left out" as a file that is no harness CSV) nor listed as the check's results."""
    repo, results, first, second = machine
    run_history(repo, results)
    collected = pd.read_csv(results / "history" / "sources.csv", dtype=str)["file"]
    assert not collected.str.endswith(".inputs.csv").any()
    assert collected.str.endswith("run-1.csv").any()
    assert "left out" not in (results / "history" / "index.html").read_text()
    runs = (results / "index.html").read_text()
    assert "run-1.csv" in runs and "run-1.inputs.csv" not in runs
