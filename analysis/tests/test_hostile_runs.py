"""Hostile run folders, each made here: run.json files of the wrong shape or listing paths
outside their folder, cut and unreadable CSVs, two builds of one commit, and Markdown from
data that is raw HTML or links out of the run. Readers skip a bad file with one line naming
it; nothing outside a folder is read, embedded or removed; builds are never one median."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from synthetic import BVH, row, write_csv
from test_reproduce import ACCELBENCH, NOW, tiny_job

from accelbench_analysis.inputs.run_json import read_run_json
from accelbench_analysis.outputs.ci.history import update
from accelbench_analysis.outputs.pages.markdown_html import confined, to_html
from accelbench_analysis.outputs.pages.runs_page import runs_page_html
from accelbench_analysis.reproduce.job import reproduce
from accelbench_analysis.reproduce.runs import RUN_JSON, ReproduceError, prepare_into

JOB = {"configs": ["table4.yaml"], "tag": ""}


def test_into_refuses_run_json_paths_outside_its_folder(tmp_path):
    outside = tmp_path / "outside"
    (outside / "empty").mkdir(parents=True)
    (outside / "keep.txt").write_text("not the driver's")
    into = tmp_path / "into"
    (into / "csv").mkdir(parents=True)
    (into / "csv" / "t.csv").write_text("x")
    (into / "link").symlink_to(outside)
    for written in (
        ["../outside/empty/x"],
        [str(outside / "keep.txt")],
        ["link/keep.txt"],
        [5],
        ["csv/t.csv", ""],
    ):
        (into / RUN_JSON).write_text(json.dumps({"job": JOB, "written": written}))
        with pytest.raises(ReproduceError, match="not files inside it"):
            prepare_into(into)
        assert (outside / "empty").is_dir() and (outside / "keep.txt").read_text() == "not the driver's"
        assert (into / "csv" / "t.csv").is_file()  # nothing removed before the refusal


@pytest.mark.parametrize(
    "text, why",
    [("[1, 2]", "a JSON list, not an object"), ('{"job": ', "JSONDecodeError"), ("\xff", "")],
)
def test_a_run_json_of_the_wrong_shape_is_skipped_and_named(tmp_path, capsys, text, why):
    (tmp_path / RUN_JSON).write_text(text, encoding="latin-1")
    assert read_run_json(tmp_path) is None
    err = capsys.readouterr().err
    assert err.startswith(f"skipped {tmp_path / RUN_JSON}: ") and why in err and err.count("\n") == 1


def results_with_one_bad_run_of_each_kind(tmp_path: Path) -> Path:
    results = tmp_path / "results"
    runs = results / "runs"
    good = runs / "20261201T100000Z-aaaaaaa"
    (good / "csv").mkdir(parents=True)
    rows = [row("stanford-bunny", "bvh", BVH, build=0.1, render=0.2, nodes=9, prim_tests=100)]
    rows.append(row("stanford-bunny", "embree", {"threads": "1"}, build=0.05, render=0.1))
    write_csv(good / "csv" / "table4.csv", rows)
    (good / RUN_JSON).write_text(
        json.dumps({"job": JOB, "provenance": {"git_sha": "a" * 40}, "complete": True})
    )
    shapes = {
        "20261201T110000Z-bbbbbbb": "[1, 2, 3]",  # not an object
        "20261201T120000Z-ccccccc": '{"job": "x", "provenance": [1], "started": 5, "complete": "yes"}',
        "20261201T130000Z-ddddddd": '{"job": {"configs": ',  # cut
    }
    for name, text in shapes.items():
        (runs / name / "csv").mkdir(parents=True)
        (runs / name / RUN_JSON).write_text(text)
    # A cut CSV, a header-only partial run and bytes that are no text, each in a run of its own.
    cut = runs / "20261201T140000Z-eeeeeee"
    (cut / "csv").mkdir(parents=True)
    write_csv(cut / "csv" / "table4.csv", rows)
    text = (cut / "csv" / "table4.csv").read_text()
    (cut / "csv" / "table4.csv").write_text(text[: len(text) - 40])
    (cut / RUN_JSON).write_text(json.dumps({"job": JOB, "complete": False}))
    partial = runs / "20261201T150000Z-fffffff"
    (partial / "csv").mkdir(parents=True)
    (partial / "csv" / "table4.csv").write_text(text.splitlines()[0] + "\n")
    (partial / RUN_JSON).write_text(json.dumps({"job": JOB, "complete": False}))
    regress = runs / "regress"  # its newest report's run is header-only
    regress.mkdir(parents=True)
    (regress / "report-1.md").write_text("# Regression check: PASS\n")
    (regress / "run-1.csv").write_text("git_sha,git_dirty,timestamp\n")
    garbage = runs / "slurm-x"
    garbage.mkdir(parents=True)
    (garbage / "out.csv").write_bytes(b"\xff\xfe\x00garbage\x00\n\x80")
    return results


def test_runs_page_and_history_skip_each_bad_file_and_name_it(tmp_path, capsys):
    results = results_with_one_bad_run_of_each_kind(tmp_path)
    page = runs_page_html(results)
    err = capsys.readouterr().err
    assert "20261201T100000Z-aaaaaaa" in page and "aaaaaaa" in page
    assert f"skipped {results / 'runs/20261201T110000Z-bbbbbbb' / RUN_JSON}: a JSON list" in err
    assert f"skipped {results / 'runs/20261201T130000Z-ddddddd' / RUN_JSON}: JSONDecodeError" in err
    assert f"skipped {results / 'runs/slurm-x/out.csv'}: UnicodeDecodeError" in err
    c = update(results, tmp_path / "history", tmp_path)
    assert f"skipped {results / 'runs/regress/run-1.csv'}: the regression check's verdict left out" in (
        capsys.readouterr().err
    )
    notes = "\n".join(c.notes)
    for bad in (
        "slurm-x/out.csv",
        "20261201T140000Z-eeeeeee/csv/table4.csv",
        "20261201T150000Z-fffffff/csv/table4.csv",
    ):
        assert "left out " + str(results / "runs" / bad) in notes
    assert len(c.rows) == 2  # the good run's
    assert (tmp_path / "history" / "history.csv").is_file()


@pytest.mark.parametrize(
    "field, values",
    [("build_type", ("Release", "Debug")), ("compile_flags", ("-O2 -g", "-O3 -g -march=native"))],
)
def test_history_keeps_two_builds_of_one_commit_apart(tmp_path, field, values):
    results = tmp_path / "results"
    for name, value, render in (("a", values[0], 0.2), ("b", values[1], 2.0)):
        d = results / "runs" / f"slurm-{name}"
        d.mkdir(parents=True)
        rows = [
            row("stanford-bunny", "bvh", BVH, build=0.1, render=render, nodes=9, **{field: value}),
            row("stanford-bunny", "embree", {"threads": "1"}, build=0.05, render=0.1, **{field: value}),
        ]
        write_csv(d / "r.csv", rows)
    c = update(results, tmp_path / "history", tmp_path)
    h = c.history[(c.history["measure"] == "render_s") & (c.history["accel"] == "bvh")]
    assert sorted(h["value"]) == [0.2, 2.0]  # two medians, not one of both
    assert h["commit"].nunique() == 1 and h["build"].nunique() == 2
    assert all((values[0] in s) != (values[1] in s) for s in h["series"])


def test_history_collected_before_the_flags_keeps_those_rows_apart(tmp_path):
    results = tmp_path / "results"
    d = results / "runs" / "slurm-a"
    d.mkdir(parents=True)
    rows = [
        row("stanford-bunny", "bvh", BVH, build=0.1, render=0.2, nodes=9),
        row("stanford-bunny", "embree", {"threads": "1"}, build=0.05, render=0.1),
    ]
    write_csv(d / "r.csv", rows)
    out = tmp_path / "history"
    update(results, out, tmp_path)
    # The store as a history from before the column wrote it, then a new run of a known build.
    store = pd.read_csv(out / "collected.csv", dtype=str, keep_default_na=False)
    store.drop(columns=["compile_flags"]).to_csv(out / "collected.csv", index=False)
    d = results / "runs" / "slurm-b"
    d.mkdir(parents=True)
    write_csv(d / "r.csv", rows)
    c = update(results, out, tmp_path)
    assert sorted(set(c.rows["compile_flags"])) == sorted({"unknown", rows[0]["prov"]["compile_flags"]})
    h = c.history[(c.history["measure"] == "render_s") & (c.history["accel"] == "bvh")]
    assert len(h) == 2 and h["build"].nunique() == 2


def test_markdown_from_data_is_text_and_its_links_stay_inside():
    label = "<script>alert(1)</script><img src=x onerror=alert(2)> [x](javascript:alert(3)) [y](../../etc.md)"
    out = to_html(f"| structure |\n|---|\n| {label} |\n\n<div onclick=alert(4)>d</div>")
    assert "<script" not in out and "<img" not in out and "<div onclick" not in out
    assert "&lt;script&gt;" in out and "href" not in out
    assert [
        confined(h) for h in ("#a", "https://x", "tables/a.md", "a/../b.md", "../a.md", "/etc", "file:x")
    ] == [
        True,
        True,
        True,
        True,
        False,
        False,
        False,
    ]


def test_the_page_writer_under_an_address_space_limit_writes_its_page(tmp_path):
    """Under `ulimit -v` 16 GiB vl-convert's V8 cannot start: one line says so, the page is
    written all the same (its figures undrawn), and the process is not killed."""
    code = (
        "from pathlib import Path; from accelbench_analysis.outputs.pages.page import page, write_page;"
        f"write_page(Path({str(tmp_path / 'p.html')!r}), page('t', '<p>x</p>', charts=True))"
    )
    done = subprocess.run(
        ["bash", "-c", f'ulimit -v {16 * 2**20} && exec "$0" -c "$1"', sys.executable, code],
        capture_output=True,
        text=True,
        cwd=Path(__file__).resolve().parents[1],
    )
    assert done.returncode == 0, done.stderr
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "interactive figures left undrawn" in lines[0] and "16.0 GiB" in lines[0]
    assert "<p>x</p>" in (tmp_path / "p.html").read_text()


@pytest.mark.skipif(not ACCELBENCH.is_file(), reason=f"{ACCELBENCH} not built")
def test_a_job_beside_corrupt_runs_measures_writes_its_pages_and_names_them(tmp_path, capfd):
    """Other run folders with a run.json of the wrong shape, one of this very job with
    fields of the wrong types, and a cut CSV: the job measures, writes the runs page, exits
    0 and names each file it skipped."""
    job = tiny_job(tmp_path)
    runs = job.runs
    bad = {
        "20240101T000000Z-aaaaaaa": "[1]",
        "20240101T000001Z-bbbbbbb": json.dumps(
            {"job": {"configs": ["tiny.yaml", "second.yaml"], "tag": ""}, "provenance": [], "continued": 3}
        ),
    }
    for name, text in bad.items():
        (runs / name / "csv").mkdir(parents=True)
        (runs / name / RUN_JSON).write_text(text)
    (runs / "20240101T000001Z-bbbbbbb" / "csv" / "tiny.csv").write_bytes(b"config,combo\n\xff\xfe")
    rc, run_dir = reproduce(job, NOW)
    assert rc == 0 and run_dir.name not in bad
    err = capfd.readouterr().err
    assert f"skipped {runs / '20240101T000000Z-aaaaaaa' / RUN_JSON}: a JSON list, not an object" in err
    assert "another build or machine" in err  # the unfinished run of this job: provenance unknown
    assert run_dir.name in (runs.parent / "index.html").read_text()
