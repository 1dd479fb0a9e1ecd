"""Loading one or more harness CSVs as one Results: each file read and checked against the
contract (schema.py), its NAME.reps.csv beside it checked against the summary's medians,
and the rows grouped by provenance (A, B, ... in file order) with a warning for each
thing a reader must know (mixed builds, a dirty tree, an unoptimised build)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from .schema import (
    ERROR_COLUMNS,
    INSTRUCTIONS_COLUMN,
    KEY_COLUMNS,
    OPTIMISED_BUILD_TYPES,
    PEAK_RSS_COLUMN,
    PROVENANCE_IDENTITY,
    REPS_KEY_COLUMNS,
    REPS_MEDIAN_RTOL,
    REPS_REQUIRED_COLUMNS,
    REPS_TIME_COLUMNS,
    VERDICT_COLUMNS,
    ContractError,
    ProvenanceGroup,
    Results,
    read_csv,
    read_header,
    scan_records,
    to_numbers,
)


def read_reps(path: Path) -> pd.DataFrame:
    """Reads a .reps.csv (one row per timed repetition) with the same checks as read_csv:
    complete rows, and times that are positive finite numbers."""
    header = [h.strip() for h in read_header(path)]
    missing = [c for c in REPS_REQUIRED_COLUMNS if c not in header]
    if missing:
        raise ContractError(f"{path}: missing required columns: {', '.join(missing)}")
    starts = scan_records(path)
    df = pd.read_csv(path, dtype=str, keep_default_na=False)
    df.columns = [c.strip() for c in df.columns]
    problems = to_numbers(df, ["repetition"] + REPS_TIME_COLUMNS, starts, REPS_TIME_COLUMNS)
    if problems:
        raise ContractError(f"{path}: " + "; ".join(problems))
    df["source"] = str(path)
    return df


def is_companion(path: str | Path) -> bool:
    """A file the harness writes beside a results CSV (NAME.reps.csv: the repetitions;
    NAME.inputs.csv: the record of its inputs), not a results file itself."""
    return Path(path).name.endswith((".reps.csv", ".inputs.csv"))


def reps_path(path: str | Path) -> Path:
    p = Path(path)
    return p.with_name(p.name[:-4] + ".reps.csv" if p.name.endswith(".csv") else p.name + ".reps.csv")


def _check_reps(rows: pd.DataFrame, reps: pd.DataFrame) -> list[str]:
    """The summary's medians must be the medians of its repetitions."""
    warnings = []
    key = ["combo_id"] if "combo_id" in rows.columns and "combo_id" in reps.columns else REPS_KEY_COLUMNS
    med = reps.groupby(key)[["build_s", "render_s"]].median().reset_index()
    merged = rows.merge(med, on=key, how="inner")
    for measure in ("build_s", "render_s"):
        a, b = merged[f"{measure}_median"], merged[measure]
        bad = ~np.isclose(a, b, rtol=REPS_MEDIAN_RTOL, equal_nan=True)
        for _, r in merged[bad].head(5).iterrows():
            warnings.append(
                f"{measure}_median of {r['accel']} [{r['params']}] on {r['model']} "
                f"is {r[f'{measure}_median']:.6g} but the median of its repetitions "
                f"in the .reps.csv is {r[measure]:.6g}"
            )
    return warnings


def _provenance_groups(df: pd.DataFrame) -> tuple[pd.Series, list[ProvenanceGroup]]:
    keys = df[PROVENANCE_IDENTITY].astype(str).apply(tuple, axis=1)
    order: dict[tuple, str] = {}
    for k in keys:
        if k not in order:
            order[k] = chr(ord("A") + len(order)) if len(order) < 26 else f"G{len(order)}"
    labels = keys.map(order)
    groups = []
    for k, label in order.items():
        sel = labels == label
        groups.append(
            ProvenanceGroup(
                label=label,
                fields=dict(zip(PROVENANCE_IDENTITY, k)),
                files=sorted(set(df.loc[sel, "source"])),
                rows=int(sel.sum()),
            )
        )
    return labels, groups


def _provenance_warnings(groups: list[ProvenanceGroup]) -> list[str]:
    warnings = []
    if len(groups) > 1:
        differing = [f for f in PROVENANCE_IDENTITY if len({g.fields[f] for g in groups}) > 1]
        warnings.append(
            f"MIXED PROVENANCE: the rows come from {len(groups)} different builds/machines "
            f"(differing in {', '.join(differing)}). Table cells are tagged with their group; "
            f"claims comparing rows of different groups are marked not comparable. Groups: "
            + "; ".join(g.describe() for g in groups)
        )
    for g in groups:
        if g.fields["git_dirty"] == "true":
            warnings.append(
                f"Group {g.label} was measured from a dirty work tree "
                f"(git_dirty=true): commit {g.fields['git_sha'][:12]} does not "
                f"identify the code that ran."
            )
        if g.fields["build_type"].lower() not in OPTIMISED_BUILD_TYPES:
            warnings.append(
                f"Group {g.label} comes from build type "
                f"{g.fields['build_type']!r}: its timings are not representative "
                f"of an optimised build."
            )
        if g.fields["git_sha"] in ("", "unknown"):
            warnings.append(f"Group {g.label} has no git commit (git_sha={g.fields['git_sha']!r}).")
    return warnings


# One CSV as read and checked: its rows, its repetitions (None without a .reps.csv) and what
# checking them against each other found.
FileRead = tuple[pd.DataFrame, "pd.DataFrame | None", list[str]]


def _read_file(p: str | Path) -> FileRead:
    df = read_csv(p)
    rp = reps_path(p)
    if not rp.is_file():
        return df, None, []
    reps = read_reps(rp)
    return df, reps, [f"{rp}: {w}" for w in _check_reps(df, reps)]


def load_results(paths: list[str | Path], cache: dict[Path, FileRead] | None = None) -> Results:
    """Loads and checks one or more harness CSVs (and their .reps.csv where present).
    `cache`: files already read, by resolved path, filled with those read here (an analysis
    that loads overlapping sets of files reads each once; the frames are not modified)."""
    if not paths:
        raise ContractError("no CSV given")
    cache = {} if cache is None else cache
    frames, rep_frames, warnings = [], [], []
    for p in paths:
        key = Path(p).resolve()
        if key not in cache:
            cache[key] = _read_file(p)
        df, reps, file_warnings = cache[key]
        frames.append(df)
        warnings += file_warnings
        if reps is not None:
            rep_frames.append(reps)
    rows = pd.concat(frames, ignore_index=True)
    labels, groups = _provenance_groups(rows)
    rows["prov_group"] = labels.values
    warnings = _provenance_warnings(groups) + warnings

    if len(frames) > 1:
        dup = rows.duplicated(KEY_COLUMNS, keep=False)
        if dup.any():
            n = int(rows[dup].drop_duplicates(KEY_COLUMNS).shape[0])
            warnings.append(
                f"{n} ({', '.join(KEY_COLUMNS)}) keys occur in more than one "
                f"file; where such a row fills a table cell the newest timestamp "
                f"is used and the cell's note says so."
            )
    for col in ERROR_COLUMNS + [PEAK_RSS_COLUMN, INSTRUCTIONS_COLUMN]:
        if col not in rows.columns:
            rows[col] = np.nan
    for col in VERDICT_COLUMNS:
        rows[col] = rows[col].fillna("").astype(str).str.strip() if col in rows.columns else ""
    reps = pd.concat(rep_frames, ignore_index=True) if rep_frames else None
    return Results(rows=rows, groups=groups, warnings=warnings, reps=reps, files=[str(p) for p in paths])
