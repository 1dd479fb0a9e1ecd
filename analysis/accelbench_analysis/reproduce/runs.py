"""The main job's run directories: their names, run.json (what was asked, the provenance
of the build that measured, the inputs' sha256, whether the job finished, the files the
driver wrote), the decision to continue an unfinished run or start a new one, a fixed
directory made ready for a run from scratch (--into), and results/latest."""

from __future__ import annotations

import csv
import json
import os
import re
import subprocess
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

from ..inputs.run_json import RUN_JSON, field, read_run_json
from ..inputs.schema import MIXING_COLUMNS

RUN_NAME = re.compile(r"^\d{8}T\d{6}Z-[0-9a-z]+(-\d+)?(-[A-Za-z0-9_][A-Za-z0-9_.-]*)?$")


class ReproduceError(RuntimeError):
    """A job that cannot go on, with the reason for the user (exit 2)."""


# ---- provenance and the resume decision ---------------------------------------------------


def provenance_differences(recorded: dict[str, str], current: dict[str, str]) -> list[str]:
    """Every field of the mixing rule (MIXING_COLUMNS, the harness's) in which two builds
    differ, "name: old -> new"; a field one of them does not record at all (an older build
    without `isa`) differs as "(absent)"."""
    out = []
    for name in MIXING_COLUMNS:
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
                found.append((str(field(meta, "started", str, "")), d.name, d, meta))
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
    diffs = provenance_differences(field(meta, "provenance", dict, {}), provenance)
    if diffs:
        return Decision(
            new,
            False,
            f"the last run {d} is unfinished but was measured by "
            f"another build or machine ({'; '.join(diffs)})",
        )
    measured = {c for c in inputs or {} if csv_rows(d / "csv" / f"{Path(c).stem}.csv") > 0}
    if inputs is not None and (
        changed := inputs_differences(field(meta, "inputs", dict, None), inputs, measured)
    ):
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
    written = meta.get("written") if meta is not None and "job" in meta else None
    if not present:
        return set()
    if not isinstance(written, list):
        shown = ", ".join(sorted(present)[:5]) + (f" and {len(present) - 5} more" if len(present) > 5 else "")
        raise ReproduceError(
            f"--into {into}: the directory holds files this driver did not write ({shown}) and no "
            f"{RUN_JSON} of an earlier run listing what it wrote; give a new or empty directory"
        )
    outside = [w for w in written if not inside(into, w)]
    if outside:
        raise ReproduceError(
            f"--into {into}: its {RUN_JSON} lists paths that are not files inside it "
            f"({', '.join(map(repr, outside[:5]))}): nothing removed; give a new or empty directory"
        )
    for rel in sorted(set(written) & present):
        (into / rel).unlink()
    # Directories left empty by that, deepest first (each inside `into`: checked above).
    holding = {p for w in written for p in Path(w).parents if p != Path(".")}
    for rel in sorted(holding, key=lambda p: -len(p.parts)):
        if (into / rel).is_dir() and not (into / rel).is_symlink() and not any((into / rel).iterdir()):
            (into / rel).rmdir()
    return present - set(written)


def inside(root: Path, rel) -> bool:
    """Whether `rel` (an entry of run.json's `written`) names a path inside `root`: a
    relative path without "..", whose folder resolves (links followed) inside root."""
    if not isinstance(rel, str) or not rel:
        return False
    p = Path(rel)
    if p.is_absolute() or ".." in p.parts:
        return False
    return (root / p).parent.resolve().is_relative_to(root.resolve())


def record_written(run_dir: Path, meta: dict, foreign: set[str]) -> None:
    """run.json's `written`: every file under run_dir but those that were there before the
    driver started writing (and were not its own): what a later --into may remove."""
    meta["written"] = sorted((files_under(run_dir) | {RUN_JSON}) - foreign - {RUN_JSON + ".tmp"})
    write_run_json(run_dir, meta)


def point_latest(latest: Path, run_dir: Path) -> None:
    latest.parent.mkdir(parents=True, exist_ok=True)
    tmp = latest.with_name(latest.name + ".tmp")
    tmp.unlink(missing_ok=True)
    tmp.symlink_to(os.path.relpath(run_dir.resolve(), latest.parent.resolve()))
    tmp.replace(latest)
