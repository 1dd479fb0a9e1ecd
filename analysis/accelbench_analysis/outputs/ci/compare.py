"""`compare A B`: two runs (run directories or results CSVs) set side by side.

Per combination measured in both (same config, model, structure, parameters, ray set and
render settings, on the same machine and ISA): both medians of the trace and build time,
B/A with an interval, and a two-sided Mann-Whitney U test over the two runs' repetitions
(the .reps.csv samples), as google/benchmark's tools/compare.py does it ("am I just looking
at the noise?"). A time is flagged changed only when the test says the two samples differ
(p < ALPHA) and B/A lies beyond MIN_CHANGE either way: two processes of one commit differ
by a few percent systematically, which a U test over ten repetitions finds significant,
and that is not a change of the code. The interval shown beside B/A divides the two
medians' 95% intervals end by end (B's low end by A's high end, and the other way round). Counts (nodes, primitive tests,
hits, ...) are deterministic: any difference is listed separately (on one commit there is
none). Rows of different machines or ISAs are never compared: B's rows on a machine A did
not measure are listed as unmatched, and two runs with no machine in common are refused."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from ...inputs.load import is_companion, load_results
from ...inputs.schema import RENDER_SETTING_COLUMNS, ContractError, Results
from ...mapping.formatting import md_escape, md_table
from .regress import ERROR_COUNTS, EXACT_COUNTS
from .u_test import mann_whitney_u, smallest_p

ALPHA = 0.01
MIN_CHANGE = 0.10
MACHINE = ["cpu", "isa", "embree_isa"]
COMBINATION = ["config", "model", "accel", "params", "ray_set", *RENDER_SETTING_COLUMNS]
TIMES = {"trace": "render_s", "build": "build_s"}
COUNTS = [*EXACT_COUNTS, *ERROR_COUNTS]


@dataclass
class TimeChange:
    """One time of one combination in both runs."""

    measure: str  # trace or build
    a: float  # medians
    b: float
    ratio: float  # b / a
    lo: float  # the ratio's interval: B's median CI over A's (conservative, both ends)
    hi: float
    p: float | None  # None: too few repetitions for the test
    n_a: int
    n_b: int
    changed: bool


@dataclass
class Paired:
    key: tuple
    label: str
    times: list[TimeChange]
    counts: list[tuple[str, float, float]]  # the counts that differ: (column, A, B)


@dataclass
class Comparison:
    a_name: str
    b_name: str
    machines: list[str]
    pairs: list[Paired]
    only_a: list[str]
    only_b: list[str]


def result_files(path: Path) -> list[Path]:
    """A results CSV as given; a run directory's results CSVs (in csv/ or the directory)."""
    if path.is_file():
        return [path]
    if not path.is_dir():
        raise ContractError(f"{path}: neither a results CSV nor a run directory")
    folder = path / "csv" if (path / "csv").is_dir() else path
    files = sorted(f for f in folder.glob("*.csv") if not is_companion(f))
    if not files:
        raise ContractError(f"{folder}: no results CSV")
    return files


def load_run(path: Path) -> Results:
    return load_results(result_files(path))


def _machine(row: pd.Series) -> str:
    return f"{row['cpu']} (isa {row['isa']}, Embree kernels {row['embree_isa']})"


def _samples(results: Results, row: pd.Series, column: str) -> list[float]:
    reps = results.reps
    if reps is None or "combo_id" not in reps.columns:
        return []
    own = reps[(reps["config"] == row["config"]) & (reps["combo_id"] == row["combo_id"])]
    return [float(v) for v in own[column] if v == v]


def _time_change(
    measure: str, ra: pd.Series, rb: pd.Series, sa: list[float], sb: list[float]
) -> TimeChange | None:
    col = TIMES[measure]
    a, b = float(ra[f"{col}_median"]), float(rb[f"{col}_median"])
    if not (a > 0 and b > 0):
        return None
    lo_a, hi_a = float(ra[f"{col}_ci_lo"]), float(ra[f"{col}_ci_hi"])
    lo_b, hi_b = float(rb[f"{col}_ci_lo"]), float(rb[f"{col}_ci_hi"])
    lo = lo_b / hi_a if lo_b > 0 and hi_a > 0 else math.nan
    hi = hi_b / lo_a if hi_b > 0 and lo_a > 0 else math.nan
    enough = sa and sb and smallest_p(len(sa), len(sb)) < ALPHA
    p = mann_whitney_u(sa, sb) if enough else None
    beyond = b / a > 1 + MIN_CHANGE or b / a < 1 / (1 + MIN_CHANGE)
    return TimeChange(
        measure, a, b, b / a, lo, hi, p, len(sa), len(sb), p is not None and p < ALPHA and beyond
    )


