"""The main job's driver (reproduce.py): a run directory per invocation, resuming only an
unfinished run of the same build, the job's progress line, the reference run's clean-tree
rule; and the three-way comparison (report / this run / reference run) with the claims'
machine-dependent verdicts."""

from __future__ import annotations

import json
import subprocess
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest
from synthetic import BVH, KD, LBVH, row, write_csv

from accelbench_analysis.cli import main
from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.outputs.report.claims import FAILS, HOLDS, evaluate_all
from accelbench_analysis.outputs.report.comparison import three_way
from accelbench_analysis.reproduce.job import Job, Progress, reproduce
from accelbench_analysis.reproduce.runs import (
    RUN_JSON,
    ReproduceError,
    csv_rows,
    decide,
    inputs_differences,
    prepare_into,
    provenance_differences,
    tree_changes,
)

REPO = Path(__file__).resolve().parents[2]
ACCELBENCH = REPO / "build" / "accelbench"
NOW = datetime(2026, 12, 1, 20, 0, 0, tzinfo=UTC)
PROV = {
    "git_sha": "a" * 40,
    "git_dirty": "false",
    "compiler": "gcc 12.2.0",
    "build_type": "RelWithDebInfo",
    "cpu": "AMD EPYC",
    "embree_version": "3.13.5",
}
JOB = {"configs": ["tiny.yaml"], "tag": ""}


# ---- the resume decision on crafted run directories ------------------------------------------


def make_run(runs: Path, name: str, *, complete: bool, prov=PROV, job=JOB, started="") -> Path:
    d = runs / name
    (d / "csv").mkdir(parents=True)
    (d / RUN_JSON).write_text(
        json.dumps(
            {
                "job": job,
                "provenance": prov,
                "complete": complete,
                "started": started or name,
                "continued": [],
            }
        )
    )
    return d


def test_provenance_differences_name_fields_and_absent_ones():
    assert provenance_differences(PROV, dict(PROV)) == []
    newer = dict(PROV, isa="avx2", cpu="Intel Xeon")
    assert provenance_differences(PROV, newer) == ["isa: (absent) -> avx2", "cpu: AMD EPYC -> Intel Xeon"]
    assert provenance_differences(dict(PROV, isa="sse2"), PROV) == ["isa: sse2 -> (absent)"]


def test_decide_resumes_only_an_unfinished_run_of_the_same_build_and_job(tmp_path):
    runs = tmp_path / "runs"
    d = decide(runs, JOB, PROV, False, NOW)
    assert not d.resume and "no earlier run" in d.reason
    assert d.run_dir.name == "20261201T200000Z-aaaaaaa"

    old = make_run(runs, "20261130T100000Z-aaaaaaa", complete=True)
    d = decide(runs, JOB, PROV, False, NOW)
    assert not d.resume and "complete" in d.reason and d.run_dir != old

    unfinished = make_run(runs, "20261201T100000Z-aaaaaaa", complete=False)
    d = decide(runs, JOB, PROV, False, NOW)
    assert d.resume and d.run_dir == unfinished and "provenance matches" in d.reason
    assert not decide(runs, JOB, PROV, True, NOW).resume  # FRESH=1

    # Another build (the dirty flag, or a column only one build records) starts afresh.
    for other, said in (
        (dict(PROV, git_dirty="true"), "git_dirty: false -> true"),
        (dict(PROV, isa="avx2"), "isa: (absent) -> avx2"),
    ):
        d = decide(runs, JOB, other, False, NOW)
        assert not d.resume and said in d.reason and d.run_dir != unfinished

    # A newer run of another job (QUICK's configs) does not hide this job's unfinished run.
    make_run(
        runs,
        "20261201T150000Z-aaaaaaa-quick",
        complete=False,
        job={"configs": ["quick.yaml"], "tag": "quick"},
    )
    assert decide(runs, JOB, PROV, False, NOW).run_dir == unfinished
    # The newest run of the job decides: a finished one after the unfinished one wins.
    make_run(runs, "20261201T160000Z-aaaaaaa", complete=True)
    assert not decide(runs, JOB, PROV, False, NOW).resume


