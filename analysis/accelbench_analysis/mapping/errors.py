"""How wrong a row is: the error columns, labelled and formatted once for every
table that lists our rows.

The harness traces each combination's primary rays (the `rays` column) through the
double-precision `reference` accelerator too and counts, against it: false misses, false
hits, wrong primitives (both hit, different primitive, t differing by more than 64 float
ulps; ties are not errors) and NaN results; the float-ulp distance of t where both hit the
same primitive (median and maximum); and for image runs the image RMSE and hole pixels
against the reference image.

An empty cell means one of two things, and the tables keep them apart: the comparison did
not run for that row ("not measured": config `errors: false`, or an older harness), or it
ran but the quantity does not apply ("n/a": no ray qualified for a t error, not an image
run).
"""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

from .formatting import fmt_count, fmt_sig

NOT_MEASURED = "not measured"
NOT_APPLICABLE = "n/a"


@dataclass(frozen=True)
class ErrorMetric:
    column: str
    label: str  # a table row's or section's label
    short: str  # a column header in wide tables
    kind: str  # "count", "ulp" or "fraction": how the value is printed
    image: bool = False  # only image runs (shading=true) have it


ERROR_METRICS = [
    ErrorMetric("false_misses", "False misses (primary rays, vs the reference)", "false misses", "count"),
    ErrorMetric("false_hits", "False hits (primary rays, vs the reference)", "false hits", "count"),
    ErrorMetric("prim_mismatches", "Wrong primitive (t differs by > 64 ulps)", "wrong prims", "count"),
    ErrorMetric("nan_results", "NaN results", "NaN", "count"),
    ErrorMetric("t_err_ulp_p50", "t error vs the reference, median (float ulps)", "t ulp p50", "ulp"),
    ErrorMetric("t_err_ulp_max", "t error vs the reference, max (float ulps)", "t ulp max", "ulp"),
    ErrorMetric("image_rmse", "Image RMSE vs the reference image", "image RMSE", "fraction", True),
    ErrorMetric("hole_pixels", "Hole pixels vs the reference image", "hole pixels", "count", True),
]
ERROR_METRIC = {m.column: m for m in ERROR_METRICS}
# The counts that say whether the comparison ran for a row at all.
MEASURED_WHEN = ("false_misses", "false_hits", "prim_mismatches", "nan_results")
# The wrong answers summed in the Pareto figure and the compact cells.
WRONG_ANSWERS = ("false_misses", "false_hits", "prim_mismatches")


def _value(row, column: str):
    v = None if row is None else row.get(column)
    return None if v is None or pd.isna(v) else float(v)


def error_measured(row) -> bool:
    """Whether the reference comparison ran for this row."""
    return any(_value(row, c) is not None for c in MEASURED_WHEN)


def any_error_values(rows: pd.DataFrame) -> bool:
    cols = [c for c in MEASURED_WHEN if c in rows.columns]
    return bool(cols) and bool(rows[cols].notna().any().any())


def shown_metrics(rows: pd.DataFrame) -> list[ErrorMetric]:
    """Every error metric, the image ones only when some row has an image value."""
    has_image = any(
        m.column in rows.columns and rows[m.column].notna().any() for m in ERROR_METRICS if m.image
    )
    return [m for m in ERROR_METRICS if has_image or not m.image]


def fmt_error(value, metric: ErrorMetric) -> str:
    if metric.kind == "fraction":
        return fmt_sig(value)
    if metric.kind == "ulp" and value != int(value):
        return fmt_sig(value)  # a median of an even count can fall between two integers
    return fmt_count(value)


def error_text(row, metric: ErrorMetric) -> str:
    """One error cell of an existing row: the value, "n/a" or "not measured"."""
    v = _value(row, metric.column)
    if v is not None:
        return fmt_error(v, metric)
    if not error_measured(row):
        return NOT_MEASURED
    return NOT_APPLICABLE


COMPACT_HEADER = "false misses / false hits / wrong prims / NaN"


def compact_errors(row) -> str:
    """The four counts in one cell ("0 / 2 / 0 / 0"), or "not measured"."""
    if not error_measured(row):
        return NOT_MEASURED
    return " / ".join(
        error_text(row, ERROR_METRIC[c])
        for c in ("false_misses", "false_hits", "prim_mismatches", "nan_results")
    )


def wrong_answers(rows: pd.DataFrame) -> pd.Series:
    """False misses + false hits + wrong primitives per row (a missing count adds nothing)."""
    return rows[list(WRONG_ANSWERS)].fillna(0).sum(axis=1)


def note_errors(rows: pd.DataFrame) -> str:
    """What the error numbers are, or that the CSV has none; for every table's notes."""
    if not any_error_values(rows):
        return (
            "Error against the reference: not measured. No row of the CSV has error "
            "values (the harness ran without the reference comparison, config "
            "`errors: false`, or predates it); the error rows/columns are kept and say "
            "so instead of being dropped."
        )
    return (
        "Errors are ours only (the report measured none): counts over each row's primary "
        "rays against the double-precision `reference` accelerator. Wrong primitive: both "
        "hit, different primitive, t differs by more than 64 float ulps (ties are not "
        "errors). t error: float-ulp distance of t where both hit the same primitive "
        "(n/a: no ray qualified). 'not measured': the comparison did not run for that "
        "row."
    )
