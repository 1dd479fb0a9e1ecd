"""Every measurement on this machine across commits (`make history`).

Collects the harness CSVs of every run under results/: the main job's run directories
(results/runs/<run>/csv/), the regression check's (results/runs/regress/run-N.csv), the
committed reference run (results/reference/csv/), the grid searches
(results/runs/grid-NAME/pass-N.csv) and merged Slurm runs (results/runs/slurm-NAME/).
Each ok row gives its measures: render and build time, both as a ratio to the Embree row
of the same file with the same model and render settings (regress.embree_ratios, tier 3's
ratio), and the deterministic counts (regress's tier 1 and 2 columns, memory).

A run directory is rewritten by the next run (`make regress` starts afresh; the
reference run is re-measured), so what was collected is kept: results/history/
collected.csv holds every row ever collected (one per source file, timestamp and
combination), and each `history` adds the rows on disk that it does not hold yet. Delete
results/history/ to forget.

results/history/history.csv: one row per commit x machine x combination x measure (the
median over the rows of that commit on that machine, `cpu` and `isa`, never over two
machines; n, min and max say how many and how far apart), commits in
commit order (git's topological order; commits git does not know after them by time; a
dirty tree right after its commit). A count that differs from the previous commit's is
marked as a step."""

from __future__ import annotations

import math
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from ...inputs.load import is_companion
from ...inputs.run_json import skipped
from ...inputs.schema import (
    BUILD_IDENTITY,
    COMPILE_FLAGS_COLUMN,
    KEY_COLUMNS,
    UNKNOWN,
    ContractError,
    Results,
    parse_params,
    read_csv,
)
from ...mapping.selection import label_of
from .regress import ERROR_COUNTS, EXACT_COUNTS, RENDER_SETTING_COLUMNS, embree_ratios

HISTORY_DIR = Path("results/history")
COLLECTED = "collected.csv"
SOURCES = "sources.csv"
HISTORY = "history.csv"
VERDICTS = "regress.csv"

# Measures: (name in history.csv, what it is). Ratios and times are trends; counts are
# exact, so any change between commits is a step.
RATIOS = {
    "trace_ratio_to_embree": "render_s_median",
    "build_ratio_to_embree": "build_s_median",
}
TIMES = {"render_s": "render_s_median", "build_s": "build_s_median"}
COUNTS = [*EXACT_COUNTS, *ERROR_COUNTS, "memory_bytes", "instructions"]
MEASURES = [*RATIOS, *TIMES, *COUNTS]

# A combination: the same structure, parameters, model and rays, whichever config measured it.
SETTINGS = ["ray_set", "render_threads", *[c for c in RENDER_SETTING_COLUMNS if c != "render_threads"]]
COMBINATION = ["model", "accel", "params", *SETTINGS]
# Rows of two machines (or two instruction sets of one) are never one median: each keeps
# its own series, and a count's step is against the same machine's previous commit.
MACHINE = ["cpu", "isa"]
PROVENANCE = [*BUILD_IDENTITY, "cpu", "embree_isa"]
# What tells two builds of one commit apart on the page (the commit says the rest).
BUILD_FIELDS = [c for c in BUILD_IDENTITY if c not in ("git_sha", "git_dirty")]
SOURCE = ["kind", "run", "file", "config", "timestamp"]


@dataclass
class Source:
    kind: str  # run, reference, regress, grid, slurm
    run: str  # the run directory, relative to results/
    file: Path


def sources(results: Path) -> list[Source]:
    """Every harness CSV of every run under `results`: the files beside each (repetitions,
    records of inputs) and the regression check's partial runs left out (run-N.csv joins
    timed-N.csv and callgrind.csv)."""
    out = []
    runs = results / "runs"
    for d in sorted(p for p in runs.glob("*") if p.is_dir() and not p.is_symlink()) if runs.is_dir() else []:
        if (d / "run.json").is_file():
            out += [Source("run", f"runs/{d.name}", f) for f in sorted((d / "csv").glob("*.csv"))]
        elif d.name == "regress":
            out += [Source("regress", "runs/regress", f) for f in sorted(d.glob("run-*.csv"))]
        elif d.name.startswith("grid-"):
            out += [Source("grid", f"runs/{d.name}", f) for f in sorted(d.glob("pass-*.csv"))]
        elif d.name.startswith("slurm-"):
            out += [
                Source("slurm", f"runs/{d.name}", f)
                for f in sorted(d.glob("*.csv"))
                if not f.name.startswith("shard-")
            ]
    ref = results / "reference" / "csv"
    out += [Source("reference", "reference", f) for f in sorted(ref.glob("*.csv"))] if ref.is_dir() else []
    return [s for s in out if not is_companion(s.file)]


