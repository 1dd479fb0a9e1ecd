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

import re
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from pathlib import Path

from .. import commands
from ..inputs import run_json
from ..mapping.structures import use_accelbench
from .runs import (
    RUN_JSON,
    ReproduceError,
    csv_rows,
    decide,
    job_of,
    point_latest,
    prepare_into,
    read_run_json,
    record_written,
    tree_changes,
    utc,
    write_run_json,
)

# A tag is part of a directory name: letters, digits, '_', '-' and '.', not first '-' or '.'.
TAG = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$")
DRY_RUN_COUNT = re.compile(r"^(\d+) combinations", re.M)
# `accelbench run --dry-run`'s inputs: "  KIND SHA256 NAME" after its "inputs" line.
DRY_RUN_INPUT = re.compile(r"^  (config|model|rays) +([0-9a-f]{64}) (.*)$")


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


# ---- measuring ------------------------------------------------------------------------------


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


def benchmark_json(out_csv: Path) -> Path:
    """Where the harness writes Google Benchmark's JSON beside NAME.csv, for google/benchmark's
    tools/compare.py: NAME.json. A continued run's process writes only what it measures, so
    each continuation has a file of its own (NAME.part-2.json, ...), never half of NAME.json."""
    stem = out_csv.name[: -len(".csv")]
    path, part = out_csv.with_name(f"{stem}.json"), 1
    while path.exists():
        part += 1
        path = out_csv.with_name(f"{stem}.part-{part}.json")
    return path


def run_config(accelbench: Path, config: Path, out_csv: Path, progress: Progress, done_elsewhere: int) -> int:
    """One config through the harness into out_csv (continued when it has rows). Its lines
    pass through; after a line, when the CSV has gained a row since the job's progress line
    was last shown, the line is shown again (the harness prints a line as each combination
    starts, so the job's line follows each per-combination line, whatever their format)."""
    resume = out_csv.is_file() and out_csv.stat().st_size > 0
    cmd = [
        str(accelbench),
        "run",
        str(config),
        "--out",
        str(out_csv),
        f"--benchmark_out={benchmark_json(out_csv)}",
    ]
    cmd += ["--resume"] if resume else []
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
        meta["continued"] = [*run_json.field(meta, "continued", list, []), utc(now)]
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


def analysis_steps(job: Job, run_dir: Path) -> list[tuple[str, Callable[[], list[Path]]]]:
    """The analysis's commands over the run's CSVs, each a name and a typed call."""
    csvs = {c: run_dir / "csv" / f"{c.stem}.csv" for c in job.configs}
    steps = []
    if job.scaling is not None:
        scaling_csv = csvs[job.scaling]
        steps.append(("scaling", lambda: commands.scaling([scaling_csv], run_dir)))
    main = [p for c, p in csvs.items() if c != job.scaling]
    if main:
        # The scaling rows are the run's too: the claims' spread floor and the provenance read them.
        src = commands.Sources(main, run_csvs=[csvs[job.scaling]] if job.scaling is not None else [])
        if job.report_numbers is not None:
            src = replace(src, report_numbers=job.report_numbers)
        ref_csv = job.reference_run / "csv" if job.reference_run is not None else None
        if ref_csv is not None and ref_csv.is_dir() and ref_csv.resolve() != (run_dir / "csv").resolve():
            src = replace(src, reference_run=job.reference_run)
        steps.append(("all", lambda: commands.analyse_all(src, run_dir)))
    return steps


def analyse(job: Job, run_dir: Path) -> int:
    """Runs the analysis steps, printing what each wrote; 2 on input it cannot use. The
    structure table is the measuring build's."""
    use_accelbench(job.accelbench)
    for name, step in analysis_steps(job, run_dir):
        print(f"== analysis: {name} -> {run_dir}", file=sys.stderr, flush=True)
        try:
            for path in step():
                print(path)
        except commands.BAD_INPUT as e:
            print(f"error: {e}", file=sys.stderr)
            return commands.EXIT_BAD_INPUT
    return 0