INPUTS = {"tiny.yaml": [["config", "1" * 64, "tiny"], ["model", "2" * 64, "mesh.obj"]]}


def test_decide_continues_only_a_run_of_the_same_contents(tmp_path):
    runs = tmp_path / "runs"
    d = make_run(runs, "20261201T100000Z-aaaaaaa", complete=False)
    meta = json.loads((d / RUN_JSON).read_text())
    (d / RUN_JSON).write_text(json.dumps(dict(meta, inputs=INPUTS)))
    # No rows yet: nothing can mix, the run is continued whatever the contents.
    other = {"tiny.yaml": [["config", "1" * 64, "tiny"], ["model", "3" * 64, "mesh.obj"]]}
    assert decide(runs, JOB, PROV, False, NOW, other).resume
    (d / "csv" / "tiny.csv").write_text("config,combo_id\ntiny,1\n")
    assert decide(runs, JOB, PROV, False, NOW, INPUTS).resume
    # The same config name, a model file of other contents: a new run, saying which.
    new = decide(runs, JOB, PROV, False, NOW, other)
    assert not new.resume and new.run_dir != d
    assert "tiny.yaml: model mesh.obj: sha256 222222222222 then, 333333333333 now" in new.reason
    edited = {"tiny.yaml": [["config", "4" * 64, "tiny"], *INPUTS["tiny.yaml"][1:]]}
    assert (
        "config tiny: sha256 111111111111 then, 444444444444 now"
        in decide(runs, JOB, PROV, False, NOW, edited).reason
    )
    # A run that recorded no inputs (an older driver) with rows: its contents are unknown.
    (d / RUN_JSON).write_text(json.dumps(meta))
    assert not decide(runs, JOB, PROV, False, NOW, INPUTS).resume
    assert inputs_differences(INPUTS, INPUTS) == []
    assert inputs_differences(INPUTS, {}) == [
        "tiny.yaml: config tiny: only then",
        "tiny.yaml: model mesh.obj: only then",
    ]


def test_progress_line_counts_over_all_configs():
    p = Progress(total=40, done_before=10)
    p.start -= 30  # 30 s into this invocation
    assert p.line(10) == "reproduce: 10/40 combinations (25%) over all configs, elapsed 0:30"
    # 10 combinations in 30 s here, 20 to go: about a minute.
    assert p.line(20) == (
        "reproduce: 20/40 combinations (50%) over all configs, elapsed 0:30, about 1:00 left"
    )
    assert "left" not in p.line(40)


def test_csv_rows_ignores_a_cut_line(tmp_path):
    f = tmp_path / "r.csv"
    f.write_text('a,b\n1,"x\ny"\n2,z\n3,')
    assert csv_rows(f) == 2
    assert csv_rows(tmp_path / "none.csv") == 0


# ---- the driver with the real harness ------------------------------------------------------

needs_binary = pytest.mark.skipif(not ACCELBENCH.is_file(), reason=f"{ACCELBENCH} not built")

TINY = """name: {name}
repetitions: 1
warmup: 1
timeout_s: 60
render: {{width: 32, height: 24, spp: 1, light: true, shading: false, threads: 1}}
models:
  - {model}
accelerators:
  - {{name: bvh}}
  - {{name: lbvh}}
"""
# Two triangles: a valid mesh; MESH_BAD refers to a vertex the file does not have, so the
# harness refuses the model at load, writes no rows and exits 2 (an interrupted job).
MESH_GOOD = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n"
MESH_BAD = "v 0 0 0\nv 1 0 0\nf 1 2 9\n"


def tiny_job(tmp_path: Path, broken: bool = False) -> Job:
    first = tmp_path / "tiny.yaml"
    first.write_text(TINY.format(name="tiny", model="{procedural: soup, triangles: 200, seed: 1}"))
    mesh = tmp_path / "mesh.obj"
    mesh.write_text(MESH_BAD if broken else MESH_GOOD)
    second = tmp_path / "second.yaml"
    second.write_text(TINY.format(name="second", model=f"{{path: {mesh}}}"))
    return Job(
        accelbench=ACCELBENCH,
        configs=[first, second],
        runs=tmp_path / "runs",
        latest=tmp_path / "latest",
        analyse=False,
    )