def measured_rows(src: Source, results: Path) -> pd.DataFrame:
    """One row per ok row of the file: source, provenance, combination, structure, measures."""
    df = read_csv(src.file)
    df = df[df["status"] == "ok"].copy()
    for c in SETTINGS + ["label"]:
        if c not in df.columns:
            df[c] = ""
    keyed = Results(rows=df, groups=[])
    keys = df[KEY_COLUMNS].astype(str).agg(" | ".join, axis=1)
    for name, column in RATIOS.items():
        ratios = embree_ratios(keyed, False, str(src.file), column)
        df[name] = [ratios[k].ratio if k in ratios else math.nan for k in keys]
    for name, column in TIMES.items():
        df[name] = df[column]
    for c in COUNTS:
        if c not in df.columns:
            df[c] = math.nan
    df["structure"] = [
        lab if isinstance(lab, str) and lab.strip() else label_of(a, p)
        for lab, a, p in zip(df["label"], df["accel"], df["param_dict"])
    ]
    df["kind"], df["run"] = src.kind, src.run
    df["file"] = str(src.file.relative_to(results)) if src.file.is_relative_to(results) else str(src.file)
    cols = SOURCE + PROVENANCE + COMBINATION + ["structure"] + MEASURES
    out = df[cols].copy()
    for c in SETTINGS:
        out[c] = out[c].map(
            lambda v: (
                ""
                if v is None or (isinstance(v, float) and math.isnan(v))
                else f"{v:g}"
                if isinstance(v, float)
                else str(v)
            )
        )
    return out


IDENTITY = ["file", "timestamp", "config", *COMBINATION]


def file_state(path: Path) -> str:
    st = path.stat()
    return f"{st.st_size}:{st.st_mtime_ns}"


def collect(results: Path, out: Path) -> tuple[pd.DataFrame, pd.DataFrame, list[str]]:
    """The rows out/collected.csv holds plus those of the files on disk it does not hold
    yet (a file whose size and modification time out/sources.csv recorded is not read
    again); the files' states; notes on files that are not harness CSVs."""
    store, manifest = out / COLLECTED, out / SOURCES
    known = {}
    if store.is_file() and manifest.is_file():
        m = pd.read_csv(manifest, dtype=str, keep_default_na=False)
        known = dict(zip(m["file"], m["state"]))
    frames, notes, states = [], [], []
    for src in sources(results):
        state = file_state(src.file)
        states.append((str(src.file), state))
        if known.get(str(src.file)) == state:
            continue
        try:
            frames.append(measured_rows(src, results))
        except (ContractError, OSError, ValueError, KeyError, TypeError) as e:
            # One unreadable file (cut, not a harness CSV, unreadable bytes) is named and
            # left out; the others are still collected.
            notes.append(f"left out {src.file}: {type(e).__name__}: {e}")
    text = [*IDENTITY, *PROVENANCE, "kind", "run", "structure"]
    new = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=[*text, *MEASURES])
    if store.is_file():
        stored = pd.read_csv(store, dtype=str, keep_default_na=False)
        if COMPILE_FLAGS_COLUMN not in stored.columns:  # collected before the column: not known
            stored[COMPILE_FLAGS_COLUMN] = UNKNOWN
        new = pd.concat([stored, new.astype({c: str for c in text})])
    new[MEASURES] = new[MEASURES].apply(pd.to_numeric, errors="coerce")
    new = new.astype({c: str for c in text}).drop_duplicates(IDENTITY, keep="last")
    return new.reset_index(drop=True), pd.DataFrame(states, columns=["file", "state"]), notes


# ---- commit order ------------------------------------------------------------------------------


