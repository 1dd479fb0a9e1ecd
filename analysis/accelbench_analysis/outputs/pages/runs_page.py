"""results/index.html: the run directories on this machine, newest first, with their commits.

A main-job run says what it is in its run.json (configs, tag, provenance, started, whether
it finished); the other run directories (the regression check's, grid searches, Slurm
runs) say it in their CSVs' provenance columns. Each line links the run's index.html and
REPORT.md where they exist; the history page (`make history`) is linked at the top."""

from __future__ import annotations

import csv
import html
from dataclasses import dataclass
from pathlib import Path

from ...inputs.load import is_companion
from ...inputs.run_json import RUN_JSON, field, read_run_json, skipped
from .page import data_table, page, write_page

INDEX = "index.html"


@dataclass
class RunEntry:
    path: Path  # the run directory
    kind: str
    when: str  # started (run.json) or the newest row's timestamp
    commit: str
    what: str
    state: str


def csv_provenance(files: list[Path]) -> tuple[str, str]:
    """(commit, newest timestamp) over the rows of harness CSVs; "?" when they have none.
    A file that cannot be read is skipped, said so (skipped)."""
    shas, stamps = set(), []
    for f in files:
        try:
            with f.open(newline="") as fh:
                rows = list(csv.DictReader(fh))
        except (OSError, ValueError, csv.Error) as e:
            skipped(f, f"{type(e).__name__}: {e}")
            continue
        for row in rows:
            if row.get("git_sha"):
                shas.add(str(row["git_sha"])[:7] + ("+dirty" if row.get("git_dirty") == "true" else ""))
            stamps.append(str(row.get("timestamp") or ""))
    return ", ".join(sorted(shas)) or "?", max(stamps, default="")


def entry(d: Path, kind: str) -> RunEntry | None:
    if (d / RUN_JSON).is_file():
        meta = read_run_json(d)  # None (said so) when unreadable or not an object
        if meta is None:
            return None
        prov, job = field(meta, "provenance", dict, {}), field(meta, "job", dict, {})
        commit = str(prov.get("git_sha", "?"))[:7] + ("+dirty" if prov.get("git_dirty") == "true" else "")
        configs = [str(c) for c in field(job, "configs", list, [])]
        what = ", ".join(configs) + (f" (tag {job['tag']})" if job.get("tag") else "")
        state = "complete" if meta.get("complete") is True else "unfinished"
        return RunEntry(d, kind, str(field(meta, "started", str, "")), commit, what, state)
    files = [f for f in sorted(d.glob("*.csv")) if not is_companion(f)]
    if not files:
        return None
    commit, when = csv_provenance(files)
    return RunEntry(d, kind, when, commit, ", ".join(f.name for f in files), "")


def kind_of(d: Path) -> str:
    """run (the main job), regress, grid (grid-NAME), slurm (slurm-NAME)."""
    if (d / "run.json").is_file():
        return "run"
    return "regress" if d.name == "regress" else d.name.split("-")[0]


def run_entries(results: Path) -> list[RunEntry]:
    runs = results / "runs"
    out = []
    for d in sorted(runs.iterdir()) if runs.is_dir() else []:
        if d.is_dir() and not d.is_symlink():
            e = entry(d, kind_of(d))
            if e is not None:
                out.append(e)
    ref = entry(results / "reference", "reference (committed)")
    if ref is not None:
        out.append(ref)
    return sorted(out, key=lambda e: e.when, reverse=True)


def link(results: Path, path: Path, text: str) -> str:
    return f'<a href="{html.escape(path.relative_to(results).as_posix())}">{html.escape(text)}</a>'


def runs_page_html(results: Path) -> str:
    rows = []
    for e in run_entries(results):
        links = [link(results, e.path / f, f) for f in (INDEX, "REPORT.md") if (e.path / f).is_file()]
        rows.append(
            f"<tr><td>{html.escape(e.when)}</td><td>{html.escape(e.path.relative_to(results).as_posix())}</td>"
            f"<td>{html.escape(e.kind)}</td><td>{html.escape(e.commit)}</td><td>{html.escape(e.what)}</td>"
            f"<td>{html.escape(e.state)}</td><td>{' '.join(links)}</td></tr>"
        )
    history = results / "history" / INDEX
    body = [
        "<h1>accelbench runs on this machine</h1>",
        "<p>Newest first. "
        + (
            link(results, history, "Every measurement across commits") + " (make history)."
            if history.is_file()
            else "Run <code>make history</code> for every measurement across commits."
        )
        + "</p>",
        data_table(["started / measured", "run", "kind", "commit", "what", "state", "pages"], rows),
    ]
    return page("accelbench runs", "\n".join(body))


def write_runs_page(results: Path) -> Path:
    return write_page(results / INDEX, runs_page_html(results))
