"""Rows timed alternately in the same processes (a config's `interleave: true`): the
harness times the combinations of one model and ray set in one child process, repetition
by repetition, and names in each row's `timed_with` the combo_ids timed with it.

Two such rows can be compared process by process: in each process, the ratio of their
median render times is of two medians timed under the same load, turn by turn. The worse
of those ratios is how the goals read "the worse of two processes" (docs/benchmarks.md).
Two rows timed apart (an empty `timed_with`, every file from before the column) have no
such ratio: two medians of different processes are never read as one process's.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from ..inputs.load import reps_path
from ..inputs.schema import TIMED_WITH_COLUMN

# (repetitions file, config, combo_id) -> {process: median render_s of its repetitions there}
ProcessMedians = dict[tuple[str, str, str], dict[str, float]]


def timed_with(row: pd.Series) -> set[str]:
    """The combo_ids a row was timed alternately with; empty when it was timed alone."""
    text = str(row.get(TIMED_WITH_COLUMN, "") or "")
    return {c.strip() for c in text.split(";") if c.strip()}


def process_medians(reps: pd.DataFrame | None, column: str = "render_s") -> ProcessMedians:
    """Per combination of each repetitions file, the median of `column` over its repetitions
    in each process; {} without repetitions, or without their `process` or `combo_id`."""
    if reps is None or not {"process", "combo_id"} <= set(reps.columns):
        return {}
    known = reps[reps["process"].astype(str).str.strip() != ""]
    keys = [known["source"], known["config"], known["combo_id"], known["process"].astype(str).str.strip()]
    out: ProcessMedians = {}
    for (source, config, combo, process), median in known.groupby(keys)[column].median().items():
        out.setdefault((source, config, combo), {})[process] = float(median)
    return out


def _key(row: pd.Series) -> tuple[str, str, str]:
    return (str(reps_path(Path(row["source"]))), str(row["config"]), str(row.get("combo_id", "")))


def worse_process_ratio(medians: ProcessMedians, row: pd.Series, base: pd.Series | None) -> float:
    """min over the processes p of both of median(base's render_s in p) / median(row's in
    p): the row's speed over the base's (> 1: faster) in its worse process. NaN unless the
    base was timed alternately with the row (its combo_id in the row's `timed_with`; the
    base itself: 1.0 when it was timed alternately with any) in the same file, and both
    have repetitions in at least one common process."""
    if base is None or row.get("source") != base.get("source"):
        return float("nan")
    together = timed_with(row)
    if not together or (base.get("combo_id") not in together and _key(row) != _key(base)):
        return float("nan")
    own, other = medians.get(_key(row), {}), medians.get(_key(base), {})
    ratios = [other[p] / own[p] for p in own.keys() & other.keys()]
    return min(ratios) if ratios else float("nan")
