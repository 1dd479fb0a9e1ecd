"""CI regression check: a fresh run of configs/ci.yaml against the committed baseline.

Three tiers, from the strictest to the noisiest:

1. Deterministic counts. Tree shape (nodes, leaves, max_depth), traversal work
   (prim_tests, node_visits) and results (rays, hits, shadow_rays, shadow_hits) depend only
   on the code and the input, so they must equal the baseline exactly; sah_cost is a
   floating-point sum and must agree to a relative 1e-9. Any change fails, and so does a
   combination of the baseline that is missing from the run (or whose status changed).
   Combinations the run adds are listed, not failed.
2. Instruction counts (the `instructions` column: callgrind's Ir of the measured render).
   Independent of machine load but not of the compiler, hence a tolerance: more than +10%
   fails; less than -10% passes with a reminder to update the baseline.
3. Render time as a ratio to Embree's render time in the same run (same model, same render
   settings). Dividing by Embree cancels most of the machine's speed and load; what is left
   is still noisy on a shared 2-core machine, so a combination fails only when its ratio
   exceeds the baseline ratio by more than a factor (default 1.5) in two consecutive
   measurements: this run and the previous one (`--history`). A single exceedance cannot
   be decided and says so (exit code 3): re-measure and run again with the first run as
   history.

Exit codes: 0 pass, 1 regression, 2 bad input, 3 a time exceedance needs a second
measurement (nothing failed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from ...inputs.load import load_results
from ...inputs.schema import INSTRUCTIONS_COLUMN, KEY_COLUMNS, RENDER_SETTING_COLUMNS, ContractError, Results
from ...mapping.formatting import fmt_count, fmt_sig, md_table

EXIT_PASS, EXIT_REGRESSION, EXIT_BAD_INPUT, EXIT_REMEASURE = 0, 1, 2, 3

EXACT_COUNTS = [
    "nodes",
    "leaves",
    "tree_depth",
    "prim_tests",
    "node_visits",
    "rays",
    "hits",
    "shadow_rays",
    "shadow_hits",
]
# Hit errors against the `reference` accelerator are as deterministic as the counts: a change is
# a structure answering differently. Compared where the baseline has them (older
# baselines predate the columns).
ERROR_COUNTS = ["false_misses", "false_hits", "prim_mismatches", "nan_results"]
# Answers (not counters) of the third-party row, which vary between runs (tier_counts).
THIRD_PARTY_ANSWERS = ["hits", "shadow_hits", *ERROR_COUNTS]
SAH_COLUMN = "sah_cost"
SAH_RTOL = 1e-9
INSTRUCTIONS_TOLERANCE = 0.10  # fail above +10%, remind to update the baseline below -10%
DEFAULT_TIME_FACTOR = 1.5
# Render times are divided by this accelerator's in the same run (the baseline row).
RATIO_DENOMINATOR = "embree"
# The columns that, where the harness writes them, must agree between a row and the Embree
# row it is divided by (the same rays must have been traced): schema.RENDER_SETTING_COLUMNS.

PASS, FAIL, REMEASURE, NOT_CHECKED = "pass", "FAIL", "needs a second measurement", "not checked"


@dataclass
class Change:
    combo: str
    metric: str
    old: str
    new: str
    ratio: str


@dataclass
class Tier:
    name: str
    verdict: str = PASS
    summary: str = ""
    header: list[str] = field(default_factory=list)
    rows: list[list[str]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


@dataclass
class Comparison:
    tiers: list[Tier]
    provenance: list[str]
    warnings: list[str]
    matched_by: str

    @property
    def exit_code(self) -> int:
        verdicts = {t.verdict for t in self.tiers}
        if FAIL in verdicts:
            return EXIT_REGRESSION
        if REMEASURE in verdicts:
            return EXIT_REMEASURE
        return EXIT_PASS

    @property
    def verdict(self) -> str:
        return {EXIT_PASS: "PASS", EXIT_REGRESSION: "FAIL", EXIT_REMEASURE: "NEEDS A SECOND MEASUREMENT"}[
            self.exit_code
        ]


# ---- matching combinations across files ---------------------------------------------------


def _has_combo_id(df: pd.DataFrame) -> bool:
    return "combo_id" in df.columns and (df["combo_id"].astype(str).str.strip() != "").all()


def keyed(df: pd.DataFrame, by_id: bool, path: str) -> dict[str, pd.Series]:
    """The rows of one file by combination key (the harness's combo_id, or the contract's
    (config, model, accel, params) key when some file has no combo_id)."""
    if by_id:
        keys = df["combo_id"].astype(str).str.strip()
    else:
        keys = df[KEY_COLUMNS].astype(str).agg(" | ".join, axis=1)
    dup = keys[keys.duplicated()]
    if not dup.empty:
        raise ContractError(f"{path}: combination {dup.iloc[0]!r} occurs more than once")
    return {k: r for k, (_, r) in zip(keys, df.iterrows())}


def labels(rows: list[pd.Series], keys: list[str]) -> dict[str, str]:
    """Readable names: model / accel plus only the parameters that vary between rows of
    the same accelerator (the full params text of every row would drown the tables)."""
    varying: dict[str, set[str]] = {}
    for accel in {r["accel"] for r in rows}:
        dicts = [r["param_dict"] for r in rows if r["accel"] == accel]
        names = {n for d in dicts for n in d}
        varying[accel] = {n for n in names if len({d.get(n) for d in dicts}) > 1}
    out = {}
    for k, r in zip(keys, rows):
        shown = [f"{n}={v}" for n, v in r["param_dict"].items() if n in varying[r["accel"]]]
        out[k] = f"{r['model']} / {r['accel']}" + (f" ({', '.join(shown)})" if shown else "")
    seen: dict[str, int] = {}
    for v in out.values():
        seen[v] = seen.get(v, 0) + 1
    return {k: (v if seen[v] == 1 else f"{v} [{k}]") for k, v in out.items()}


# ---- formatting ----------------------------------------------------------------------------


def _missing(x) -> bool:
    return x is None or (isinstance(x, float) and math.isnan(x))


def plural(n: int, noun: str) -> str:
    return f"{n} {noun}{'' if n == 1 else 's'}"


def fmt_ratio(r: float) -> str:
    if _missing(r) or not math.isfinite(r):
        return "—"
    return f"{r:.4f}" if 0.01 <= r < 100 else f"{r:.3g}"


def _ratio(new, old) -> float:
    if _missing(new) or _missing(old) or old == 0:
        return math.nan
    return float(new) / float(old)


def _fmt_value(metric: str, v) -> str:
    if isinstance(v, str):
        return v
    if _missing(v):
        return "(empty)"
    return f"{v:.10g}" if metric == SAH_COLUMN else fmt_count(v)


# ---- tier 1: deterministic counts -----------------------------------------------------------


def _count_changed(metric: str, old, new) -> bool:
    if _missing(old) and _missing(new):
        return False
    if _missing(old) or _missing(new):
        return True
    if metric == SAH_COLUMN:
        return not math.isclose(float(old), float(new), rel_tol=SAH_RTOL, abs_tol=0.0)
    return float(old) != float(new)


def count_notes(
    t: Tier, missing: list[str], added: list[str], third_party_changes: list[str], unchecked_errors: set[str]
) -> None:
    """Tier 1's notes: combinations missing or new, third-party answers that changed, error
    columns the baseline lacks."""
    if missing:
        t.notes.append(
            "Missing from this run (a failure: the baseline measured them): " + "; ".join(missing) + "."
        )
    if third_party_changes:
        t.notes.append(
            f"Changed in the {RATIO_DENOMINATOR} rows (third-party answers, not compared exactly): "
            + "; ".join(third_party_changes)
            + "."
        )
    if unchecked_errors:
        t.notes.append(
            "Error columns not in the baseline, so not compared: "
            + ", ".join(sorted(unchecked_errors))
            + ". Update the baseline to cover them."
        )
    if added:
        t.notes.append(
            "New in this run (not in the baseline; not compared): "
            + "; ".join(added)
            + ". Update the baseline to cover them."
        )


def tier_counts(base: dict, cur: dict, name: dict) -> Tier:
    t = Tier(
        "1. Deterministic counts", header=["combination", "metric", "baseline", "current", "current/baseline"]
    )
    changed_combos = set()
    unchecked_errors: set[str] = set()
    third_party_changes: list[str] = []
    common = [k for k in base if k in cur]
    for k in common:
        b, c = base[k], cur[k]
        if b["status"] != c["status"]:
            detail = f"{c['status']}: {c['message']}" if c["message"] else c["status"]
            t.rows.append([name[k], "status", b["status"], detail, ""])
            changed_combos.add(k)
            continue
        if b["status"] != "ok":
            continue
        errors = [m for m in ERROR_COUNTS if not _missing(b.get(m))]
        unchecked_errors |= {m for m in ERROR_COUNTS if _missing(b.get(m)) and not _missing(c.get(m))}
        for metric in EXACT_COUNTS + [SAH_COLUMN] + errors:
            old, new = b[metric], c.get(metric)
            if (
                _count_changed(metric, old, new)
                and b.get("accel") == RATIO_DENOMINATOR
                and metric in THIRD_PARTY_ANSWERS
                and not _missing(old)
                and not _missing(new)
            ):
                # Embree's answers are not ours to regress: measured here, its bunny shadow
                # hits at 160x120 are 613 in one run and 614 in the next of the same build
                # (robust=false decides near-edge rays by its build order). Shown, not failed.
                third_party_changes.append(
                    f"{name[k]} {metric} {_fmt_value(metric, old)} -> {_fmt_value(metric, new)}"
                )
                continue
            if _count_changed(metric, old, new):
                t.rows.append(
                    [
                        name[k],
                        metric,
                        _fmt_value(metric, old),
                        _fmt_value(metric, new),
                        fmt_ratio(_ratio(new, old)),
                    ]
                )
                changed_combos.add(k)
    missing = [k for k in base if k not in cur]
    added = [k for k in cur if k not in base]
    count_notes(
        t, [name[k] for k in missing], [name[k] for k in added], third_party_changes, unchecked_errors
    )
    t.verdict = FAIL if (t.rows or missing) else PASS
    t.summary = (
        f"{len(common)} combinations compared on {len(EXACT_COUNTS) + 1} metrics "
        f"{'and the error counts ' if not unchecked_errors else ''}"
        f"(+ status): {plural(len(t.rows), 'value')} changed in "
        f"{plural(len(changed_combos), 'combination')}; {len(missing)} missing, "
        f"{len(added)} added"
    )
    if not t.rows:
        t.header = []
    return t


# ---- tier 2: instruction counts ---------------------------------------------------------------


def tier_instructions(base: dict, cur: dict, name: dict, tolerance: float) -> Tier:
    t = Tier(
        "2. Instruction counts (callgrind Ir of the measured render)",
        header=["combination", "baseline Ir", "current Ir", "current/baseline", "verdict"],
    )
    failed = improved = compared = unmeasured = 0
    for k in (k for k in base if k in cur):
        old, new = base[k][INSTRUCTIONS_COLUMN], cur[k][INSTRUCTIONS_COLUMN]
        if _missing(old) and _missing(new):
            continue
        if _missing(new):
            verdict = "not measured in this run"
            unmeasured += 1
        elif _missing(old):
            verdict = "no baseline value"
        else:
            compared += 1
            r = _ratio(new, old)
            if old == 0:
                verdict = "pass" if new == 0 else FAIL
            elif r > 1 + tolerance:
                verdict = FAIL
            elif r < 1 - tolerance:
                verdict = f"improved by more than {tolerance:.0%}: update the baseline"
                improved += 1
            else:
                verdict = "pass"
            failed += verdict == FAIL
        t.rows.append([name[k], fmt_count(old), fmt_count(new), fmt_ratio(_ratio(new, old)), verdict])
    if not t.rows:
        t.verdict, t.header = NOT_CHECKED, []
        t.summary = (
            "no instruction counts in the baseline or this run (the `instructions` "
            "column is absent or empty): tier 2 was not checked"
        )
        return t
    t.verdict = FAIL if failed else PASS
    t.summary = (
        f"{compared} combinations compared: {failed} above +{tolerance:.0%}, "
        f"{improved} below -{tolerance:.0%}"
        + (f", {unmeasured} not measured in this run" if unmeasured else "")
    )
    if improved:
        t.notes.append(
            f"{improved} combinations need {tolerance:.0%} fewer instructions than "
            f"the baseline: run `make update-baseline` and say why in the commit."
        )
    return t


# ---- tier 3: time relative to Embree ----------------------------------------------------------


@dataclass
class EmbreeRatio:
    ratio: float
    denominator: str = ""  # the Embree row divided by, or why there is no ratio


def embree_ratios(
    results: Results, by_id: bool, path: str, column: str = "render_s_median"
) -> dict[str, EmbreeRatio]:
    """`column` (render_s_median; the history also divides build_s_median) of each row
    over that of the Embree row with the same model and render settings in the same file.
    Several Embree rows (quality/robust variants): the one whose params text sorts first,
    in every file alike."""
    df = results.rows
    settings = [c for c in RENDER_SETTING_COLUMNS if c in df.columns]
    ok = df[(df["status"] == "ok") & (df[column] > 0)]
    embree = ok[ok["accel"] == RATIO_DENOMINATOR].sort_values("params")
    group = ["model"] + settings
    first: dict[tuple, pd.Series] = {}
    for _, e in embree.iterrows():
        first.setdefault(tuple(str(e[c]) for c in group), e)
    out = {}
    for k, r in keyed(df, by_id, path).items():
        if r["accel"] == RATIO_DENOMINATOR:
            continue
        if r["status"] != "ok" or _missing(r[column]):
            out[k] = EmbreeRatio(math.nan, f"status {r['status']}, no {column}")
            continue
        e = first.get(tuple(str(r[c]) for c in group))
        if e is None:
            out[k] = EmbreeRatio(math.nan, "no Embree row with this model and render settings")
            continue
        out[k] = EmbreeRatio(float(r[column]) / float(e[column]), f"embree [{e['params']}]")
    return out


def tier_time(
    base: dict[str, EmbreeRatio],
    cur: dict[str, EmbreeRatio],
    prev: dict[str, EmbreeRatio] | None,
    name: dict,
    factor: float,
) -> Tier:
    t = Tier(
        "3. Render time relative to Embree in the same run",
        header=["combination", "baseline ratio", "current ratio", "current/baseline"]
        + (["previous ratio"] if prev is not None else [])
        + ["verdict"],
    )
    counts = {FAIL: 0, REMEASURE: 0, "once": 0, "no ratio": 0, "pass": 0}
    for k in (k for k in base if k in cur):
        b, c = base[k], cur[k]
        p = prev.get(k) if prev is not None else None
        if _missing(b.ratio) or _missing(c.ratio):
            verdict = "no ratio: " + (c.denominator if _missing(c.ratio) else "baseline has " + b.denominator)
            counts["no ratio"] += 1
        elif c.ratio <= b.ratio * factor:
            verdict = "pass"
            counts["pass"] += 1
        elif p is not None and not _missing(p.ratio) and p.ratio > b.ratio * factor:
            verdict = FAIL
            counts[FAIL] += 1
        elif p is not None and not _missing(p.ratio):
            verdict = "exceeded once (the previous measurement was within): warning"
            counts["once"] += 1
        else:
            why = (
                "no previous measurement given (--history)"
                if prev is None
                else "the previous measurement has no ratio for it"
            )
            verdict = f"exceeded once, {why}: measure again"
            counts[REMEASURE] += 1
        row = [name[k], fmt_sig(b.ratio), fmt_sig(c.ratio), fmt_ratio(_ratio(c.ratio, b.ratio))]
        if prev is not None:
            row.append(fmt_sig(p.ratio) if p is not None else "—")
        t.rows.append(row + [verdict])
    if counts[FAIL]:
        t.verdict = FAIL
    elif counts[REMEASURE]:
        t.verdict = REMEASURE
    if not any(counts[v] for v in (FAIL, REMEASURE, "once", "pass")):
        t.verdict = NOT_CHECKED
    t.summary = (
        f"limit: {factor:g} x the baseline ratio, exceeded in two consecutive "
        f"measurements; {counts['pass']} within, {counts[FAIL]} failed (exceeded now "
        f"and in the previous measurement), {counts[REMEASURE]} exceeded once with no "
        f"second measurement, {counts['once']} exceeded once after a good previous "
        f"measurement, {counts['no ratio']} without a ratio"
    )
    if counts[REMEASURE]:
        t.notes.append(
            "A single exceedance may be noise. Measure again and rerun with the "
            "first run as history: `python -m accelbench_analysis regress --baseline "
            "BASE --current SECOND.csv --history FIRST.csv`."
        )
    if counts["once"]:
        t.notes.append(
            "An exceedance after a previous measurement within the limit is a "
            "warning only; it fails if the next run exceeds again."
        )
    return t


# ---- the comparison ------------------------------------------------------------------------------


def _provenance_lines(role: str, results: Results) -> list[str]:
    lines = []
    for g in results.groups:
        stamps = sorted(results.rows.loc[results.rows["prov_group"] == g.label, "timestamp"])
        when = f", measured {stamps[0]}" + (f" .. {stamps[-1]}" if stamps[-1] != stamps[0] else "")
        lines.append(
            f"{role}: commit {g.fields['git_sha']}"
            f"{' (dirty)' if g.fields['git_dirty'] == 'true' else ''}, cpu "
            f"{g.fields['cpu']}, {g.fields['compiler']}, {g.fields['build_type']} "
            f"(flags {g.fields['compile_flags']}), "
            f"Embree {g.fields['embree_version']}{when} ({g.rows} rows of "
            f"{', '.join(g.files)})"
        )
    return lines


def compare(
    baseline: Path,
    current: Path,
    history: Path | None = None,
    time_factor: float = DEFAULT_TIME_FACTOR,
    instructions_tolerance: float = INSTRUCTIONS_TOLERANCE,
) -> Comparison:
    """Loads the files (ContractError on bad input) and runs the three tiers."""
    if time_factor <= 1:
        raise ContractError(f"--time-factor must be above 1 (got {time_factor:g})")
    files = [("baseline", baseline), ("current", current)]
    if history is not None:
        files.append(("previous", history))
    loaded = {role: load_results([path]) for role, path in files}
    by_id = all(_has_combo_id(r.rows) for r in loaded.values())
    rows = {role: keyed(r.rows, by_id, str(path)) for (role, path), r in zip(files, loaded.values())}
    union = {**rows["current"], **rows["baseline"]}
    name = labels(list(union.values()), list(union.keys()))

    tiers = [
        tier_counts(rows["baseline"], rows["current"], name),
        tier_instructions(rows["baseline"], rows["current"], name, instructions_tolerance),
    ]
    ratios = {role: embree_ratios(r, by_id, str(path)) for (role, path), r in zip(files, loaded.values())}
    tiers.append(tier_time(ratios["baseline"], ratios["current"], ratios.get("previous"), name, time_factor))

    provenance = [line for role, r in loaded.items() for line in _provenance_lines(role, r)]
    warnings = [f"{role}: {w}" for role, r in loaded.items() for w in r.warnings]
    # Compared across builds on purpose, but never silently: another machine or other flags
    # (a baseline from before compile_flags reads "unknown") move times and instructions.
    for column, what, tiers_moved in (
        ("cpu", "measured on different CPUs", "tier 3 ratios to Embree"),
        ("compile_flags", "built with different compiler flags", "tier 2 instructions and tier 3 ratios"),
    ):
        seen = {role: {g.fields[column] for g in r.groups} for role, r in loaded.items()}
        if any(v != seen["baseline"] for v in seen.values()):
            warnings.append(
                f"the files were {what} ({'; '.join(f'{k}: {sorted(v)}' for k, v in seen.items())}): "
                f"{tiers_moved} may differ for that reason alone"
            )
    matched_by = (
        "combo_id" if by_id else "(config, model, accel, params): not every file has a combo_id column"
    )
    return Comparison(tiers, provenance, warnings, matched_by)


VERDICT_HEADING = "# Regression check: "


def verdict_of_report(text: str) -> str | None:
    """The verdict a report written by to_markdown states (PASS, FAIL, ...), or None."""
    first = text.split("\n", 1)[0]
    return first[len(VERDICT_HEADING) :].strip() if first.startswith(VERDICT_HEADING) else None


def to_markdown(cmp: Comparison, exit_code_note: bool = True) -> str:
    out = [f"{VERDICT_HEADING}{cmp.verdict}", ""]
    out += [f"- {line}" for line in cmp.provenance]
    out += [f"- combinations matched by {cmp.matched_by}", ""]
    for w in cmp.warnings:
        out += [f"> **Warning:** {w}", ""]
    out += md_table(
        ["tier", "verdict", "summary"], [[t.name, t.verdict, t.summary] for t in cmp.tiers], align="lll"
    )
    for t in cmp.tiers:
        out += ["", f"## {t.name}: {t.verdict}", "", t.summary + "."]
        if t.header:
            align = "ll" if t.header[1] == "metric" else "l" + "r" * (len(t.header) - 2) + "l"
            out += [""] + md_table(t.header, t.rows, align)
        for n in t.notes:
            out += ["", n]
    if exit_code_note:
        out += [
            "",
            f"Exit code {cmp.exit_code} (0 pass, 1 regression, 2 bad input, 3 a time "
            f"exceedance needs a second measurement).",
        ]
    if cmp.exit_code != EXIT_PASS:
        out += [
            "",
            "If a change is intended, `make update-baseline` rewrites the baseline from "
            "a fresh run; the commit that changes it says why.",
        ]
    return "\n".join(out) + "\n"
