"""The main job (`make reproduce-tables`): measure the configs on this machine into a run
directory of their own, then analyse it.

Every invocation measures. Each run gets results/runs/<UTC timestamp>-<short sha>[-TAG]/
with csv/, tables/, figures/, REPORT.md and run.json (what was asked, the provenance of
the build that measured, whether the job finished); results/latest points at the newest
finished run. Resuming exists only to finish an interrupted run of the same code on the
same machine: when the newest run directory of the same job (same configs, same tag) is
unfinished and its recorded provenance equals this build's (`accelbench provenance`: git
sha, dirty flag, compiler, build type, cpu, Embree, and any column a build adds such as
`isa`), the harness continues its CSVs (`--resume`); otherwise a new directory is started
and the reason is printed.

A run is its contents, not its names: run.json records the inputs of each config (the
sha256 of the config file, of each model and ray file: `accelbench run --dry-run`), and a
run whose recorded inputs differ from the current ones is never continued (the harness
refuses to continue a results file of other inputs too).

`--into DIR` writes one fixed directory instead, always from scratch (the committed
reference run, `make reference-run`, results/reference/): a directory the driver makes, an
empty one, or one holding a run.json of an earlier run, whose `written` list names the
files the driver wrote there; only those are removed, every other file is left as it is.
With `--require-clean-tree` it refuses a work tree with uncommitted changes to tracked
files, so that the commit the rows name is the code that ran.

Before anything is measured every config is checked by the harness (a config it refuses
ends the job with the harness's own message) and every output path is checked (a file
where a directory belongs, a directory where results/latest's link belongs).

Progress: the harness prints a line per combination of its config; after each, this
driver prints one line for the whole job (combinations done / total over all configs,
elapsed, an estimate of what is left from the pace so far in this invocation).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import re
import subprocess
import sys
import time
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

RUN_JSON = "run.json"
# A tag is part of a directory name: letters, digits, '_', '-' and '.', not first '-' or '.'.
TAG = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$")
RUN_NAME = re.compile(r"^\d{8}T\d{6}Z-[0-9a-z]+(-\d+)?(-[A-Za-z0-9_][A-Za-z0-9_.-]*)?$")
DRY_RUN_COUNT = re.compile(r"^(\d+) combinations", re.M)
# `accelbench run --dry-run`'s inputs: "  KIND SHA256 NAME" after its "inputs" line.
DRY_RUN_INPUT = re.compile(r"^  (config|model|rays) +([0-9a-f]{64}) (.*)$")


class ReproduceError(RuntimeError):
    """A job that cannot go on, with the reason for the user (exit 2)."""


def harness(cmd: list[str]) -> str:
    """Runs the harness and returns its standard output; a failure is a ReproduceError
    carrying the harness's own message (its standard error), not a traceback."""
    try:
        out = subprocess.run(cmd, capture_output=True, text=True)
    except OSError as e:
        raise ReproduceError(f"cannot run {cmd[0]}: {e.strerror} (build it with `make build`)") from None
    if out.returncode != 0:
        said = (out.stderr or out.stdout).strip()
        raise ReproduceError(f"`{' '.join(cmd)}` failed (exit {out.returncode}):\n{said}")
    return out.stdout


# ---- provenance and the resume decision ---------------------------------------------------


def build_provenance(accelbench: Path) -> dict[str, str]:
    """What the harness will write into every row (`accelbench provenance`, NAME=VALUE)."""
    out = harness([str(accelbench), "provenance"])
    prov = {}
    for line in out.splitlines():
        name, sep, value = line.partition("=")
        if sep:
            prov[name] = value
    if "git_sha" not in prov:
        raise ReproduceError(f"{accelbench} provenance printed no git_sha: {out!r}")
    return prov


