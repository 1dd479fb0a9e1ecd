"""The CSV contract between the C++ harness and this package, and the loader that enforces it.

The harness writes one row per accelerator x params x model combination (see
analysis/README.md for the column list). Loading checks that contract before anything is
computed: a file missing required columns, with an unknown status or with text where a
number belongs is rejected with an error that names the file, the columns and the rows.

Provenance (PROVENANCE_IDENTITY: the build's identity, cpu and embree_isa) is grouped: rows
that differ in any of these fields belong to different groups, labelled A, B, ... in file
order. More than one group is never an error (comparing two machines is legitimate), but
it is never silent either: every output carries a warning, table cells are tagged with
their group, and a claim that would compare rows of different groups is "not comparable".
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .provenance import (  # noqa: F401  (re-exported: the columns' one home for readers)
    BUILD_IDENTITY,
    COMPILE_FLAGS_COLUMN,
    EMBREE_ISA_COLUMN,
    ISA_COLUMN,
    MIXING_COLUMNS,
    PLUGIN_COLUMNS,
    PROVENANCE_IDENTITY,
    UNKNOWN,
)

# A row's identity. `ray_set` (camera, or one of RAY_SETS), `render_threads` and
# `fp_mode` tell apart the rows of one combination in a ray-set, thread-scaling or
# floating-point-mode run; CSVs from before ray sets get ray_set = camera.
KEY_COLUMNS = ["config", "model", "accel", "params", "ray_set", "render_threads", "fp_mode"]
CAMERA_SET = "camera"
RAY_SETS = ("primary", "shadow", "ao", "diffuse", "random")
# The floating-point mode every trace of a row ran in (the config's render.fp_mode; the
# robustness catalogue's rows: ieee). Files from before the column traced in IEEE mode,
# the process default, and load with "ieee".
FP_MODE_COLUMN = "fp_mode"
FP_MODES = ("ieee", "ftz_daz")


def stat_columns(measure: str) -> list[str]:
    """The five summary columns the harness writes for one timed measure."""
    return [f"{measure}_{s}" for s in ("median", "mean", "stddev", "ci_lo", "ci_hi")]


IDENTITY_COLUMNS = ["config", "model", "triangles", "vertices", "accel", "params"]
STATUS_COLUMNS = ["status", "message", "repetitions"]
TIMING_COLUMNS = stat_columns("build_s") + stat_columns("render_s")
COUNT_COLUMNS = [
    "rays",
    "hits",
    "shadow_rays",
    "shadow_hits",
    "mrays_per_s",
    "nodes",
    "leaves",
    "tree_depth",
    "memory_bytes",
    "sah_cost",
    "prim_tests",
    "node_visits",
]
PROVENANCE_COLUMNS = [
    "git_sha",
    "git_dirty",
    "compiler",
    "build_type",
    "cpu",
    "render_threads",
    "embree_version",
    "timestamp",
]
REQUIRED_COLUMNS = IDENTITY_COLUMNS + STATUS_COLUMNS + TIMING_COLUMNS + COUNT_COLUMNS + PROVENANCE_COLUMNS

# Written by the harness when it compares with the `reference` accelerator; every consumer
# must cope with their absence (older CSVs; has_error_columns()). Counts are over the primary rays
# (`rays`) against the double-precision `reference` accelerator; empty = not measured.
ERROR_COLUMNS = [
    "false_misses",
    "false_hits",
    "prim_mismatches",
    "t_err_ulp_p50",
    "t_err_ulp_max",
    "nan_results",
    "image_rmse",
    "hole_pixels",
]
# The measuring process's memory high-water mark (bytes, the loaded model included).
PEAK_RSS_COLUMN = "peak_rss_bytes"
# Robustness-catalogue rows (configs/robustness.yaml) carry a verdict instead of timings:
# `verdict` is pass/fail, `verdict_counts` the counts behind it ("leaks=0 false_hits=0 ...").
VERDICT_COLUMNS = ["verdict", "verdict_counts"]
VERDICTS = ("pass", "fail")
# The model label of a catalogue case's rows: `case-<id>:<name>` (e.g. case-2a:closed-...).
CASE_PREFIX = "case-"
# The optional columns after `instructions` in the harness's order: errors, memory, verdicts.
ERROR_MEMORY_VERDICT_COLUMNS = ERROR_COLUMNS + [PEAK_RSS_COLUMN] + VERDICT_COLUMNS

# Written by the harness for the CI regression runs (tier 2 of `regress`): callgrind's
# instruction count (Ir) of the measured render, empty where it was not measured.
INSTRUCTIONS_COLUMN = "instructions"

NUMERIC_COLUMNS = (
    ["triangles", "vertices", "repetitions"]
    + TIMING_COLUMNS
    + COUNT_COLUMNS
    + ["render_threads"]
    + ERROR_COLUMNS
    + [PEAK_RSS_COLUMN, INSTRUCTIONS_COLUMN]
)

STATUSES = ("ok", "skipped", "timeout", "error")

# The render settings of a row: two rows differing in one of them traced other rays (or on
# another number of threads), so neither stands for the other nor divides it.
RENDER_SETTING_COLUMNS = [
    "ray_source",
    "image_width",
    "image_height",
    "spp",
    "light",
    "shading",
    "render_threads",
    "fp_mode",
]
# Settings that are counts: where a row has one, a whole number of at least 1.
COUNT_SETTING_COLUMNS = ["render_threads", "image_width", "image_height", "spp"]

# The combo_ids timed alternately with a row in its processes (`interleave: true`), sorted,
# ';'-separated; empty when timed alone, as in the files from before the column.
TIMED_WITH_COLUMN = "timed_with"

# The results CSV's columns other than the parameters' (which sit between `params` and
# `status`, one per parameter name of the registry), in the harness's order, with their kind
# in the harness's column table (`accelbench columns`; a test holds the two equal). The
# groups above are the subsets the analysis requires or converts.
RESULT_CSV_COLUMNS: list[tuple[str, str]] = [
    ("config", "text"),
    ("combo_id", "text"),
    ("model", "text"),
    ("triangles", "number"),
    ("vertices", "number"),
    ("ray_source", "text"),
    ("ray_set", "text"),
    ("ray_set_hash", "text"),
    ("accel", "text"),
    ("label", "text"),
    ("params", "text"),
    ("status", "text"),
    ("message", "text"),
    ("repetitions", "number"),
    ("processes", "number"),
    (TIMED_WITH_COLUMN, "text"),
    *[(c, "number") for c in TIMING_COLUMNS],
    ("ci_coverage", "number"),
    ("build_s_process_gap", "number"),
    ("render_s_process_gap", "number"),
    ("render_cpu_s_median", "number"),
    ("rays", "number"),
    ("hits", "number"),
    ("shadow_rays", "number"),
    ("shadow_hits", "number"),
    ("mrays_per_s", "number"),
    ("nodes", "number"),
    ("leaves", "number"),
    ("tree_depth", "number"),
    ("memory_bytes", "number"),
    ("sah_cost", "number"),
    ("avg_leaf_size", "number"),
    ("build_extra", "text"),
    ("prim_tests", "number"),
    ("node_visits", "number"),
    ("box_tests", "number"),
    ("prim_tests_per_ray", "number"),
    ("node_visits_per_ray", "number"),
    (INSTRUCTIONS_COLUMN, "number"),
    *[(c, "number") for c in ERROR_COLUMNS],
    (PEAK_RSS_COLUMN, "number"),
    *[(c, "text") for c in VERDICT_COLUMNS],
    ("image_width", "number"),
    ("image_height", "number"),
    ("spp", "number"),
    ("light", "text"),
    ("shading", "text"),
    (FP_MODE_COLUMN, "text"),
    ("git_sha", "text"),
    ("git_dirty", "text"),
    ("compiler", "text"),
    ("build_type", "text"),
    (COMPILE_FLAGS_COLUMN, "text"),
    ("cpu", "text"),
    ("render_threads", "number"),
    ("embree_version", "text"),
    ("timestamp", "text"),
    (ISA_COLUMN, "text"),
    (EMBREE_ISA_COLUMN, "text"),
    *[(c, "text") for c in PLUGIN_COLUMNS],
]

# Build types whose timings are representative (the Makefile builds RelWithDebInfo).
OPTIMISED_BUILD_TYPES = {"release", "relwithdebinfo"}

# The repetitions file names rows by combo_id (unique per row, ray set and thread count
# included) besides the four columns it always had.
REPS_KEY_COLUMNS = ["config", "model", "accel", "params"]
REPS_REQUIRED_COLUMNS = REPS_KEY_COLUMNS + ["repetition", "build_s", "render_s"]

# Prefix of the per-parameter columns once read: the harness's per-parameter columns (those
# between `params` and `status`, headed by the bare parameter name) are renamed to
# "param.<name>" on load, so that code reading a parameter says so.
PARAM_PREFIX = "param."

# Measured and global columns the harness renamed so that no column name repeats (pandas
# renames a repeat `max_depth.1`, csv.DictReader keeps the last): old name -> new name.
# A file with an old name after `status` was written before; `accelbench convert-csv`
# converts it. The harness's column table (`accelbench columns`) lists the same renames.
RENAMED_COLUMNS = {
    "max_depth": "tree_depth",
    "width": "image_width",
    "height": "image_height",
    "threads": "render_threads",
}

# Median of the .reps.csv must reproduce the summary's median to this relative tolerance.
REPS_MEDIAN_RTOL = 1e-6

# Values every numeric column must hold where it is not empty: a finite number, never
# negative (counts, sizes, errors, times). Times are more: a measured duration is > 0 (the
# standard deviation may be 0). A NaN, an infinity, a negative or a zero time is a broken
# measurement or a corrupted file, never a result: loading refuses it, naming the cell.
POSITIVE_TIME_COLUMNS = [c for c in TIMING_COLUMNS if not c.endswith("_stddev")]
REPS_TIME_COLUMNS = ["build_s", "render_s"]


class ContractError(ValueError):
    """A CSV that does not follow the harness's contract."""


