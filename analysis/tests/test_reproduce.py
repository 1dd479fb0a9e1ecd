"""The main job's driver (reproduce/): a run directory per invocation, resuming only an
unfinished run of the same build, the job's progress line, the reference run's clean-tree
rule."""

from __future__ import annotations

import json
import subprocess
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest

from accelbench_analysis.cli import main
from accelbench_analysis.inputs.load import load_results
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
        (dict(PROV, compile_flags="-O2"), "compile_flags: (absent) -> -O2"),
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
    # Google Benchmark's JSON beside each CSV, for google/benchmark's tools/compare.py.
    for name in ("tiny", "second"):
        gb = json.loads((first / "csv" / f"{name}.json").read_text())
        assert gb["context"] and len({b["run_name"] for b in gb["benchmarks"]}) == 4  # build, render x 2
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