def provenance_differences(recorded: dict[str, str], current: dict[str, str]) -> list[str]:
    """Every field in which two builds differ, "name: old -> new"; a field one of them does
    not record at all (an older build without `isa`) differs as "(absent)"."""
    out = []
    for name in list(recorded) + [n for n in current if n not in recorded]:
        old, new = recorded.get(name), current.get(name)
        if old != new:
            out.append(
                f"{name}: {old if old is not None else '(absent)'} -> "
                f"{new if new is not None else '(absent)'}"
            )
    return out


@dataclass
class Decision:
    run_dir: Path
    resume: bool
    reason: str


def read_run_json(run_dir: Path) -> dict | None:
    try:
        return json.loads((run_dir / RUN_JSON).read_text())
    except (OSError, ValueError):
        return None


def job_of(configs: list[Path], tag: str) -> dict:
    return {"configs": [p.name for p in configs], "tag": tag}


def newest_run_of_job(runs: Path, job: dict) -> tuple[Path, dict] | None:
    """The newest run directory under `runs` whose run.json asked for the same job."""
    if not runs.is_dir():
        return None
    found = []
    for d in runs.iterdir():
        if d.is_dir() and not d.is_symlink() and RUN_NAME.match(d.name):
            meta = read_run_json(d)
            if meta is not None and meta.get("job") == job:
                found.append((meta.get("started", ""), d.name, d, meta))
    if not found:
        return None
    _, _, d, meta = max(found)
    return d, meta


def new_run_dir(runs: Path, provenance: dict[str, str], tag: str, now: datetime) -> Path:
    sha = provenance.get("git_sha", "unknown")[:7] or "unknown"
    base = f"{now.strftime('%Y%m%dT%H%M%SZ')}-{sha}"
    name, n = base, 1
    while (runs / (name + (f"-{tag}" if tag else ""))).exists():  # two runs in one second
        n += 1
        name = f"{base}-{n}"
    return runs / (name + (f"-{tag}" if tag else ""))


def inputs_differences(recorded: dict | None, current: dict, measured: set[str] | None = None) -> list[str]:
    """Where two records of a job's inputs ({config file name: [[kind, sha256, name], ...]})
    differ: "CONFIG: KIND NAME: sha256 OLD then, NEW now", "...: only then" or "only now".
    `measured`: compare only these configs (those with rows: another's rows cannot mix)."""
    if recorded is None:
        if measured is not None and not measured:
            return []
        return ["the run recorded no inputs (an older driver): its contents cannot be compared"]
    out = []
    for config in list(recorded) + [c for c in current if c not in recorded]:
        if measured is not None and config not in measured:
            continue
        then = {(k, n): sha for k, sha, n in recorded.get(config, [])}
        now = {(k, n): sha for k, sha, n in current.get(config, [])}
        for key in list(then) + [k for k in now if k not in then]:
            what = f"{config}: {key[0]} {key[1]}"
            if key not in now:
                out.append(f"{what}: only then")
            elif key not in then:
                out.append(f"{what}: only now")
            elif then[key] != now[key]:
                out.append(f"{what}: sha256 {then[key][:12]} then, {now[key][:12]} now")
    return out


def decide(
    runs: Path, job: dict, provenance: dict[str, str], fresh: bool, now: datetime, inputs: dict | None = None
) -> Decision:
    """Resume the newest run of this job only when it is unfinished, was measured by a
    build with the same provenance and from the same inputs (`inputs`: the configs' and
    their models' contents, compared for every config with rows; None: not compared);
    otherwise a new directory, saying why."""
    last = newest_run_of_job(runs, job)
    new = new_run_dir(runs, provenance, job["tag"], now)
    if last is None:
        return Decision(new, False, "no earlier run of these configs")
    d, meta = last
    if meta.get("complete"):
        return Decision(new, False, f"the last run {d} is complete")
    if fresh:
        return Decision(new, False, f"FRESH=1: not resuming the unfinished run {d}")
    diffs = provenance_differences(meta.get("provenance", {}), provenance)
    if diffs:
        return Decision(
            new,
            False,
            f"the last run {d} is unfinished but was measured by "
            f"another build or machine ({'; '.join(diffs)})",
        )
    measured = {c for c in inputs or {} if csv_rows(d / "csv" / f"{Path(c).stem}.csv") > 0}
    if inputs is not None and (changed := inputs_differences(meta.get("inputs"), inputs, measured)):
        return Decision(
            new,
            False,
            f"the last run {d} is unfinished but was measured from other contents under the same "
            f"names ({'; '.join(changed)})",
        )
    return Decision(
        d,
        True,
        f"the last run {d} is unfinished, its provenance matches this build's and its inputs the configs'",
    )