@dataclass
class ProvenanceGroup:
    label: str
    fields: dict[str, str]
    files: list[str]
    rows: int

    def describe(self) -> str:
        sha = self.fields["git_sha"]
        dirty = " (dirty)" if self.fields["git_dirty"] == "true" else ""
        return (
            f"{self.label}: commit {sha[:12]}{dirty}, cpu {self.fields['cpu']}, "
            f"{self.fields['compiler']}, {self.fields['build_type']}, flags {self.fields['compile_flags']}, "
            f"isa {self.fields['isa']}, "
            f"Embree {self.fields['embree_version']} (kernels {self.fields['embree_isa']}) ({self.rows} rows from "
            f"{', '.join(self.files)})"
        )


@dataclass
class Results:
    """All rows of the loaded CSVs plus what loading found out about them."""

    rows: pd.DataFrame
    groups: list[ProvenanceGroup]
    warnings: list[str] = field(default_factory=list)
    reps: pd.DataFrame | None = None
    files: list[str] = field(default_factory=list)

    @property
    def mixed(self) -> bool:
        return len(self.groups) > 1

    def has_error_columns(self) -> bool:
        return (
            all(c in self.rows.columns for c in ("false_misses", "false_hits"))
            and self.rows[["false_misses", "false_hits"]].notna().any().any()
        )

    def ok(self) -> pd.DataFrame:
        return self.rows[self.rows["status"] == "ok"]

    def is_case(self) -> pd.Series:
        """Rows of robustness-catalogue cases: model `case-<id>:<name>`, or a verdict."""
        return self.rows["model"].str.startswith(CASE_PREFIX) | (self.rows["verdict"] != "")

    def case_rows(self) -> pd.DataFrame:
        return self.rows[self.is_case()]

    def measured_rows(self) -> pd.DataFrame:
        """Every row that measures a structure on a model (not a catalogue case)."""
        return self.rows[~self.is_case()]