def run_json(d: Path) -> dict:
    return json.loads((d / RUN_JSON).read_text())


def timestamps(csv: Path) -> list[str]:
    return sorted(load_results([csv]).rows["timestamp"])


@needs_binary
def test_every_invocation_measures_into_a_new_run_directory(tmp_path, capfd):
    rc, first = reproduce(tiny_job(tmp_path), NOW)
    assert rc == 0
    assert csv_rows(first / "csv" / "tiny.csv") == 2 and csv_rows(first / "csv" / "second.csv") == 2
    meta = run_json(first)
    assert meta["complete"] and meta["job"] == {"configs": ["tiny.yaml", "second.yaml"], "tag": ""}
    assert meta["provenance"]["git_sha"] == load_results([first / "csv" / "tiny.csv"]).rows["git_sha"].iloc[0]
    assert (tmp_path / "latest").resolve() == first.resolve()
    err = capfd.readouterr().err
    assert "reproduce: 4/4 combinations (100%) over all configs" in err
    assert "reproduce: 1/4 combinations" in err and "[1/2] " in err  # the harness's lines too

    rc, second = reproduce(tiny_job(tmp_path), NOW + timedelta(seconds=1))
    assert rc == 0 and second != first
    assert "is complete" in capfd.readouterr().err
    assert csv_rows(second / "csv" / "tiny.csv") == 2  # measured again, not resumed
    assert (tmp_path / "latest").resolve() == second.resolve()


@needs_binary
def test_an_interrupted_run_continues_with_the_same_build_only(tmp_path, capfd):
    rc, run = reproduce(tiny_job(tmp_path, broken=True), NOW)
    assert rc == 2 and not run_json(run)["complete"] and not (tmp_path / "latest").exists()
    measured = timestamps(run / "csv" / "tiny.csv")
    capfd.readouterr()

    # Same build, same machine: the unfinished run is continued, its rows kept.
    rc, again = reproduce(tiny_job(tmp_path), NOW + timedelta(minutes=1))
    assert rc == 0 and again == run
    err = capfd.readouterr().err
    assert "continuing" in err and "provenance matches" in err
    assert "2 already in" in err
    assert timestamps(run / "csv" / "tiny.csv") == measured
    assert csv_rows(run / "csv" / "second.csv") == 2 and run_json(run)["complete"]

    # An unfinished run recorded by another build is not continued.
    rc, other = reproduce(tiny_job(tmp_path, broken=True), NOW + timedelta(minutes=2))
    assert rc == 2
    meta = run_json(other)
    meta["provenance"]["git_sha"] = "0" * 40
    (other / RUN_JSON).write_text(json.dumps(meta))
    capfd.readouterr()
    rc, fresh = reproduce(tiny_job(tmp_path), NOW + timedelta(minutes=3))
    assert rc == 0 and fresh not in (run, other)
    assert "git_sha: " + "0" * 40 in capfd.readouterr().err
    assert csv_rows(fresh / "csv" / "tiny.csv") == 2