def tree_changes(repo: Path) -> list[str]:
    """Uncommitted changes to tracked files (`git status --porcelain`, untracked files not
    counted: the harness's git_dirty uses the same test). Raises when repo is no checkout."""
    out = subprocess.run(
        ["git", "-C", str(repo), "status", "--porcelain", "--untracked-files=no"],
        capture_output=True,
        text=True,
    )
    if out.returncode != 0:
        raise RuntimeError(f"{repo}: not a git work tree ({out.stderr.strip()})")
    return [line for line in out.stdout.splitlines() if line.strip()]


# ---- measuring ------------------------------------------------------------------------------


def csv_rows(path: Path) -> int:
    """Complete data rows of a results CSV (a line cut by an interruption does not count;
    the harness drops it when it resumes)."""
    if not path.is_file():
        return 0
    with path.open(newline="") as fh:
        text = fh.read()
    if not text:
        return 0
    if not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]
    return max(0, sum(1 for _ in csv.reader(text.splitlines())) - 1)


@dataclass
class DryRun:
    combinations: int  # skipped ones get rows too
    inputs: list[list[str]]  # [kind, sha256, name]: what the harness records beside the CSV


def dry_run(accelbench: Path, config: Path) -> DryRun:
    """The harness's check of a config (`accelbench run --dry-run`): its combination count
    and its inputs. A config the harness refuses is a ReproduceError with its message."""
    out = harness([str(accelbench), "run", "--dry-run", str(config)])
    m = DRY_RUN_COUNT.search(out)
    if not m:
        raise ReproduceError(f"{accelbench} run --dry-run {config}: no combination count in its output")
    inputs = [list(i.groups()) for i in map(DRY_RUN_INPUT.match, out.splitlines()) if i]
    if not any(kind == "config" for kind, _, _ in inputs):
        raise ReproduceError(
            f"{accelbench} run --dry-run {config}: no inputs in its output (an older build?)"
        )
    return DryRun(int(m.group(1)), inputs)


def clock(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"


@dataclass
class Progress:
    """One line for the whole job: done / total over every config, elapsed, time left."""

    total: int
    done_before: int  # rows already in the CSVs when this invocation started
    start: float = field(default_factory=time.monotonic)

    def line(self, done: int) -> str:
        elapsed = time.monotonic() - self.start
        here = done - self.done_before
        left = ""
        if here > 0 and done < self.total:
            left = f", about {clock(elapsed / here * (self.total - done))} left"
        pct = 100 * done // self.total if self.total else 100
        return (
            f"reproduce: {done}/{self.total} combinations ({pct}%) over all configs, "
            f"elapsed {clock(elapsed)}{left}"
        )

    def show(self, done: int) -> None:
        print(self.line(done), file=sys.stderr, flush=True)


def run_config(accelbench: Path, config: Path, out_csv: Path, progress: Progress, done_elsewhere: int) -> int:
    """One config through the harness into out_csv (continued when it has rows). Its lines
    pass through; after a line, when the CSV has gained a row since the job's progress line
    was last shown, the line is shown again (the harness prints a line as each combination
    starts, so the job's line follows each per-combination line, whatever their format)."""
    resume = out_csv.is_file() and out_csv.stat().st_size > 0
    cmd = [str(accelbench), "run", str(config), "--out", str(out_csv)] + (["--resume"] if resume else [])
    print(f"== {config.stem} -> {out_csv}{' (continuing)' if resume else ''}", file=sys.stderr, flush=True)
    proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True, bufsize=1)
    assert proc.stderr is not None
    shown = done_elsewhere + csv_rows(out_csv)
    for line in proc.stderr:
        sys.stderr.write(line)
        done = done_elsewhere + csv_rows(out_csv)
        if done != shown:
            progress.show(done)
            shown = done
    rc = proc.wait()
    if done_elsewhere + csv_rows(out_csv) != shown:
        progress.show(done_elsewhere + csv_rows(out_csv))
    return rc