def parse_params(text: str) -> dict[str, str]:
    """The canonical "k=v;k=v" text of the `params` column as a dict (values normalised)."""
    out: dict[str, str] = {}
    text = (text or "").strip()
    if not text:
        return out
    for item in text.split(";"):
        if not item.strip():
            continue
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ContractError(f"malformed params entry {item!r} in {text!r} (expected k=v;k=v)")
        out[key.strip()] = normalise_value(value)
    return out


def normalise_value(value: str) -> str:
    """Canonical text of a parameter value, so that "1", "1.0" and " 1" compare equal."""
    v = str(value).strip()
    low = v.lower()
    if low in ("true", "false"):
        return low
    try:
        f = float(v)
    except ValueError:
        return v
    if math.isfinite(f) and f == int(f):
        return str(int(f))
    return repr(f)


def read_header(path: Path) -> list[str]:
    with path.open(newline="") as fh:
        try:
            return next(csv.reader(fh))
        except StopIteration:
            raise ContractError(f"{path}: empty file (no header)") from None


def old_header_message(path: Path, header: list[str]) -> str | None:
    """For a results header from before the renames (an old name after `status`): what
    changed and how to convert it. None for any other header."""
    names = [h.strip() for h in header]
    if "status" not in names:
        return None
    after = names[names.index("status") + 1 :]
    if not any(n in RENAMED_COLUMNS for n in after):
        return None
    renames = ", ".join(f"{a} -> {b}" for a, b in RENAMED_COLUMNS.items())
    return (
        f"{path}: written before the measured and global columns were renamed so that no "
        f"name repeats ({renames}; the parameter columns keep their names); convert it with "
        f"`accelbench convert-csv {path} NEW`"
    )