def git_commits(repo: Path, shas: list[str]) -> dict[str, tuple[int, str, str]]:
    """sha -> (position in git's topological order, commit date, subject) for the commits
    git knows; {} without git."""
    try:
        order = subprocess.run(
            ["git", "-C", str(repo), "rev-list", "--topo-order", "--reverse", "--all"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.split()
    except (OSError, subprocess.CalledProcessError):
        return {}
    position = {sha: i for i, sha in enumerate(order)}
    known = [s for s in shas if s in position]
    if not known:
        return {}
    log = subprocess.run(
        ["git", "-C", str(repo), "log", "--no-walk=unsorted", "--format=%H%x09%cI%x09%s", *known],
        capture_output=True,
        text=True,
    ).stdout
    info = {}
    for line in log.splitlines():
        sha, date, subject = (line.split("\t", 2) + ["", ""])[:3]
        info[sha] = (position[sha], date, subject)
    return info


def commit_table(rows: pd.DataFrame, repo: Path) -> pd.DataFrame:
    """One row per (git_sha, git_dirty): commit (short sha, "+dirty"), order, date, subject."""
    c = rows.groupby(["git_sha", "git_dirty"], as_index=False)["timestamp"].min()
    info = git_commits(repo, sorted(set(c["git_sha"])))
    c["known"] = c["git_sha"].map(lambda s: s in info)
    c["position"] = c["git_sha"].map(lambda s: info[s][0] if s in info else math.inf)
    c["commit_date"] = c["git_sha"].map(lambda s: info[s][1] if s in info else "")
    c["subject"] = c["git_sha"].map(lambda s: info[s][2] if s in info else "(not in this repository)")
    # Known commits in git's order, then the others by when they were first measured; a
    # dirty tree just after its commit.
    first = c.groupby("git_sha")["timestamp"].transform("min")
    c = c.assign(first=first).sort_values(["position", "first", "git_sha", "git_dirty"])
    c["commit_order"] = range(len(c))
    c["commit"] = c["git_sha"].str[:7] + c["git_dirty"].map(lambda d: "+dirty" if d == "true" else "")
    return c[["git_sha", "git_dirty", "commit", "commit_order", "commit_date", "subject"]]


# ---- history.csv ---------------------------------------------------------------------------------


def series_labels(df: pd.DataFrame) -> pd.Series:
    """What tells apart the combinations of one structure on one model: the parameters that
    vary among them (all of them in history.csv's `params`), the ray set (other than the
    camera's), the image size and the render threads (more than 1)."""
    label = pd.Series("", index=df.index, dtype=object)
    for _, g in df.groupby(["model", "structure"], sort=False):
        texts = g["params"].unique()
        dicts = {t: parse_params(t) for t in texts}
        keys = sorted({k for d in dicts.values() for k in d})
        varying = [k for k in keys if len({d.get(k, "") for d in dicts.values()}) > 1]
        names = {t: ", ".join(f"{k}={dicts[t].get(k, '')}" for k in varying) for t in texts}
        label[g.index] = g["params"].map(names)
    if df[MACHINE].drop_duplicates().shape[0] > 1:
        label = label + " · " + df["cpu"] + " (" + df["isa"] + ")"
    rays = ~df["ray_set"].isin(["", "camera"])
    label = label.where(~rays, label + " · ray set " + df["ray_set"])
    image = df["image_width"] != ""
    label = label.where(~image, label + " · " + df["image_width"] + "x" + df["image_height"])
    threads = ~df["render_threads"].isin(["", "1"])
    label = label.where(~threads, label + " · " + df["render_threads"] + " threads")
    if "build" in df.columns:  # two builds of one commit or more: each its own series, named
        builds = df.groupby(["model", "structure"])["build"].transform("nunique") > 1
        label = label.where(~builds, label + " · " + df["build"])
    return label.str.strip(" ·").where(lambda s: s != "", "(one combination)")


def build_text(rows: pd.DataFrame) -> pd.Series:
    """The build beside its commit: compiler, build type, flags, ISA and Embree, e.g.
    "gcc 12.2.0, RelWithDebInfo, flags -O3 -g -DNDEBUG, avx2, Embree 4.3.0"."""
    named = {COMPILE_FLAGS_COLUMN: "flags ", "embree_version": "Embree "}
    return (
        rows[BUILD_FIELDS]
        .astype(str)
        .agg(lambda r: ", ".join(named.get(c, "") + v for c, v in r.items()), axis=1)
    )


def history(collected: pd.DataFrame, repo: Path) -> pd.DataFrame:
    """One row per commit x combination x measure, in commit order; count steps marked.
    configs, runs: what measured the combination at that commit; cpu and isa: where (each
    machine its own row)."""
    if collected.empty:
        return pd.DataFrame(columns=["commit", "measure", "value"])
    # Aggregated per commit and combination first (a few thousand groups, not one per
    # measure too), then one row per measure.
    # Per build and machine, not per commit: a Debug and a Release build of one commit, or
    # two machines, are never one median.
    collected = collected.assign(build=build_text(collected))
    keys = [*BUILD_IDENTITY, "build", "cpu", *COMBINATION, "structure"]
    g = collected.groupby(keys, sort=False)
    stats = [
        getattr(g[MEASURES], how)().reset_index().melt(id_vars=keys, var_name="measure", value_name=name)
        for how, name in (("median", "value"), ("count", "n"), ("min", "min"), ("max", "max"))
    ]
    out = pd.concat([stats[0], *(s[[s.columns[-1]]] for s in stats[1:])], axis=1)
    out = out[out["n"] > 0]
    joined = g.agg(
        configs=("config", lambda v: ";".join(sorted(set(v)))),
        runs=("run", lambda v: ";".join(sorted(set(v)))),
        first_measured=("timestamp", "min"),
        last_measured=("timestamp", "max"),
    ).reset_index()
    out = out.merge(joined, on=keys, how="left")
    out = out.merge(commit_table(collected, repo), on=["git_sha", "git_dirty"], how="left")
    out["series"] = series_labels(out)
    out = out.sort_values([*MACHINE, *COMBINATION, "measure", "commit_order"]).reset_index(drop=True)
    prev = out.groupby([*MACHINE, *COMBINATION, "build", "measure"])["value"].shift()
    out["step"] = out["measure"].isin(COUNTS) & prev.notna() & (out["value"] != prev)
    cols = [
        "commit",
        "git_sha",
        "git_dirty",
        "commit_order",
        "commit_date",
        "subject",
        "build",
        "model",
        "structure",
        "accel",
        "params",
        *SETTINGS,
        "series",
        "measure",
        "value",
        "n",
        "min",
        "max",
        "step",
        "configs",
        "runs",
        *MACHINE,
        "first_measured",
        "last_measured",
    ]
    return (
        out[cols]
        .sort_values(["commit_order", "model", "structure", "series", "measure"])
        .reset_index(drop=True)
    )


# ---- the regression check's verdicts ---------------------------------------------------------


@dataclass
class Verdict:
    verdict: str
    commit: str
    measured: str
    report: Path
    text: str = field(repr=False, default="")


def latest_verdict(results: Path) -> Verdict | None:
    """The verdict of the newest report in results/runs/regress/ (report-2.md, the second
    measurement, decides when it exists), with the commit its run measured."""
    from .regress import verdict_of_report

    d = results / "runs" / "regress"
    reports = sorted(d.glob("report-*.md"), key=lambda p: p.stem)
    if not reports:
        return None
    report = reports[-1]
    run = d / f"run-{report.stem.split('-')[-1]}.csv"
    try:
        text = report.read_text()
        verdict = verdict_of_report(text)
        if verdict is None or not run.is_file():
            return None
        rows = pd.read_csv(
            run, dtype=str, keep_default_na=False, usecols=["git_sha", "git_dirty", "timestamp"]
        )
        sha = rows["git_sha"].iloc[0]
        commit = sha[:7] + ("+dirty" if rows["git_dirty"].iloc[0] == "true" else "")
    except (OSError, ValueError, KeyError, IndexError) as e:  # a cut or header-only run, bytes no text
        skipped(run, f"the regression check's verdict left out: {type(e).__name__}: {e}")
        return None
    return Verdict(verdict, commit, rows["timestamp"].max(), report, text)


def verdict_history(latest: Verdict | None, store: Path) -> pd.DataFrame:
    """Every verdict collected so far (commit, measured, verdict, report), the latest added."""
    cols = ["commit", "measured", "verdict", "report"]
    old = (
        pd.read_csv(store, dtype=str, keep_default_na=False)
        if store.is_file()
        else pd.DataFrame(columns=cols)
    )
    if latest is not None:
        old = pd.concat(
            [
                old,
                pd.DataFrame(
                    [[latest.commit, latest.measured, latest.verdict, str(latest.report)]], columns=cols
                ),
            ]
        )
    return (
        old.drop_duplicates(["commit", "measured"], keep="last")
        .sort_values("measured")
        .reset_index(drop=True)
    )


# ---- the command -------------------------------------------------------------------------------


@dataclass
class Collected:
    rows: pd.DataFrame  # collected.csv
    history: pd.DataFrame  # history.csv
    verdicts: pd.DataFrame
    latest: Verdict | None
    notes: list[str]


def update(results: Path, out: Path, repo: Path) -> Collected:
    """Collects; writes out/collected.csv, sources.csv, history.csv and regress.csv."""
    out.mkdir(parents=True, exist_ok=True)
    rows, states, notes = collect(results, out)
    hist = history(rows, repo)
    latest = latest_verdict(results)
    verdicts = verdict_history(latest, out / VERDICTS)
    for frame, name in ((rows, COLLECTED), (states, SOURCES), (hist, HISTORY), (verdicts, VERDICTS)):
        tmp = out / (name + ".tmp")
        frame.to_csv(tmp, index=False)
        tmp.replace(out / name)
    return Collected(rows, hist, verdicts, latest, notes)