# ---- the job --------------------------------------------------------------------------------


@dataclass
class Job:
    accelbench: Path
    configs: list[Path]
    scaling: Path | None = None  # among configs: analysed by `scaling`, not `all`
    tag: str = ""  # "quick": its own run directories and job identity
    runs: Path = Path("results/runs")
    latest: Path | None = Path("results/latest")
    into: Path | None = None  # a fixed directory, always fresh (the reference run)
    reference_run: Path | None = None  # the committed reference run, for the three-way table
    report_numbers: Path | None = None
    cost_images: list[str] | None = None  # command writing OUT/figures/cost-*.png, OUT appended
    fresh: bool = False
    require_clean_tree: bool = False  # refuse uncommitted changes (the reference run)
    analyse: bool = True


def write_run_json(run_dir: Path, meta: dict) -> None:
    tmp = run_dir / (RUN_JSON + ".tmp")
    tmp.write_text(json.dumps(meta, indent=2) + "\n")
    tmp.replace(run_dir / RUN_JSON)


def utc(now: datetime) -> str:
    return now.strftime("%Y-%m-%dT%H:%M:%SZ")


def files_under(d: Path) -> set[str]:
    """Every file (or link) under d, as paths relative to it."""
    if not d.is_dir():
        return set()
    return {str(p.relative_to(d)) for p in d.rglob("*") if p.is_file() or p.is_symlink()}


def prepare_into(into: Path) -> set[str]:
    """Makes `into` ready for a run from scratch and returns the files in it that the driver
    did not write (kept, never removed). It must be a directory the driver makes, an empty
    one, or one whose run.json (an earlier run's) lists what the driver wrote there: only
    those files are removed."""
    if into.exists() and not into.is_dir():
        raise ReproduceError(f"--into {into}: not a directory")
    if not into.exists():
        into.mkdir(parents=True)
        return set()
    present = files_under(into)
    meta = read_run_json(into)
    written = meta.get("written") if isinstance(meta, dict) and "job" in meta else None
    if not present:
        return set()
    if not isinstance(written, list):
        shown = ", ".join(sorted(present)[:5]) + (f" and {len(present) - 5} more" if len(present) > 5 else "")
        raise ReproduceError(
            f"--into {into}: the directory holds files this driver did not write ({shown}) and no "
            f"{RUN_JSON} of an earlier run listing what it wrote; give a new or empty directory"
        )
    for rel in sorted(set(written) & present):
        (into / rel).unlink()
    # Directories left empty by that, deepest first.
    holding = {p for w in written for p in Path(w).parents if p != Path(".")}
    for rel in sorted(holding, key=lambda p: -len(p.parts)):
        if (into / rel).is_dir() and not any((into / rel).iterdir()):
            (into / rel).rmdir()
    return present - set(written)


def record_written(run_dir: Path, meta: dict, foreign: set[str]) -> None:
    """run.json's `written`: every file under run_dir but those that were there before the
    driver started writing (and were not its own): what a later --into may remove."""
    meta["written"] = sorted((files_under(run_dir) | {RUN_JSON}) - foreign - {RUN_JSON + ".tmp"})
    write_run_json(run_dir, meta)