def _rename_param_columns(header: list[str]) -> list[str]:
    """Per-parameter columns sit between `params` and `status`; prefix them (see PARAM_PREFIX)."""
    names = [h.strip() for h in header]
    if "params" in names and "status" in names:
        lo, hi = names.index("params"), names.index("status")
        names = [PARAM_PREFIX + n if lo < i < hi else n for i, n in enumerate(names)]
    return names


def scan_records(path: Path) -> list[int]:
    """The line each data row starts on (1-based, the header is line 1). Refuses, naming the
    line, a row with more or fewer fields than the header (a row cut short), an empty line,
    and a file whose last row has no line break (the harness ends every row with one: a
    file that does not was cut while it was written)."""
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        line = raw[: e.start].count(b"\n") + 1
        raise ContractError(f"{path}: line {line}: not UTF-8 text ({e.reason})") from None
    starts: list[int] = []
    problems: list[str] = []
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    try:
        width = len(next(reader))
        line = reader.line_num + 1
        for record in reader:
            start, line = line, reader.line_num + 1
            row = len(starts) + 1
            if not record:
                problems.append(f"line {start}: an empty line")
            elif len(record) != width:
                problems.append(
                    f"line {start} (row {row}): {len(record)} fields but the header has "
                    f"{width}" + (" (the row is cut short)" if len(record) < width else "")
                )
            starts.append(start)
    except StopIteration:
        raise ContractError(f"{path}: empty file (no header)") from None
    except csv.Error as e:
        raise ContractError(f"{path}: line {reader.line_num}: not a well-formed CSV ({e})") from None
    if text and not text.endswith("\n"):
        problems.append(
            f"line {text.count(chr(10)) + 1} (the last row) has no line break at its end: "
            f"the file was cut while it was written"
        )
    if problems:
        raise ContractError(
            f"{path}: "
            + "; ".join(problems[:5])
            + (f"; and {len(problems) - 5} more" if len(problems) > 5 else "")
        )
    return starts


def record_lines(starts: list[int], index) -> str:
    """ "line 3 (row 2)" for up to five data rows (row: counted from 1 after the header)."""
    picked = [int(i) for i in list(index)[:5]]
    more = f" and {len(index) - 5} more" if len(index) > 5 else ""
    return ", ".join(f"line {starts[i]} (row {i + 1})" for i in picked) + more


