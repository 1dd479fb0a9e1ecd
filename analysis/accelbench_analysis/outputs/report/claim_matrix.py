"""Every claim under every setting (mapping/settings.py): the factor matrix.

Each claim is judged at our defaults, at the faithful setting and at each setting that
switches one factor of the faithful setting back to our default, by the same code on the
rows that setting declares. Nothing is chosen: the matrix is written whole
(tables/claims_factors.csv, columns claim, setting, value, verdict, and the heat map
figures/claims_factors.png from one Vega-Lite specification), and a claim's cause is the
factor whose switch flips its faithful verdict, or "no single factor". A cell whose margin
lies inside the spread measured on the rows it read shows `within noise` (mark_noise), and a
verdict within noise neither is flipped nor flips one: a factor that "flips" a claim only
inside the noise (the kd-tree build=nlogn setting builds the same tree) is no cause.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from ...inputs.schema import Results
from ...mapping.settings import DEFAULT, FAITHFUL, SETTING, SETTINGS, Setting
from ...mapping.spread import Spread, claim_spread
from .claims import CLAIMS, FAILS, HOLDS, NOT_COMPARABLE, Claim, Finding, OurSource, evaluate, holds_within

MATRIX_COLUMNS = ("claim", "setting", "value", "verdict")
NOT_MEASURED = "not measured"
WITHIN_NOISE = "within noise"
BY_CONSTRUCTION = "by construction"


def setting_source(results: Results, report_nums: pd.DataFrame, setting: Setting) -> OurSource:
    return OurSource(results, report_nums, setting)


@dataclass
class Cell:
    """One claim at one setting."""

    finding: Finding
    read: set[tuple[str, str]] = field(default_factory=set)
    models_read: set[str] = field(default_factory=set)
    # within_noise's answer for this cell, once asked (mark_noise asks it for every cell).
    noise: tuple[bool, Spread] | None = None

    @property
    def verdict(self) -> str:
        """The verdict of the medians: holds, does not hold or not comparable."""
        return self.finding.verdict if self.finding.verdict in (HOLDS, FAILS) else NOT_COMPARABLE

    @property
    def shown(self) -> str:
        """The verdict the matrix shows: `within noise` where the margin lies inside the
        spread measured on what the cell read (once that is known), else the verdict."""
        return WITHIN_NOISE if self.noise is not None and self.noise[0] else self.verdict


@dataclass
class Matrix:
    """cells[claim id][setting name]; sources[setting name]."""

    cells: dict[str, dict[str, Cell]]
    sources: dict[str, OurSource]
    claims: dict[str, Claim]  # by id, the claims the cells judge

    def verdict(self, claim_id: str, setting: str) -> str:
        return self.cells[claim_id][setting].verdict

    def shown(self, claim_id: str, setting: str) -> str:
        """What the matrix shows: the cell's (Cell.shown), and `by construction` where it
        holds only because it cannot fail: a claim that cannot fail, or a labelled variant
        (lbvh build=median, the median BVH's tree) holding where faithful does not."""
        at = self.cells[claim_id]
        v = at[setting].shown
        if v != HOLDS:
            return v
        if self.claims[claim_id].by_construction:
            return BY_CONSTRUCTION
        variant = SETTING[setting].by_construction and FAITHFUL in at and at[FAITHFUL].shown != HOLDS
        return BY_CONSTRUCTION if variant else v


def evaluate_matrix(
    results: Results,
    report_nums: pd.DataFrame,
    claims: list[Claim] | None = None,
    settings: tuple[Setting, ...] = SETTINGS,
) -> Matrix:
    claims = claims or CLAIMS
    cells: dict[str, dict[str, Cell]] = {c.id: {} for c in claims}
    sources = {}
    for s in settings:
        src = setting_source(results, report_nums, s)
        sources[s.name] = src
        for c in claims:
            finding = evaluate(c, src)
            if not src.picker.rows.shape[0]:
                finding = Finding(NOT_COMPARABLE, f"{NOT_MEASURED}: this run has no rows of setting {s.name}")
            cells[c.id][s.name] = Cell(finding, set(src.read), set(src.models_read))
    return Matrix(cells, sources, {c.id: c for c in claims})


def within_noise(
    matrix: Matrix, results: Results, c: Claim, setting: str, run: Results | None = None
) -> tuple[bool, Spread]:
    """Whether the claim's verdict at `setting` lies inside the spread measured on the
    combinations it read (at least the widest gap of `run`, every row of the run): some
    draw of its timed values within that spread gives the opposite verdict. Returns that
    and the spread."""
    cell = matrix.cells[c.id][setting]
    if cell.noise is None:
        spread = claim_spread(results, cell.read, run)
        inside = False
        if cell.verdict in (HOLDS, FAILS) and spread.value > 0:
            opposite = FAILS if cell.verdict == HOLDS else HOLDS
            inside = holds_within(c, matrix.sources[setting], spread.value, opposite)
        cell.noise = (inside, spread)
    return cell.noise


def mark_noise(matrix: Matrix, results: Results, run: Results | None = None) -> None:
    """Every cell's within_noise, so that the matrix, its causes and its heat map show
    which verdicts the measured spread decides (`run`: every row of the run, the floor)."""
    for c in matrix.claims.values():
        for setting in matrix.cells[c.id]:
            within_noise(matrix, results, c, setting, run)


def flipping_factors(matrix: Matrix, claim_id: str) -> list[str]:
    """The factor settings whose switch gives the opposite of the faithful verdict, both
    outside the noise where it was marked (labelled variants never count: they cannot
    fail)."""
    at = matrix.cells[claim_id]
    base = at[FAITHFUL].shown
    if base not in (HOLDS, FAILS):
        return []
    return [
        s.name
        for s in SETTINGS
        if s.name not in (DEFAULT, FAITHFUL)
        and not s.by_construction
        and {base, at[s.name].shown} == {HOLDS, FAILS}
    ]


def cause_text(matrix: Matrix, claim_id: str) -> str:
    """What decides the claim between our defaults and the faithful setting."""
    at = matrix.cells[claim_id]
    d, f = at[DEFAULT].shown, at[FAITHFUL].shown
    flips = flipping_factors(matrix, claim_id)
    if f == WITHIN_NOISE:
        return "within noise at the faithful setting: no factor is shown to decide it"
    if f not in (HOLDS, FAILS):
        return "not judged at the faithful setting"
    if flips:
        cited = [SETTING[n].evidence for n in flips if SETTING[n].evidence]
        return "flipped by " + ", ".join(flips) + "".join(f" ({e})" for e in cited)
    if d in (HOLDS, FAILS) and d != f:
        return "no single factor (default and faithful differ; no one switch flips it)"
    shown = {c.shown for c in at.values()}
    if len(shown - {NOT_COMPARABLE, WITHIN_NOISE}) > 1:
        return "no single factor"
    return (
        "the same at every setting where it is outside the noise"
        if WITHIN_NOISE in shown
        else "the same at every setting judged"
    )


def matrix_frame(matrix: Matrix) -> pd.DataFrame:
    rows = [
        {
            "claim": cid,
            "setting": s.name,
            "value": at[s.name].finding.evidence,
            "verdict": matrix.shown(cid, s.name),
        }
        for cid, at in matrix.cells.items()
        for s in SETTINGS
    ]
    return pd.DataFrame(rows, columns=list(MATRIX_COLUMNS))


MATRIX_MARKS = {HOLDS: "✓", FAILS: "✗", WITHIN_NOISE: "≈", BY_CONSTRUCTION: "□", NOT_COMPARABLE: "–"}
MATRIX_LEGEND = (
    "✓ holds, ✗ does not hold, ≈ within noise (either, by a margin inside the measured "
    "spread), □ holds by construction (the claim, or the labelled variant, cannot fail), "
    "– not comparable"
)


def matrix_markdown(matrix: Matrix) -> list[str]:
    """The matrix as a table: one row per claim, one column per setting (MATRIX_MARKS), and
    the cause."""
    head = "| claim | " + " | ".join(s.name for s in SETTINGS) + " | cause |"
    rule = "|:---|" + ":---:|" * len(SETTINGS) + ":---|"
    out = [head, rule]
    for cid in matrix.cells:
        out.append(
            f"| {cid} | "
            + " | ".join(MATRIX_MARKS[matrix.shown(cid, s.name)] for s in SETTINGS)
            + f" | {cause_text(matrix, cid)} |"
        )
    return out


VERDICT_COLOURS = {
    HOLDS: "#4c9a5b",
    FAILS: "#c8553d",
    WITHIN_NOISE: "#e3b448",
    BY_CONSTRUCTION: "#8fb3d9",
    NOT_COMPARABLE: "#bbbbbb",
}


def heat_map_spec(frame: pd.DataFrame) -> dict:
    """Claims x settings, each cell coloured by its verdict (one specification: the page
    embeds it, the PNG is rendered from it)."""
    data = json.loads(frame.to_json(orient="records"))
    return {
        "$schema": "https://vega.github.io/schema/vega-lite/v6.json",
        "title": "Every claim under every setting (one factor switched back from faithful per column)",
        "data": {"values": data},
        "mark": {"type": "rect", "stroke": "white"},
        "encoding": {
            "x": {"field": "setting", "type": "nominal", "sort": [s.name for s in SETTINGS], "title": None},
            "y": {
                "field": "claim",
                "type": "nominal",
                "sort": list(dict.fromkeys(frame["claim"])),
                "title": None,
            },
            "color": {
                "field": "verdict",
                "type": "nominal",
                "scale": {"domain": list(VERDICT_COLOURS), "range": list(VERDICT_COLOURS.values())},
            },
            "tooltip": [{"field": c} for c in MATRIX_COLUMNS],
        },
        "config": {"axis": {"labelLimit": 300}},
    }


def write_matrix(matrix: Matrix, tables_dir: Path, figures_dir: Path | None = None) -> list[Path]:
    """tables/claims_factors.csv and, where vl-convert renders, figures/claims_factors.png
    beside its specification figures/claims_factors.vl.json."""
    frame = matrix_frame(matrix)
    tables_dir.mkdir(parents=True, exist_ok=True)
    csv = tables_dir / "claims_factors.csv"
    frame.to_csv(csv, index=False)
    written = [csv]
    if figures_dir is not None:
        figures_dir.mkdir(parents=True, exist_ok=True)
        spec = heat_map_spec(frame)
        spec_path = figures_dir / "claims_factors.vl.json"
        spec_path.write_text(json.dumps(spec, separators=(",", ":"), allow_nan=False))
        import vl_convert

        png = figures_dir / "claims_factors.png"
        png.write_bytes(vl_convert.vegalite_to_png(spec, scale=1.5))
        written += [spec_path, png]
    return written
