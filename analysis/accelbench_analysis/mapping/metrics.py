"""What every output measures by: the metrics a table row or a claim reads (ours and the
report's column), the ratio of two numbers, the traversal variant that stands for a
structure, and a table's structure rows (one per structure, or one per variant)."""

from __future__ import annotations

from dataclasses import dataclass

from .formatting import is_missing
from .selection import Picker, Structure, variant_label

# Our traversal variant used wherever one BVH/LBVH row must stand for the structure (the
# "relative to BVH" denominators and the claims): the report's own order first.
VARIANT_PREFERENCE = ("report", "ordered", "")


@dataclass(frozen=True)
class Metric:
    key: str
    label: str
    ours: str  # our column (median for times)
    report: str  # report-tables.csv column
    timed: bool


METRICS = [
    Metric("build", "Build time (s)", "build_s_median", "build_s", True),
    Metric("render", "Render time (s)", "render_s_median", "render_s", True),
    Metric("prim_tests", "#int. tests (primitive tests, all rays)", "prim_tests", "prim_tests", False),
    Metric("nodes", "#nodes", "nodes", "nodes", False),
]
METRIC = {m.key: m for m in METRICS}


def preferred_variant(variants: list[str]) -> str | None:
    for v in VARIANT_PREFERENCE:
        if v in variants:
            return v
    return variants[0] if variants else None


def ratio(ours, report) -> float | None:
    if is_missing(ours) or is_missing(report) or report == 0:
        return None
    return float(ours) / float(report)


@dataclass
class StructureRow:
    structure: Structure
    variant: str | None
    label: str


def structure_rows(picker: Picker, models: list[str]) -> list[StructureRow]:
    rows = []
    for s in picker.structures():
        variants = picker.variants(models, s.spec)
        if len(variants) <= 1:
            rows.append(StructureRow(s, None, s.label))
        else:
            rows += [StructureRow(s, v, variant_label(s.label, v, variants)) for v in variants]
    return rows