def to_numbers(
    df: pd.DataFrame, columns: list[str], starts: list[int], positive: list[str] = ()
) -> list[str]:
    """Converts the columns in place (empty text = missing); returns the problems found,
    each naming the column, the lines and an example value. Non-empty cells must be finite
    and not negative; those of `positive` columns greater than 0."""
    problems = []
    for col in columns:
        if col not in df.columns:
            continue
        text = df[col].astype(str).str.strip()
        nums = pd.to_numeric(text.where(text != ""), errors="coerce").astype(float)
        present = text != ""
        checks = [
            (
                present & nums.isna() & ~text.str.lower().isin(["nan", "-nan", "+nan"]),
                "non-numeric values",
                "",
            ),
            (
                present & ~np.isfinite(nums.fillna(0.0))
                | present & nums.isna() & text.str.lower().isin(["nan", "-nan", "+nan"]),
                "values that are not finite",
                "",
            ),
            (present & np.isfinite(nums.fillna(0.0)) & (nums < 0), "negative values", ""),
        ]
        if col in positive:
            checks.append((present & (nums == 0), "zero times", ": a measured duration is > 0"))
        for bad, what, note in checks:
            if bad.any():
                idx = df.index[bad]
                problems.append(
                    f"column {col!r} has {what} on {record_lines(starts, idx)} (e.g. {text[bad].iloc[0]!r}){note}"
                )
                break
        df[col] = nums
    return problems


def check_settings(df: pd.DataFrame, starts: list[int]) -> list[str]:
    """A `ray_set` the harness does not make, and a thread count, image size or sample
    count that is not a whole number of at least 1 (0.5 threads, 0 pixels): the tables
    select rows by these, so a wrong one would put a row where it does not belong."""
    problems = []
    sets = (CAMERA_SET,) + RAY_SETS
    bad = ~df["ray_set"].isin(sets)
    if bad.any():
        problems.append(
            f"column 'ray_set' must be one of {', '.join(sets)} (or empty: camera); found "
            f"{sorted(set(df['ray_set'][bad]))} on {record_lines(starts, df.index[bad])}"
        )
    for col in COUNT_SETTING_COLUMNS:
        if col not in df.columns:
            continue
        text = df[col].astype(str).str.strip()
        nums = pd.to_numeric(text.where(~text.isin(["", "nan"])), errors="coerce")
        given = ~text.isin(["", "nan"])
        bad = given & ~(nums.notna() & (nums >= 1) & (nums == nums.round()))
        if bad.any():
            problems.append(
                f"column {col!r} must be a whole number of at least 1; found "
                f"{sorted(set(text[bad]))} on {record_lines(starts, df.index[bad])}"
            )
    return problems


def check_text_columns(df: pd.DataFrame, starts: list[int]) -> list[str]:
    """The columns of words (status, fp_mode, verdict, git_dirty; model, accel and config
    non-empty; params parsed into param_dict), normalised in place; the problems found."""
    problems: list[str] = []
    status = df["status"].str.strip().str.lower()
    bad_status = ~status.isin(STATUSES)
    if bad_status.any():
        problems.append(
            f"column 'status' must be one of {', '.join(STATUSES)}; found "
            f"{sorted(set(df['status'][bad_status]))} on {record_lines(starts, df.index[bad_status])}"
        )
    df["status"] = status

    bad_mode = ~df[FP_MODE_COLUMN].isin(FP_MODES)
    if bad_mode.any():
        problems.append(
            f"column {FP_MODE_COLUMN!r} must be one of {', '.join(FP_MODES)}; found "
            f"{sorted(set(df[FP_MODE_COLUMN][bad_mode]))} on {record_lines(starts, df.index[bad_mode])}"
        )

    if "verdict" in df.columns:
        verdict = df["verdict"].str.strip().str.lower()
        bad = ~verdict.isin(VERDICTS + ("",))
        if bad.any():
            problems.append(
                f"column 'verdict' must be pass, fail or empty; found "
                f"{sorted(set(df['verdict'][bad]))} on {record_lines(starts, df.index[bad])}"
            )
        df["verdict"] = verdict

    for col in ("model", "accel", "config"):
        empty = df[col].str.strip() == ""
        if empty.any():
            problems.append(f"column {col!r} is empty on {record_lines(starts, df.index[empty])}")

    try:
        df["param_dict"] = [parse_params(p) for p in df["params"]]
    except ContractError as e:
        problems.append(str(e))

    dirty = df["git_dirty"].str.strip().str.lower()
    dirty = dirty.replace({"1": "true", "0": "false", "yes": "true", "no": "false"})
    if not dirty.isin(["true", "false"]).all():
        bad = ~dirty.isin(["true", "false"])
        problems.append(
            f"column 'git_dirty' must be true/false; found "
            f"{sorted(set(df['git_dirty'][bad]))} on {record_lines(starts, df.index[bad])}"
        )
    df["git_dirty"] = dirty
    return problems