@needs_binary
def test_a_run_of_other_contents_under_the_same_names_is_not_continued(tmp_path, capfd):
    rc, run = reproduce(tiny_job(tmp_path, broken=True), NOW)
    assert rc == 2 and csv_rows(run / "csv" / "tiny.csv") == 2
    assert [k for k, _, _ in run_json(run)["inputs"]["second.yaml"]] == ["config", "model"]
    # tiny.yaml has rows; the same file name with another structure in it starts afresh.
    config = tmp_path / "tiny.yaml"
    config.write_text(config.read_text().replace("{name: lbvh}", "{name: kdtree}"))
    (tmp_path / "mesh.obj").write_text(MESH_GOOD)
    capfd.readouterr()
    rc, fresh = reproduce(tiny_job_configs(tmp_path), NOW + timedelta(minutes=1))
    assert rc == 0 and fresh != run
    assert (
        "measured from other contents under the same names (tiny.yaml: config tiny: sha256"
        in capfd.readouterr().err
    )
    accels = sorted(load_results([fresh / "csv" / "tiny.csv"]).rows["accel"])
    assert accels == ["bvh", "kdtree"]  # not the earlier run's lbvh row beside them

    # A mesh file given by path and changed after its rows were measured.
    rc, done = reproduce(tiny_job_configs(tmp_path), NOW + timedelta(minutes=2))
    meta = run_json(done)
    meta["complete"] = False
    (done / RUN_JSON).write_text(json.dumps(meta))
    (tmp_path / "mesh.obj").write_text(MESH_GOOD + "v 2 2 0\nf 2 5 4\n")
    capfd.readouterr()
    rc, after = reproduce(tiny_job_configs(tmp_path), NOW + timedelta(minutes=3))
    assert rc == 0 and after != done
    assert "second.yaml: model " in capfd.readouterr().err
    assert set(load_results([after / "csv" / "second.csv"]).rows["triangles"]) == {3}


def tiny_job_configs(tmp_path: Path) -> Job:
    """tiny_job's configs as they are now in tmp_path (not rewritten)."""
    return Job(
        accelbench=ACCELBENCH,
        configs=[tmp_path / "tiny.yaml", tmp_path / "second.yaml"],
        runs=tmp_path / "runs",
        latest=tmp_path / "latest",
        analyse=False,
    )


@needs_binary
def test_a_config_the_harness_refuses_is_its_message_before_anything_is_written(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: bad\nmodels: [stanford-bunny]\naccelerators: [{name: nope}]\n")
    good = tmp_path / "tiny.yaml"
    good.write_text(TINY.format(name="tiny", model="{procedural: soup, triangles: 200, seed: 1}"))
    rc = main(
        [
            "reproduce",
            str(good),
            str(bad),
            "--accelbench",
            str(ACCELBENCH),
            "--runs",
            str(tmp_path / "runs"),
            "--latest",
            str(tmp_path / "latest"),
        ]
    )
    err = capsys.readouterr().err
    assert rc == 2
    assert "unknown accelerator 'nope'" in err and "Traceback" not in err and "CalledProcessError" not in err
    assert not (tmp_path / "runs").exists()  # nothing measured, no run directory


@needs_binary
def test_a_tag_with_a_dash_continues_and_a_tag_that_is_no_name_is_refused(tmp_path, capfd):
    job = tiny_job(tmp_path, broken=True)
    job.tag = "my-tag.2"
    rc, run = reproduce(job, NOW)
    assert rc == 2 and run.name.endswith("-my-tag.2")
    job = tiny_job(tmp_path)
    job.tag = "my-tag.2"
    capfd.readouterr()
    rc, again = reproduce(job, NOW + timedelta(minutes=1))
    assert rc == 0 and again == run and "continuing" in capfd.readouterr().err
    for bad in ("a/b", "..", "-x"):
        job.tag = bad
        assert reproduce(job, NOW)[0] == 2
        assert "--tag" in capfd.readouterr().err


@needs_binary
def test_a_cost_images_command_that_does_not_exist_is_named(tmp_path):
    job = tiny_job(tmp_path)
    job.analyse, job.cost_images = True, [str(tmp_path / "no-such-script.sh")]
    with pytest.raises(ReproduceError, match="cannot run the cost images command .*no-such-script.sh"):
        reproduce(job, NOW)


def test_a_directory_where_latest_belongs_is_refused_before_measuring(tmp_path, capsys):
    (tmp_path / "latest").mkdir()
    (tmp_path / "latest" / "mine.txt").write_text("keep")
    config = tmp_path / "tiny.yaml"
    config.write_text("name: tiny\n")
    job = Job(
        accelbench=tmp_path / "no-such-binary",
        configs=[config, tmp_path / "other" / "tiny.yaml"],
        runs=tmp_path / "runs",
        latest=tmp_path / "latest",
    )
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "tiny.yaml").write_text("name: tiny\n")
    rc, _ = reproduce(job, NOW)
    err = capsys.readouterr().err
    assert rc == 2 and "nothing measured" in err
    assert f"{tmp_path / 'latest'} is a directory, not the link" in err
    assert "would both write csv/tiny.csv" in err
    assert (tmp_path / "latest" / "mine.txt").read_text() == "keep" and not (tmp_path / "runs").exists()