def _label(row: pd.Series) -> str:
    parts = [row["model"], row.get("label", "") or row["accel"]]
    if row["params"]:
        parts.append(f"[{row['params']}]")
    if row.get("ray_set", "") not in ("", "camera"):
        parts.append(f"ray set {row['ray_set']}")
    threads = row.get("render_threads", math.nan)
    if threads == threads and float(threads) != 1:
        parts.append(f"{float(threads):g} threads")
    return " · ".join(p for p in parts if p)


def _keyed(results: Results) -> dict[tuple, pd.Series]:
    df = results.measured_rows()
    df = df[df["status"] == "ok"]
    out = {}
    for _, r in df.iterrows():
        out[tuple(str(r.get(c, "")) for c in MACHINE + COMBINATION)] = r
    return out


def compare_runs(a: Results, b: Results, a_name: str, b_name: str) -> Comparison:
    ka, kb = _keyed(a), _keyed(b)
    machines_a = {_machine(r) for r in ka.values()}
    machines_b = {_machine(r) for r in kb.values()}
    common = sorted(machines_a & machines_b)
    if ka and kb and not common:
        raise ContractError(
            f"{a_name} and {b_name} share no machine and ISA (A: {'; '.join(sorted(machines_a))}; "
            f"B: {'; '.join(sorted(machines_b))}): times of different machines are never compared"
        )
    pairs = []
    for key in (k for k in ka if k in kb):
        ra, rb = ka[key], kb[key]
        times = []
        for measure, col in TIMES.items():
            t = _time_change(measure, ra, rb, _samples(a, ra, col), _samples(b, rb, col))
            if t is not None:
                times.append(t)
        counts = [
            (c, float(ra[c]), float(rb[c]))
            for c in COUNTS
            if c in ra.index and c in rb.index and ra[c] == ra[c] and rb[c] == rb[c] and ra[c] != rb[c]
        ]
        pairs.append(Paired(key, _label(ra), times, counts))
    only_a = sorted(_label(ka[k]) for k in ka if k not in kb)
    only_b = sorted(_label(kb[k]) for k in kb if k not in ka)
    return Comparison(a_name, b_name, common, pairs, only_a, only_b)


def changed(c: Comparison) -> list[tuple[Paired, TimeChange]]:
    return [(p, t) for p in c.pairs for t in p.times if t.changed]


def worst_ratio(c: Comparison, measure: str = "trace") -> float:
    """The largest B/A of a time flagged changed (1 when none is)."""
    return max((t.ratio for _, t in changed(c) if t.measure == measure), default=1.0)


def _p_text(t: TimeChange) -> str:
    if t.p is None:
        return f"too few repetitions ({t.n_a}, {t.n_b})"
    return f"{t.p:.2g}"


def compare_markdown(c: Comparison) -> str:
    flagged = changed(c)
    counts = [p for p in c.pairs if p.counts]
    out = [
        f"# {md_escape(c.b_name)} against {md_escape(c.a_name)}",
        "",
        f"Machine{'s' if len(c.machines) > 1 else ''}: {'; '.join(md_escape(m) for m in c.machines) or 'none in common'}. "
        f"{len(c.pairs)} combinations in both; a time is changed when the Mann-Whitney U test over "
        f"the repetitions gives p < {ALPHA:g} and B/A lies beyond {MIN_CHANGE:.0%} either way "
        f"(the interval: B's median interval over A's, end by end).",
        "",
        f"- **Times changed:** {len(flagged)}",
        f"- **Counts changed:** {len(counts)} combinations (counts are deterministic: on one commit, none)",
        f"- **Only in A:** {len(c.only_a)}; **only in B:** {len(c.only_b)}",
        "",
        "## Every combination",
        "",
    ]
    rows = []
    for p in c.pairs:
        for t in p.times:
            rows.append(
                [
                    p.label,
                    t.measure,
                    f"{t.a:.4g}",
                    f"{t.b:.4g}",
                    f"{t.ratio:.3f}",
                    f"{t.lo:.3f}–{t.hi:.3f}",
                    _p_text(t),
                    "**changed**" if t.changed else "",
                ]
            )
    out += md_table(
        ["combination", "time", "A median (s)", "B median (s)", "B/A", "interval", "U test p", ""], rows
    )
    if counts:
        out += ["", "## Counts that changed", ""]
        out += md_table(
            ["combination", "count", "A", "B"],
            [[p.label, col, f"{x:g}", f"{y:g}"] for p in counts for col, x, y in p.counts],
        )
    for title, labels in (("Only in A", c.only_a), ("Only in B", c.only_b)):
        if labels:
            out += ["", f"## {title}", ""] + [f"- {md_escape(s)}" for s in labels]
    return "\n".join(out) + "\n"