def read_csv(path: str | Path) -> pd.DataFrame:
    """Reads one harness CSV and checks it against the contract; raises ContractError."""
    path = Path(path)
    if not path.is_file():
        raise ContractError(f"{path}: no such file")
    if path.name.endswith(".reps.csv"):
        raise ContractError(
            f"{path}: this is a per-repetition file; pass the summary CSV "
            f"beside it (its .reps.csv is read automatically)"
        )
    if path.name.endswith(".inputs.csv"):
        raise ContractError(
            f"{path}: this is a run's record of its inputs (the sha256 of its config, model and "
            f"ray files); pass the results CSV beside it"
        )
    header = read_header(path)
    if (old := old_header_message(path, header)) is not None:
        raise ContractError(old)
    starts = scan_records(path)
    names = _rename_param_columns(header)
    missing = [c for c in REQUIRED_COLUMNS if c not in names]
    if missing:
        raise ContractError(f"{path}: missing required columns: {', '.join(missing)}")
    dups = sorted({n for n in names if names.count(n) > 1})
    if dups:
        raise ContractError(f"{path}: duplicate column names: {', '.join(dups)}")

    try:
        df = pd.read_csv(path, header=0, names=names, dtype=str, keep_default_na=False)
    except (pd.errors.ParserError, ValueError) as e:
        raise ContractError(f"{path}: not a well-formed CSV ({e})") from None
    if df.empty:
        raise ContractError(f"{path}: no data rows")
    if "ray_set" not in df.columns:
        df["ray_set"] = CAMERA_SET
    df["ray_set"] = df["ray_set"].str.strip().replace("", CAMERA_SET)
    if FP_MODE_COLUMN not in df.columns:
        df[FP_MODE_COLUMN] = "ieee"
    df[FP_MODE_COLUMN] = df[FP_MODE_COLUMN].str.strip()
    problems = check_settings(df, starts)  # on the text as written
    problems += to_numbers(df, NUMERIC_COLUMNS, starts, POSITIVE_TIME_COLUMNS)
    if "render_cpu_s_median" in df.columns:
        problems += to_numbers(df, ["render_cpu_s_median"], starts)

    problems += check_text_columns(df, starts)

    if problems:
        raise ContractError(f"{path}: " + "; ".join(problems))

    dup = df.duplicated(KEY_COLUMNS, keep=False)
    if dup.any():
        keys = df.loc[dup, KEY_COLUMNS].drop_duplicates().head(3).to_dict("records")
        raise ContractError(f"{path}: the key ({', '.join(KEY_COLUMNS)}) must be unique; repeated: {keys}")
    df["source"] = str(path)
    for col in (ISA_COLUMN, EMBREE_ISA_COLUMN, COMPILE_FLAGS_COLUMN):
        if col not in df.columns:
            df[col] = UNKNOWN
    for col in PLUGIN_COLUMNS + [TIMED_WITH_COLUMN]:
        df[col] = df[col].fillna("").astype(str) if col in df.columns else ""
    for col in PROVENANCE_IDENTITY + ["timestamp"]:
        df[col] = df[col].astype(str).str.strip()
    return df