def test_a_directory_where_a_page_belongs_is_refused_before_measuring(tmp_path, capsys):
    """results/index.html (the runs page, written when the job ends) and a run's own
    index.html: a directory there ended the job in a traceback after measuring."""
    config = tmp_path / "tiny.yaml"
    config.write_text("name: tiny\n")
    (tmp_path / "results" / "index.html").mkdir(parents=True)
    (tmp_path / "ref" / "index.html").mkdir(parents=True)
    for into in (None, tmp_path / "ref"):
        job = Job(
            accelbench=tmp_path / "no-such-binary",
            configs=[config],
            runs=tmp_path / "results" / "runs",
            latest=tmp_path / "results" / "latest",
            into=into,
        )
        rc, _ = reproduce(job, NOW)
        err = capsys.readouterr().err
        assert rc == 2 and "nothing measured" in err
        assert f"{tmp_path / 'results' / 'index.html'} is a directory" in err
        if into is not None:
            assert f"{into / 'index.html'} is not a file" in err
    assert not (tmp_path / "results" / "runs").exists()


def test_into_removes_only_what_the_driver_wrote(tmp_path):
    into = tmp_path / "results"
    (into / "runs" / "20261201T100000Z-aaaaaaa").mkdir(parents=True)
    (into / "runs" / "20261201T100000Z-aaaaaaa" / "table4.csv").write_text("a run")
    (into / "csv").mkdir()
    (into / "csv" / "mine.csv").write_text("mine")
    with pytest.raises(ReproduceError, match="holds files this driver did not write"):
        prepare_into(into)
    assert (into / "runs" / "20261201T100000Z-aaaaaaa" / "table4.csv").read_text() == "a run"

    # A directory an earlier run wrote: its run.json lists what; everything else stays.
    ref = tmp_path / "reference"
    for rel in ("csv/table4.csv", "tables/table4.md", "figures/a.png", "README.md", "tables/notes.md"):
        (ref / rel).parent.mkdir(parents=True, exist_ok=True)
        (ref / rel).write_text(rel)
    written = ["csv/table4.csv", "figures/a.png", RUN_JSON, "tables/table4.md"]
    (ref / RUN_JSON).write_text(json.dumps({"job": JOB, "written": written}))
    assert prepare_into(ref) == {"README.md", "tables/notes.md"}
    assert sorted(str(p.relative_to(ref)) for p in ref.rglob("*")) == [
        "README.md",
        "tables",
        "tables/notes.md",
    ]
    assert prepare_into(tmp_path / "new" / "dir") == set() and (tmp_path / "new" / "dir").is_dir()
    (tmp_path / "file").write_text("x")
    with pytest.raises(ReproduceError, match="not a directory"):
        prepare_into(tmp_path / "file")


@needs_binary
def test_into_records_what_it_wrote_and_keeps_the_rest(tmp_path):
    job = tiny_job(tmp_path)
    job.into = tmp_path / "ref"
    job.into.mkdir()
    rc, run = reproduce(job, NOW)
    assert rc == 0 and run == job.into
    written = run_json(run)["written"]
    assert "csv/tiny.csv" in written and "csv/tiny.inputs.csv" in written and RUN_JSON in written
    (run / "README.md").write_text("by hand")
    rc, again = reproduce(job, NOW + timedelta(minutes=1))
    assert rc == 0 and (run / "README.md").read_text() == "by hand"
    assert "README.md" not in run_json(run)["written"]


# ---- the reference run's clean-tree rule ------------------------------------------------------


def git(repo: Path, *args: str) -> None:
    subprocess.run(
        ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t", *args],
        check=True,
        capture_output=True,
    )


