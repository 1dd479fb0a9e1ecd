"""The report's side: its numbers (results/report/report-tables.csv) and its models.

The report ("Implementation and Analysis of Acceleration Data Structures in Ray Tracing",
Freiburg 2022) measured four scanned models (Table 4) and two downloaded scenes (Table 5).
Two of the scans and both scenes are not available to us; REPORT_MODELS names what stands
in for each, and every output that shows such a model says so.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from .schema import ContractError

REPO_ROOT = Path(__file__).resolve().parents[3]
DEFAULT_REPORT_NUMBERS = REPO_ROOT / "results" / "report" / "report-tables.csv"

REPORT_NUMBERS_COLUMNS = [
    "table",
    "model",
    "accelerator",
    "setting",
    "primitives",
    "nodes",
    "prim_tests",
    "build_s",
    "render_s",
]

# The report's Table 1: the machine and image its numbers come from.
REPORT_MACHINE = "Intel i7-8565U, 16 GB; 640x480, 1 sample, Phong, 1 light"
REPORT_PRIMARY_RAYS = 640 * 480


@dataclass(frozen=True)
class ReportModel:
    key: str  # the report's model name in report-tables.csv
    label: str  # as the report prints it
    short: str  # for compact evidence text
    ours: tuple[str, ...]  # our model names, first present in the data wins
    stand_in: str | None = None  # why ours is not the same model, None when it is

    @property
    def column_label(self) -> str:
        return self.label if self.stand_in is None else f"{self.label} (stand-in)"


REPORT_MODELS = [
    ReportModel("stanford-bunny", "Stanford bunny", "bunny", ("stanford-bunny",)),
    ReportModel("igea", "Igea", "Igea", ("igea",)),
    ReportModel(
        "asian-dragon",
        "Asian Dragon",
        "Dragon",
        ("stanford-dragon",),
        "the Stanford dragon (871,414 triangles / 437,645 vertices) stands in for "
        "the report's Asian Dragon (539,205 primitives)",
    ),
    ReportModel(
        "happy-buddha",
        "Happy Buddha",
        "Buddha",
        ("happy-buddha-100k",),
        "happy-buddha-100k (100,000 triangles, a decimated copy) stands in for the "
        "report's 1.08M-primitive Happy Buddha",
    ),
    ReportModel(
        "trees",
        "Trees",
        "Trees",
        ("procedural-forest", "forest"),
        "a procedural forest (dense clusters of small triangles beside empty ground "
        "and sky) stands in for the report's downloaded Trees scene",
    ),
    ReportModel(
        "sci-fi-city",
        "Sci-Fi Tropical City",
        "City",
        ("procedural-city", "city"),
        "a procedural city (detailed geometry covering the whole image) stands in "
        "for the report's downloaded Sci-Fi Tropical City",
    ),
]
REPORT_MODEL = {m.key: m for m in REPORT_MODELS}

TABLE4_MODELS = ["stanford-bunny", "igea", "asian-dragon", "happy-buddha"]
TABLE5_MODELS = ["trees", "sci-fi-city"]
TABLE2_MODEL = "stanford-bunny"


def our_model(report_model: str, present: set[str]) -> str:
    """Our model name for a report model: the first candidate present in the data."""
    cands = REPORT_MODEL[report_model].ours
    for c in cands:
        if c in present:
            return c
    return cands[0]


def load_report_numbers(path: str | Path = DEFAULT_REPORT_NUMBERS) -> pd.DataFrame:
    path = Path(path)
    if not path.is_file():
        raise ContractError(
            f"{path}: reference table not found (expected a copy of shared/reference/report-tables.csv)"
        )
    df = pd.read_csv(path)
    missing = [c for c in REPORT_NUMBERS_COLUMNS if c not in df.columns]
    if missing:
        raise ContractError(f"{path}: missing required columns: {', '.join(missing)}")
    unknown = sorted(set(df["model"]) - set(REPORT_MODEL))
    if unknown:
        raise ContractError(f"{path}: unknown report models {unknown}")
    return df


def report_value(
    report_nums: pd.DataFrame, model: str, accel: str, setting: str, column: str
) -> float | None:
    sel = report_nums[
        (report_nums["model"] == model)
        & (report_nums["accelerator"] == accel)
        & (report_nums["setting"] == setting)
    ]
    if sel.empty:
        return None
    return float(sel.iloc[0][column])