def refusal(job: Job) -> str | None:
    """Why the job must not start, checked before the harness is asked anything: a dirty
    tree for the reference run, a missing config, a tag that cannot name a directory, an
    output path that is not what it should be."""
    if job.require_clean_tree:
        changes = tree_changes(Path.cwd())
        if changes:
            return (
                "refusing to measure the reference run from a work tree with uncommitted changes "
                "(its rows would name a commit that is not the code that ran); commit or stash them "
                "first:\n  " + "\n  ".join(changes)
            )
    for c in job.configs:
        if not c.is_file():
            return f"no such config {c}"
    if job.tag and not TAG.match(job.tag):
        return (
            f"--tag {job.tag!r}: a tag is part of a directory name: letters, digits, "
            f"'_', '-' and '.', not starting with '-' or '.'"
        )
    if job.scaling is not None and job.scaling not in job.configs:
        job.configs.append(job.scaling)
    problems = output_problems(job)
    if problems:
        return "nothing measured:\n  " + "\n  ".join(problems)
    return None


def dirty_build(job: Job, provenance: dict[str, str]) -> str | None:
    """For the reference run: why the build's own provenance makes it unfit."""
    if job.require_clean_tree and provenance.get("git_dirty") != "false":
        return (
            f"refusing: {job.accelbench} reports git_dirty="
            f"{provenance.get('git_dirty')} for the tree it was built from (when it was built, a "
            f"tracked file outside results/ differed from the commit, or a file git does not track "
            f"lay under core/ or harness/): commit or remove them and build again"
        )
    return None


def measure(job: Job, run_dir: Path, csvs: list[Path], progress: Progress) -> int:
    """Every config through the harness into its CSV; the first non-zero exit code."""
    for i, (config, out_csv) in enumerate(zip(job.configs, csvs)):
        before = sum(csv_rows(p) for p in csvs[:i])
        rc = run_config(job.accelbench, config, out_csv, progress, before)
        if rc != 0:
            print(
                f"reproduce: {config} exited with {rc}; {run_dir} stays unfinished (run the "
                f"job again with the same build to continue it)",
                file=sys.stderr,
            )
            return rc
    return 0


def cost_images(job: Job, run_dir: Path) -> int:
    """The cost images command, the run directory appended; its exit code."""
    if not job.cost_images:
        return 0
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
    return cost.returncode


def finish(job: Job, run_dir: Path, progress: Progress) -> None:
    """results/latest, the page listing the runs, and the job's last line."""
    if job.latest is not None and job.into is None:
        point_latest(job.latest, run_dir)
    from ..outputs.pages.runs_page import write_runs_page

    write_runs_page(job.runs.parent)
    took = clock(time.monotonic() - progress.start)
    print(
        f"reproduce: done in {took}; see {run_dir / 'REPORT.md'}"
        + (f" (also {job.latest})" if job.latest is not None and job.into is None else ""),
        file=sys.stderr,
    )


def reproduce(job: Job, now: datetime | None = None) -> tuple[int, Path]:
    """Runs the job; returns (exit code, run directory). The run is marked complete only
    when every config measured and the analysis ran. A ReproduceError is a job that cannot
    go on, with the reason."""
    now = now or datetime.now(UTC)
    why = refusal(job)
    provenance = build_provenance(job.accelbench) if why is None else {}
    why = why or dirty_build(job, provenance)
    if why is not None:
        print(f"reproduce: {why}", file=sys.stderr)
        return 2, Path()
    # Every config through the harness's own checks before anything is written or measured.
    checked = {c: dry_run(job.accelbench, c) for c in job.configs}
    inputs = {c.name: checked[c].inputs for c in job.configs}
    run_dir, meta, foreign = start(job, provenance, inputs, now)
    csvs = [run_dir / "csv" / f"{c.stem}.csv" for c in job.configs]
    progress = Progress(sum(checked[c].combinations for c in job.configs), sum(csv_rows(p) for p in csvs))
    progress.show(progress.done_before)
    try:
        rc = measure(job, run_dir, csvs, progress)
        if rc == 0 and job.analyse:
            rc = cost_images(job, run_dir) or analyse(job, run_dir)
        if rc != 0:
            return rc, run_dir
        meta["complete"] = True
        meta["finished"] = utc(datetime.now(UTC))
    finally:
        record_written(run_dir, meta, foreign)
    finish(job, run_dir, progress)
    return 0, run_dir