def test_reference_run_refuses_a_dirty_tree(tmp_path, monkeypatch, capsys):
    repo = tmp_path / "repo"
    repo.mkdir()
    git(repo, "init", "-q")
    (repo / "code.cpp").write_text("int main() {}\n")
    git(repo, "add", "code.cpp")
    git(repo, "commit", "-q", "-m", "code")
    config = repo / "c.yaml"
    config.write_text("name: c\n")  # untracked: not a change to committed code
    assert tree_changes(repo) == []
    (repo / "code.cpp").write_text("int main() { return 1; }\n")
    assert tree_changes(repo) == [" M code.cpp"]

    monkeypatch.chdir(repo)
    rc = main(
        [
            "reproduce",
            str(config),
            "--into",
            str(repo / "reference"),
            "--require-clean-tree",
            "--accelbench",
            str(repo / "no-such-binary"),
        ]
    )
    assert rc == 2
    err = capsys.readouterr().err
    assert "uncommitted changes" in err and "code.cpp" in err
    assert not (repo / "reference").exists()  # refused before anything was written
    with pytest.raises(RuntimeError, match="not a git work tree"):
        tree_changes(tmp_path)


# ---- the three-way comparison and the claims' second verdict ---------------------------------


def bvh_lbvh_kd(render_bvh: float, render_kd: float, cpu: str) -> list[dict]:
    return [
        row("stanford-bunny", "bvh", BVH, build=0.1, render=render_bvh, nodes=1001, cpu=cpu),
        row("stanford-bunny", "lbvh", LBVH, build=0.2, render=1.0, nodes=999, cpu=cpu),
        row("stanford-bunny", "kdtree", KD, build=0.9, render=render_kd, nodes=5000, cpu=cpu),
    ]


def test_three_way_values_and_ratios(tmp_path, report_nums):
    (tmp_path / "this").mkdir()
    (tmp_path / "ref" / "csv").mkdir(parents=True)
    this = load_results([write_csv(tmp_path / "this" / "table4.csv", bvh_lbvh_kd(2.0, 0.5, "This CPU"))])
    ref = load_results(
        [write_csv(tmp_path / "ref" / "csv" / "table4.csv", bvh_lbvh_kd(1.0, 0.8, "Reference CPU"))]
    )
    rows = {(r.metric, r.model, r.structure): r for r in three_way(this, ref, report_nums)}
    bvh = rows[("render", "Stanford bunny", "BVH (median)")]
    report_bvh = float(
        report_nums.query("model == 'stanford-bunny' and accelerator == 'bvh' and setting == 'default'")[
            "render_s"
        ].iloc[0]
    )
    assert (bvh.report, bvh.this, bvh.reference) == (report_bvh, 2.0, 1.0)
    assert bvh.this_over_reference == pytest.approx(2.0)
    assert bvh.this_over_report == pytest.approx(2.0 / report_bvh)
    kd_nodes = rows[("nodes", "Stanford bunny", "kd-tree")]
    assert (kd_nodes.this, kd_nodes.reference, kd_nodes.this_over_reference) == (5000, 5000, 1.0)
    # Only cells someone measured: Igea has no rows in either run.
    assert not any(m.startswith("Igea") for _, m, _ in rows)
    # Without a reference run the reference column is empty, the report's still there.
    alone = {(r.metric, r.model, r.structure): r for r in three_way(this, None, report_nums)}
    assert alone[("render", "Stanford bunny", "BVH (median)")].reference is None
    assert alone[("render", "Stanford bunny", "BVH (median)")].report == report_bvh

    # Through the command line: REPORT.md shows the three values and ratios, comparison.md
    # the counts, claims.md the reference run's verdict and the machine-dependent flag.
    out = tmp_path / "out"
    assert (
        main(
            [
                "report",
                str(tmp_path / "this" / "table4.csv"),
                "--out",
                str(out),
                "--reference-run",
                str(tmp_path / "ref"),
            ]
        )
        == 0
    )
    report = (out / "REPORT.md").read_text()
    assert "| Stanford bunny | BVH (median) | " + f"{report_bvh:.3g}" + " | 2.00 | 1.00 |" in report
    assert "Reference CPU" in report
    assert "| Stanford bunny | kd-tree | " in (out / "tables" / "comparison.md").read_text()