def start(job: Job, provenance: dict[str, str], inputs: dict, now: datetime) -> tuple[Path, dict, set[str]]:
    """The run directory, its run.json and the files in it the driver did not write, after
    deciding whether to continue a run."""
    ident = job_of(job.configs, job.tag)
    foreign: set[str] = set()
    if job.into is not None:
        run_dir = job.into
        foreign = prepare_into(run_dir)
        print(f"reproduce: measuring from scratch into {run_dir}", file=sys.stderr)
        meta = None
    else:
        d = decide(job.runs, ident, provenance, job.fresh, now, inputs)
        run_dir = d.run_dir
        print(
            f"reproduce: {'continuing' if d.resume else 'starting'} {run_dir}: {d.reason}",
            file=sys.stderr,
            flush=True,
        )
        meta = read_run_json(run_dir) if d.resume else None
    (run_dir / "csv").mkdir(parents=True, exist_ok=True)
    if meta is None:
        meta = {
            "job": ident,
            "provenance": provenance,
            "inputs": inputs,
            "started": utc(now),
            "complete": False,
            "continued": [],
        }
    else:
        meta["continued"].append(utc(now))
    write_run_json(run_dir, meta)
    return run_dir, meta, foreign


def output_problems(job: Job) -> list[str]:
    """What would stop the job after measuring: two configs writing one CSV, a directory or
    file where the other belongs among the outputs, a directory where results/latest's link
    or results/index.html belongs. Checked before anything is measured."""
    problems = []
    stems: dict[str, Path] = {}
    for c in job.configs:
        if c.stem in stems and stems[c.stem] != c:
            problems.append(f"{stems[c.stem]} and {c} would both write csv/{c.stem}.csv: rename one")
        stems.setdefault(c.stem, c)
    base = job.into if job.into is not None else job.runs
    for p in [base, *base.parents]:
        if p.exists() or p.is_symlink():
            if not p.is_dir():
                problems.append(f"{p} is not a directory")
            break
    if job.into is not None and job.into.is_dir():
        d = job.into
        files = [RUN_JSON, "REPORT.md", "index.html"] + [
            f"csv/{c.stem}{ext}" for c in job.configs for ext in (".csv", ".reps.csv", ".inputs.csv")
        ]
        for rel in files:
            if (d / rel).exists() and not (d / rel).is_file():
                problems.append(f"{d / rel} is not a file")
        for rel in ("csv", "tables", "figures", "report"):
            if (d / rel).exists() and not (d / rel).is_dir():
                problems.append(f"{d / rel} is not a directory")
    # The page listing every run, rewritten when the job ends (write_runs_page).
    runs_page = job.runs.parent / "index.html"
    if runs_page.is_dir():
        problems.append(f"{runs_page} is a directory, not the page listing the runs the driver keeps there")
    if job.latest is not None and job.into is None:
        if job.latest.exists() and not job.latest.is_symlink():
            problems.append(
                f"{job.latest} is a {'directory' if job.latest.is_dir() else 'file'}, not the link to the "
                f"newest run the driver keeps there: move it away"
            )
        for p in job.latest.parents:
            if p.exists():
                if not p.is_dir():
                    problems.append(f"{p} is not a directory (it would hold {job.latest})")
                break
    return problems


def analysis_commands(job: Job, run_dir: Path) -> list[list[str]]:
    """The analysis's command lines (python -m accelbench_analysis ...) over the run's CSVs."""
    csvs = {c: run_dir / "csv" / f"{c.stem}.csv" for c in job.configs}
    cmds = []
    if job.scaling is not None:
        cmds.append(["scaling", str(csvs[job.scaling]), "--out", str(run_dir)])
    main = [str(p) for c, p in csvs.items() if c != job.scaling]
    if main:
        cmd = ["all", *main, "--out", str(run_dir)]
        if job.report_numbers is not None:
            cmd += ["--report-numbers", str(job.report_numbers)]
        ref_csv = job.reference_run / "csv" if job.reference_run is not None else None
        if ref_csv is not None and ref_csv.is_dir() and ref_csv.resolve() != (run_dir / "csv").resolve():
            cmd += ["--reference-run", str(job.reference_run)]
        cmds.append(cmd)
    return cmds


def point_latest(latest: Path, run_dir: Path) -> None:
    latest.parent.mkdir(parents=True, exist_ok=True)
    tmp = latest.with_name(latest.name + ".tmp")
    tmp.unlink(missing_ok=True)
    tmp.symlink_to(os.path.relpath(run_dir.resolve(), latest.parent.resolve()))
    tmp.replace(latest)


def reproduce(job: Job, now: datetime | None = None) -> tuple[int, Path]:
    """Runs the job; returns (exit code, run directory). The run is marked complete only
    when every config measured and the analysis ran. A ReproduceError is a job that cannot
    go on, with the reason."""
    from .pipeline import main as analysis_main

    now = now or datetime.now(UTC)
    if job.require_clean_tree:
        changes = tree_changes(Path.cwd())
        if changes:
            print(
                "reproduce: refusing to measure the reference run from a work tree with "
                "uncommitted changes (its rows would name a commit that is not the code that "
                "ran); commit or stash them first:\n  " + "\n  ".join(changes),
                file=sys.stderr,
            )
            return 2, Path()
    for c in job.configs:
        if not c.is_file():
            print(f"reproduce: no such config {c}", file=sys.stderr)
            return 2, Path()
    if job.tag and not TAG.match(job.tag):
        print(
            f"reproduce: --tag {job.tag!r}: a tag is part of a directory name: letters, digits, "
            f"'_', '-' and '.', not starting with '-' or '.'",
            file=sys.stderr,
        )
        return 2, Path()
    if job.scaling is not None and job.scaling not in job.configs:
        job.configs.append(job.scaling)
    problems = output_problems(job)
    if problems:
        print("reproduce: nothing measured:\n  " + "\n  ".join(problems), file=sys.stderr)
        return 2, Path()
    provenance = build_provenance(job.accelbench)
    if job.require_clean_tree and provenance.get("git_dirty") != "false":
        print(
            f"reproduce: refusing: {job.accelbench} reports git_dirty="
            f"{provenance.get('git_dirty')} for the tree it was built from (when it was built, a "
            f"tracked file outside results/ differed from the commit, or a file git does not track "
            f"lay under core/ or harness/): commit or remove them and build again",
            file=sys.stderr,
        )
        return 2, Path()
    # Every config through the harness's own checks before anything is written or measured.
    checked = {c: dry_run(job.accelbench, c) for c in job.configs}
    inputs = {c.name: checked[c].inputs for c in job.configs}
    run_dir, meta, foreign = start(job, provenance, inputs, now)
    csvs = [run_dir / "csv" / f"{c.stem}.csv" for c in job.configs]
    totals = [checked[c].combinations for c in job.configs]
    progress = Progress(sum(totals), sum(csv_rows(p) for p in csvs))
    progress.show(progress.done_before)
    try:
        for i, (config, out_csv) in enumerate(zip(job.configs, csvs)):
            before = sum(csv_rows(p) for p in csvs[:i])
            rc = run_config(job.accelbench, config, out_csv, progress, before)
            if rc != 0:
                print(
                    f"reproduce: {config} exited with {rc}; {run_dir} stays unfinished (run the "
                    f"job again with the same build to continue it)",
                    file=sys.stderr,
                )
                return rc, run_dir
        if job.analyse:
            if job.cost_images:
                print("== cost images", file=sys.stderr, flush=True)
                try:
                    cost = subprocess.run(job.cost_images + [str(run_dir)])
                except OSError as e:
                    raise ReproduceError(
                        f"cannot run the cost images command {job.cost_images[0]}: {e.strerror}"
                    ) from None
                if cost.returncode != 0:
                    print(
                        f"reproduce: the cost images ({' '.join(job.cost_images)}) exited with "
                        f"{cost.returncode}; {run_dir} stays unfinished",
                        file=sys.stderr,
                    )
                    return cost.returncode, run_dir
            for cmd in analysis_commands(job, run_dir):
                print(f"== analysis: {cmd[0]} -> {run_dir}", file=sys.stderr, flush=True)
                rc = analysis_main(cmd)
                if rc != 0:
                    return rc, run_dir
        meta["complete"] = True
        meta["finished"] = utc(datetime.now(UTC))
    finally:
        record_written(run_dir, meta, foreign)
    if job.latest is not None and job.into is None:
        point_latest(job.latest, run_dir)
    from .outputs.runs_page import write_runs_page

    write_runs_page(job.runs.parent)
    took = clock(time.monotonic() - progress.start)
    print(
        f"reproduce: done in {took}; see {run_dir / 'REPORT.md'}"
        + (f" (also {job.latest})" if job.latest is not None and job.into is None else ""),
        file=sys.stderr,
    )
    return 0, run_dir