def test_reference_run_claims_skip_its_ray_set_rows(tmp_path):
    # Both runs hold 5.2-a on their camera rows. The reference run's ray-set CSV has newer LBVH
    # rows of the same structures that build in a twentieth of the time; judged with them,
    # the reference run would seem to fail 5.2-a and the claim be flagged machine-dependent.
    this_dir, ref_dir = tmp_path / "this", tmp_path / "ref" / "csv"
    this_dir.mkdir()
    ref_dir.mkdir(parents=True)
    for d, cpu in ((this_dir, "This CPU"), (ref_dir, "Reference CPU")):
        write_csv(d / "table4.csv", table4_rows(0.2, cpu))
        rays = [
            row(
                m,
                "lbvh",
                LBVH,
                build=0.01,
                render=0.1,
                cpu=cpu,
                config="ray-sets",
                timestamp="2024-02-01T00:00:00Z",
                extra={"ray_set": "primary"},
            )
            for m in ("stanford-bunny", "igea", "stanford-dragon", "happy-buddha-100k")
        ]
        write_csv(d / "ray-sets.csv", rays, extra_columns=("ray_set",))
    out = tmp_path / "out"
    csvs = [str(this_dir / "table4.csv"), str(this_dir / "ray-sets.csv")]
    assert main(["claims", *csvs, "--out", str(out), "--reference-run", str(tmp_path / "ref")]) == 0
    line = next(
        x for x in (out / "tables" / "claims.md").read_text().splitlines() if x.startswith("| 5.2-a |")
    )
    assert line.endswith("| holds |  |")


def table4_rows(lbvh_build: float, cpu: str) -> list[dict]:
    out = []
    for m, f in (("stanford-bunny", 1.0), ("igea", 4.0), ("stanford-dragon", 12), ("happy-buddha-100k", 2)):
        out += [
            row(m, "bvh", BVH, build=0.1 * f, render=1.0 * f, cpu=cpu),
            row(m, "lbvh", LBVH, build=lbvh_build * f, render=1.05 * f, cpu=cpu),
            row(m, "kdtree", KD, build=0.9 * f, render=0.8 * f, cpu=cpu),
        ]
    return out


def test_claims_flag_verdicts_that_differ_between_machines(tmp_path, report_nums):
    # 5.2-a, "BVH builds fastest": it holds here (LBVH builds in twice BVH's time) and not
    # in the reference run's rows, where the LBVH builds in half of it.
    this = load_results([write_csv(tmp_path / "a.csv", table4_rows(0.2, "This CPU"))])
    ref = load_results([write_csv(tmp_path / "b.csv", table4_rows(0.05, "Reference CPU"))])
    rows, _ = evaluate_all(this, report_nums, ref)
    by_id = {r.claim.id: r for r in rows}
    a = by_id["5.2-a"]
    assert (a.ours.verdict, a.reference.verdict, a.machine_dependent) == (HOLDS, FAILS, True)
    # 5.2-f (kd-tree spends the most build + render time) holds on both: not flagged.
    f = by_id["5.2-f"]
    assert (f.ours.verdict, f.reference.verdict, f.machine_dependent) == (HOLDS, HOLDS, False)
    # Not comparable on one side is no machine dependence.
    assert not any(r.machine_dependent for r in rows if FAILS not in (r.ours.verdict, r.reference.verdict))
    alone, _ = evaluate_all(this, report_nums)
    assert all(r.reference is None and not r.machine_dependent for r in alone)

    out = tmp_path / "out"
    a_csv, b_dir = tmp_path / "a.csv", tmp_path / "refrun"
    (b_dir / "csv").mkdir(parents=True)
    (b_dir / "csv" / "a.csv").write_text((tmp_path / "b.csv").read_text())
    assert main(["claims", str(a_csv), "--out", str(out), "--reference-run", str(b_dir)]) == 0
    claims = (out / "tables" / "claims.md").read_text()
    line = next(x for x in claims.splitlines() if x.startswith("| 5.2-a |"))
    assert line.endswith("| does not hold | **machine-dependent** |")
    assert "Machine-dependent (holds on one run, not on the other): 5.2-a" in claims