# ---- command line (python -m accelbench_analysis reproduce ...) -----------------------------


def add_reproduce(sub) -> None:
    s = sub.add_parser(
        "reproduce",
        help="the main job: measure configs into a run directory of their own, then analyse it",
        description="Measures every CONFIG with the harness into RUNS/<UTC time>-<sha>[-TAG]/"
        "csv/ and analyses them there (tables/, figures/, REPORT.md); LATEST then "
        "points at it. Continues the newest run of the same configs only when it "
        "is unfinished, `accelbench provenance` matches what it recorded and so do the "
        "contents of its configs, model and ray files (sha256).",
    )
    s.add_argument("configs", nargs="+", type=Path, help="configs/NAME.yaml, in order")
    s.add_argument("--accelbench", type=Path, default=Path("build/accelbench"))
    s.add_argument("--scaling", type=Path, help="the config among them analysed by `scaling`")
    s.add_argument(
        "--tag", default="", help="suffix of the run directory and part of the job's identity (e.g. quick)"
    )
    s.add_argument("--runs", type=Path, default=Path("results/runs"))
    s.add_argument("--latest", type=Path, default=Path("results/latest"))
    s.add_argument(
        "--into",
        type=Path,
        help="measure from scratch into this directory instead (the committed reference run): a new or "
        "empty one, or one an earlier run wrote (its run.json lists the files it wrote, the only ones "
        "removed)",
    )
    s.add_argument(
        "--reference-run",
        type=Path,
        default=Path("results/reference"),
        help="the committed reference run compared with (default results/reference)",
    )
    s.add_argument("--report-numbers", type=Path)
    s.add_argument(
        "--cost-images",
        help="command (split at spaces) writing OUT/figures/cost-*.png; the run directory is appended",
    )
    s.add_argument("--fresh", action="store_true", help="never continue an unfinished run")
    s.add_argument(
        "--require-clean-tree",
        action="store_true",
        help="refuse when tracked files have uncommitted changes (the reference run)",
    )


def run_reproduce(args: argparse.Namespace) -> int:
    job = Job(
        accelbench=args.accelbench,
        configs=list(args.configs),
        scaling=args.scaling,
        tag=args.tag,
        runs=args.runs,
        latest=args.latest,
        into=args.into,
        reference_run=args.reference_run,
        report_numbers=args.report_numbers,
        cost_images=args.cost_images.split() if args.cost_images else None,
        fresh=args.fresh,
        require_clean_tree=args.require_clean_tree,
    )
    try:
        rc, _ = reproduce(job)
    except ReproduceError as e:
        print(f"reproduce: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        # The harness got the same signal; what it finished is in the CSVs.
        print(
            "\nreproduce: interrupted; run the job again with the same build to continue it", file=sys.stderr
        )
        return 130
    return rc
