"""Tables 2, 4 and 5 of the report, with our numbers beside the report's.

Tables 4 and 5 are laid out as in the report: models as columns, metrics as rows, one row
per structure. Each model has three sub-columns: our median with its 95% CI, the report's
number, and ours/report. Table 2 keeps the report's layout too: one row per kd-tree
setting, metrics as column groups.

The traps in the report's numbers are stated in each table's notes, computed from the data
rather than asserted: its "#Primitives" are vertex counts, its BVH node counts are
2 x #Primitives - 1, its "#int. tests" are never defined, and its times come
from another machine (so the ratio column of a time says more about the machines than
about the structures; the "relative to BVH" table is the comparison that carries over).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from ..inputs.report_numbers import (
    REPORT_MACHINE,
    REPORT_MODEL,
    REPORT_PRIMARY_RAYS,
    TABLE2_MODEL,
    TABLE4_MODELS,
    TABLE5_MODELS,
    our_model,
    report_value,
)
from ..inputs.schema import Results
from ..mapping.selection import (
    AUTO,
    STRUCTURE,
    Pick,
    Picker,
    Spec,
    Structure,
    kd_auto_depth_report,
    setting_spec,
    variant_label,
)
from .errors import (
    COMPACT_HEADER,
    NOT_MEASURED,
    any_error_values,
    compact_errors,
    error_text,
    note_errors,
    shown_metrics,
)
from .formatting import (
    Cell,
    Section,
    TableDoc,
    fmt_count,
    fmt_measure,
    fmt_sig,
    is_missing,
    to_latex,
    to_markdown,
)

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
SUBCOLUMNS = ["ours [95% CI]", "report", "ours/report"]


def preferred_variant(variants: list[str]) -> str | None:
    for v in VARIANT_PREFERENCE:
        if v in variants:
            return v
    return variants[0] if variants else None


def missing_text(pick: Pick) -> str:
    """Why a cell has no row of ours: "no row", "timeout", ... (the note has the message)."""
    return pick.reason.split(":")[0] if pick.reason else "—"


def ours_text(pick: Pick, metric: Metric) -> str:
    """Our cell: median [CI] for times, exact counts otherwise; why, when there is none."""
    if not pick.ok:
        return missing_text(pick)
    r = pick.row
    if metric.timed:
        base = metric.ours[: -len("_median")]
        if is_missing(r[metric.ours]):
            return "n/a"
        return fmt_measure(r[metric.ours], r[f"{base}_ci_lo"], r[f"{base}_ci_hi"])
    v = r[metric.ours]
    return "n/a" if is_missing(v) else fmt_count(v)


def ratio(ours, report) -> float | None:
    if is_missing(ours) or is_missing(report) or report == 0:
        return None
    return float(ours) / float(report)


def triple(pick: Pick, metric: Metric, report_value, tag: str) -> list[Cell]:
    ours = pick.value(metric.ours)
    rep = (
        "—"
        if is_missing(report_value)
        else (fmt_sig(report_value) if metric.timed else fmt_count(report_value))
    )
    return [Cell(ours_text(pick, metric), tag), Cell(rep), Cell(fmt_sig(ratio(ours, report_value)))]


def tag_of(pick: Pick) -> str:
    return "" if pick.row is None else str(pick.row["prov_group"])


# ---- errors against the `reference` accelerator --------------------------------------------------


def picked_rows(picks) -> pd.DataFrame:
    """The rows behind a table's cells, for deciding which error metrics it shows."""
    rows = [p.row for p in picks if p.ok]
    return pd.DataFrame(rows) if rows else pd.DataFrame()


def error_cell(pick: Pick, metric) -> Cell:
    return Cell(error_text(pick.row, metric) if pick.ok else missing_text(pick), tag_of(pick))


NOT_MEASURED_SECTION = (
    "Error against the reference (false misses, false hits, wrong "
    "primitives, NaN results, t error in ulps): not measured in this CSV"
)


def error_sections(
    srows: list[StructureRow], ours: list[str], pick_of, width: int, compact: bool = False
) -> list:
    """Error rows for a table with models as column groups of `width` cells: our value
    first, the report's (it measured none) after. compact: the four counts in one cell per
    structure instead of a section per metric."""
    picked = picked_rows(pick_of(sr, o) for sr in srows for o in ours)
    if not any_error_values(picked):
        return [Section(NOT_MEASURED_SECTION)]
    blank = [Cell("—")] * (width - 1)
    if compact:
        out: list = [Section(f"Errors vs the reference, ours ({COMPACT_HEADER})")]
        for sr in srows:
            cells = [Cell(sr.label)]
            for o in ours:
                pick = pick_of(sr, o)
                cells += [
                    Cell(compact_errors(pick.row) if pick.ok else missing_text(pick), tag_of(pick))
                ] + blank
            out.append(cells)
        return out
    out = []
    for metric in shown_metrics(picked):
        out.append(Section(metric.label))
        out += [
            [Cell(sr.label)] + [c for o in ours for c in [error_cell(pick_of(sr, o), metric)] + blank]
            for sr in srows
        ]
    return out


def model_counts(results: Results, model: str) -> tuple[float | None, float | None]:
    rows = results.rows[results.rows["model"] == model]
    if rows.empty:
        return None, None
    return rows["triangles"].iloc[0], rows["vertices"].iloc[0]


# ---- notes shared by the tables ---------------------------------------------------------


def note_times() -> str:
    return (
        f"Absolute times: the report's come from another machine ({REPORT_MACHINE}) and a "
        f"much slower implementation, so the ours/report column of a time compares the "
        f"machines more than the structures. Compare orderings and ratios between "
        f"structures instead (the 'relative to BVH' table)."
    )


def note_prim_tests(report_nums: pd.DataFrame, models: list[str], table: int) -> str:
    sub = report_nums[(report_nums["table"] == table) & report_nums["model"].isin(models)]
    below = sub[sub["prim_tests"] < REPORT_PRIMARY_RAYS]
    text = (
        "#int. tests: ours are primitive (ray/triangle) tests summed over every ray of "
        "the render, primary and shadow. The report does not define its count"
    )
    if len(below):
        text += (
            f"; {len(below)} of its {len(sub)} values in this table lie below the "
            f"{REPORT_PRIMARY_RAYS:,} primary rays of its 640x480 image (e.g. "
            f"{below.iloc[0]['accelerator']} on {below.iloc[0]['model']}: "
            f"{int(below.iloc[0]['prim_tests']):,}). Totals over all rays can be that low, since a "
            f"ray that misses the model's bounds tests no primitive, so the size of a count does "
            f"not say what was counted"
        )
    return text + ". Compare how the counts move between structures and settings, not their size."


def note_primitives(report_nums: pd.DataFrame, results: Results, report_models: list[str]) -> str:
    same, differ = [], []
    for rm in report_models:
        if REPORT_MODEL[rm].stand_in:
            continue
        tri, vert = model_counts(results, our_model(rm, set(results.rows["model"])))
        prims = report_nums.loc[report_nums["model"] == rm, "primitives"]
        if tri is None or prims.empty:
            continue
        (same if int(prims.iloc[0]) == int(vert) else differ).append(
            f"{REPORT_MODEL[rm].short} {int(prims.iloc[0]):,} vs our {int(vert):,} vertices / "
            f"{int(tri):,} triangles"
        )
    text = "#Primitives: we show both our triangle and vertex counts against the report's single #Primitives."
    if same:
        text += " The report's number equals the VERTEX count for " + "; ".join(same) + "."
    if differ:
        text += " It differs from our vertex count for " + "; ".join(differ) + "."
    return text


def note_bvh_nodes(report_nums: pd.DataFrame, report_models: list[str]) -> str | None:
    sub = report_nums[
        (report_nums["accelerator"] == "bvh")
        & report_nums["model"].isin(report_models)
        & (report_nums["setting"] == "default")
    ]
    if sub.empty:
        return None
    exact = sub["nodes"] == 2 * sub["primitives"] - 1
    if exact.all():
        return (
            f"The report's BVH #nodes equal 2 x #Primitives - 1 on all {len(sub)} models: "
            f"a one-primitive-per-leaf tree over its #Primitives, i.e. over vertex counts. "
            f"Ours with max_prims=1 has 2 x triangles - 1 nodes, so the ratio follows "
            f"2 x triangles / #Primitives rather than the structures."
        )
    odd = sub[~exact].iloc[0]
    names = [REPORT_MODEL[m].short for m in sub.loc[exact, "model"]]
    return (
        f"The report's BVH #nodes equal 2 x #Primitives - 1 on {int(exact.sum())} of "
        f"{len(sub)} models"
        + (f" ({', '.join(names)})" if names else "")
        + f"; not on e.g. {REPORT_MODEL[odd['model']].short} ({int(odd['nodes']):,} nodes for "
        f"{int(odd['primitives']):,} primitives), so there its trees did not have one "
        f"primitive per leaf or its #Primitives counts something else."
    )


def note_complete_trees(
    report_nums: pd.DataFrame, report_models: list[str], ablations: pd.DataFrame | None
) -> str | None:
    """A BVH with exactly 2^(d+1) - 1 nodes is complete: every path has length d. The report's
    City BVH has 65,535 = 2^16 - 1 nodes; the ablation rows (configs/ablations.yaml) measure
    our median BVH at max_depth 15 and 16 on the Table 5 stand-ins to show what gives it."""
    sub = report_nums[
        (report_nums["accelerator"] == "bvh")
        & report_nums["model"].isin(report_models)
        & (report_nums["setting"] == "default")
    ]
    parts = []
    for _, r in sub.iterrows():
        n = int(r["nodes"])
        full = (1 << n.bit_length()) - 1 if n > 0 else 0  # the smallest 2^k - 1 >= n
        depth = full.bit_length() - 1
        name = REPORT_MODEL[r["model"]].short
        if n > 0 and n == full:
            parts.append(
                f"the report's {name} BVH has {n:,} = 2^{depth + 1} - 1 nodes, a complete tree of depth {depth}"
            )
        elif n > 0 and full - n <= full // 1000:  # within 0.1% of complete
            parts.append(
                f"the report's {name} BVH has {n:,} nodes, {full - n:,} short of the complete 2^{depth + 1} - 1 of depth {depth}"
            )
    if not any("a complete tree" in p for p in parts):
        return None
    text = "; ".join(parts)
    text = text[0].upper() + text[1:]
    if ablations is None or ablations.empty or "param_dict" not in ablations:
        return (
            text
            + ". Our median BVH at that max_depth is not in this run (configs/ablations.yaml measures it)."
        )
    models = {our_model(rm, set(ablations["model"])) for rm in report_models}
    ours = ablations[
        (ablations["accel"] == "bvh") & (ablations["status"] == "ok") & ablations["model"].isin(models)
    ]
    seen = []
    for _, r in ours.sort_values(["model", "nodes"]).iterrows():
        p = r["param_dict"]
        if p.get("split") != "median" or not str(p.get("max_depth", "")).isdigit():
            continue
        depth = int(p["max_depth"])
        nodes = int(r["nodes"])
        full = nodes == 2 ** (depth + 1) - 1
        seen.append(f"{r['model']} at max_depth {depth}: {nodes:,}{' (complete)' if full else ''}")
    if not seen:
        return text + "."
    return (
        text
        + ". Our median BVH, max_prims 1, in the ablation rows: "
        + "; ".join(seen)
        + (
            ". A median split stops only at max_depth or one primitive, so a complete tree means the depth "
            "limit ended every path: the report's tree was cut at that depth."
        )
    )


# The kd-tree at Table 3's settings with our defaults, as a row's param_dict: not the
# ablations' sweeps (other max_prims, max_depth, empty_bonus, mailboxes) on the same model.
TABLE3_KDTREE = {"max_prims": "1", "max_depth": "auto", "empty_bonus": "0.5", "mailbox": "false"}


def is_table3_kdtree(params: dict) -> bool:
    """A parameter the row does not have (an older CSV's mailbox) counts as its default."""
    return all(params.get(k, v) == v for k, v in TABLE3_KDTREE.items())


def note_what_n(report_nums: pd.DataFrame, results: Results, ablations: pd.DataFrame | None) -> str | None:
    """Which N the report's Equation 5 (kd-tree depth 8 + 1.3 log2 N) and its BVH node counts
    use: its #Primitives (the bunny's vertex count), not the triangle count we build over.
    The ablation rows hold a bunny decimated to that many triangles."""
    prims = report_nums.loc[
        (report_nums["table"] == 2) & (report_nums["model"] == TABLE2_MODEL), "primitives"
    ]
    tri, _ = model_counts(results, our_model(TABLE2_MODEL, set(results.rows["model"])))
    if prims.empty or tri is None:
        return None
    n = int(prims.iloc[0])
    text = (
        f"What N is: the report's Equation 5 gives max_depth {kd_auto_depth_report(n)} for its N = "
        f"{n:,}; our max_depth auto is {kd_auto_depth_report(tri)}, from the bunny's {int(tri):,} triangles"
    )
    if ablations is None or ablations.empty:
        return text + "."
    same_n = ablations[(ablations["triangles"] == n) & (ablations["status"] == "ok")]
    found = []
    for _, r in same_n.iterrows():
        if r["accel"] == "kdtree" and is_table3_kdtree(r["param_dict"]):
            found.append(
                f"its kd-tree (max_depth auto) is {kd_auto_depth_report(n)} deep at most and has {int(r['nodes']):,} nodes"
            )
        elif r["accel"] == "bvh" and r["param_dict"].get("split") == "median":
            rep = report_value(report_nums, TABLE2_MODEL, "bvh", "default", "nodes")
            found.append(
                f"its median BVH has {int(r['nodes']):,} nodes"
                + (f" (the report's Table 4: {int(rep):,})" if rep is not None else "")
            )
    if found:
        text += (
            f". A bunny decimated to {n:,} triangles (the ablation rows, {same_n['model'].iloc[0]}): "
            + "; ".join(found)
        )
    return text + "."


def note_stand_ins(report_models: list[str], present: set[str]) -> list[str]:
    out = []
    for rm in report_models:
        m = REPORT_MODEL[rm]
        if m.stand_in:
            ours = our_model(rm, present)
            where = "" if ours in present else " (no rows for it in the CSV)"
            out.append(f"Stand-in: {m.stand_in}; our model name {ours}{where}.")
    return out


def note_structures(variant_seen: bool, embree_counters_missing: bool) -> list[str]:
    out = [
        "Structures: BVH (median), LBVH and kd-tree use the report's Table 3 parameters "
        "(BVH split=median, max_prims=1, max_depth=50; LBVH max_prims=1, max_depth=50; "
        "kd-tree max_prims=1, max_depth = 8 + 1.3 log2 N, N = triangles). BVH (binned SAH) "
        "and Embree go beyond the report and have no report numbers."
    ]
    if variant_seen:
        out.append(
            "[traversal=...] rows are the same structure run with each of the "
            "harness's traversal modes: 'ordered' visits the nearer child first, "
            "'report' keeps the report's fixed child order (its Algorithm 1)."
        )
    if embree_counters_missing:
        out.append(
            "Embree exposes no node or primitive-test counters: its #int. tests and "
            "#nodes are n/a (missing, not zero)."
        )
    return out


def note_tags(results: Results) -> list[str]:
    if not results.mixed:
        return []
    return [
        "Superscript letters tag each of our cells with its provenance group: "
        + "; ".join(g.describe() for g in results.groups)
        + "."
    ]


# ---- Tables 4 and 5 ---------------------------------------------------------------------


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


def model_table(
    results: Results,
    report_nums: pd.DataFrame,
    number: int,
    report_models: list[str],
    ablations: pd.DataFrame | None = None,
) -> list[TableDoc]:
    picker = Picker(results)
    present = picker.models
    ours = [our_model(rm, present) for rm in report_models]
    srows = structure_rows(picker, ours)
    groups = [
        (REPORT_MODEL[rm].label + (f" → {o}" if REPORT_MODEL[rm].stand_in else ""), 3)
        for rm, o in zip(report_models, ours)
    ]
    header = [""] + SUBCOLUMNS * len(report_models)
    rows: list = [Section("#Primitives (report) vs our counts")]
    for label, idx in (("#triangles (ours)", 0), ("#vertices (ours)", 1)):
        cells = [Cell(label)]
        for rm, o in zip(report_models, ours):
            ours_v = model_counts(results, o)[idx]
            rep = report_nums.loc[
                (report_nums["model"] == rm) & (report_nums["table"] == number), "primitives"
            ]
            rep_v = None if rep.empty else float(rep.iloc[0])
            cells += [Cell(fmt_count(ours_v)), Cell(fmt_count(rep_v)), Cell(fmt_sig(ratio(ours_v, rep_v)))]
        rows.append(cells)

    notes: list[str] = []
    embree_missing_counters = False
    picks: dict[tuple[str, str, str | None], Pick] = {}
    for metric in METRICS:
        rows.append(Section(metric.label))
        for sr in srows:
            cells = [Cell(sr.label)]
            for rm, o in zip(report_models, ours):
                key = (o, sr.structure.key, sr.variant)
                if key not in picks:
                    picks[key] = picker.pick(o, sr.structure.spec, sr.variant)
                pick = picks[key]
                rep = (
                    report_value(report_nums, rm, sr.structure.report_accel, "default", metric.report)
                    if sr.structure.report_accel
                    else None
                )
                cells += triple(pick, metric, rep, tag_of(pick))
                if (
                    sr.structure.key == "embree"
                    and pick.ok
                    and not metric.timed
                    and is_missing(pick.value(metric.ours))
                ):
                    embree_missing_counters = True
            rows.append(cells)
    rows += error_sections(
        srows, ours, lambda sr, o: picks[(o, sr.structure.key, sr.variant)], len(SUBCOLUMNS)
    )
    labels = {sr.structure.key: sr.structure.label for sr in srows}
    for (o, skey, variant), pick in picks.items():
        label = labels[skey] + (f" [traversal={variant}]" if variant else "")
        if not pick.ok:
            notes.append(f"{label} on {o}: {pick.reason}.")
        notes += [n + "." for n in pick.notes]

    variant_seen = any(sr.variant for sr in srows)
    fixed = [
        note_primitives(report_nums, results, report_models),
        note_bvh_nodes(report_nums, report_models),
        note_complete_trees(report_nums, report_models, ablations),
        note_prim_tests(report_nums, report_models, number),
        note_times(),
    ]
    fixed += note_structures(variant_seen, embree_missing_counters)
    fixed += [note_errors(picked_rows(picks.values()))]
    fixed += note_stand_ins(report_models, present) + note_tags(results)
    title = {4: "Table 4: BVH, LBVH and kd-tree on four models", 5: "Table 5: much more complex scenes"}[
        number
    ]
    caption = (
        f"Report's Table {number} beside our measurement of the same structures "
        f"(plus the binned-SAH BVH and Embree). Each model: our median with its 95% "
        f"confidence interval, the report's number, and ours/report."
    )
    main = report_table(f"table{number}", title, caption, groups, header, rows, fixed + notes, results)
    return [main, relative_table(results, report_nums, number, report_models, picker, srows, ours)]


def relative_table(
    results: Results,
    report_nums: pd.DataFrame,
    number: int,
    report_models: list[str],
    picker: Picker,
    srows: list[StructureRow],
    ours: list[str],
) -> TableDoc:
    """Times relative to the median-split BVH on the same model: survives a change of machine."""
    bvh = STRUCTURE["bvh"]
    bvh_variants = picker.variants(ours, bvh.spec)
    bvh_default = preferred_variant(bvh_variants)

    def denominator_variant(variant: str | None) -> str | None:
        # Same traversal as the numerator where the BVH has it, else the report's order.
        return (
            variant
            if variant in bvh_variants and len(bvh_variants) > 1
            else (bvh_default if len(bvh_variants) > 1 else None)
        )

    denominators = {
        (o, v): picker.pick(o, bvh.spec, v)
        for o in ours
        for v in {denominator_variant(sr.variant) for sr in srows}
    }
    groups = [
        (REPORT_MODEL[rm].label + (f" → {o}" if REPORT_MODEL[rm].stand_in else ""), 2)
        for rm, o in zip(report_models, ours)
    ]
    header = [""] + ["ours", "report"] * len(report_models)
    picks = {
        (o, sr.structure.key, sr.variant): picker.pick(o, sr.structure.spec, sr.variant)
        for sr in srows
        for o in ours
    }
    rows: list = []
    for metric in (METRIC["build"], METRIC["render"]):
        rows.append(Section(f"{metric.label} / BVH (median) {metric.label.split(' (')[0].lower()}"))
        for sr in srows:
            if sr.structure.key == "bvh":
                continue
            cells = [Cell(sr.label)]
            for rm, o in zip(report_models, ours):
                pick = picks[(o, sr.structure.key, sr.variant)]
                den = denominators[(o, denominator_variant(sr.variant))]
                r_ours = ratio(pick.value(metric.ours), den.value(metric.ours))
                r_rep = None
                if sr.structure.report_accel:
                    r_rep = ratio(
                        report_value(report_nums, rm, sr.structure.report_accel, "default", metric.report),
                        report_value(report_nums, rm, "bvh", "default", metric.report),
                    )
                tag = tag_of(pick) if tag_of(pick) == tag_of(den) else f"{tag_of(pick)}/{tag_of(den)}"
                cells += [Cell(fmt_sig(r_ours), tag if r_ours is not None else ""), Cell(fmt_sig(r_rep))]
            rows.append(cells)
    rows += error_sections(
        srows, ours, lambda sr, o: picks[(o, sr.structure.key, sr.variant)], 2, compact=True
    )
    caption = (
        "Build and render time of each structure divided by that of BVH (median) on the "
        "same model, ours beside the report's: ratios within one machine are what can be "
        "compared across machines. The last rows: how wrong each of our rows is."
    )
    if len(bvh_variants) > 1:
        caption += (
            f" A [traversal=X] row is divided by the BVH with the same traversal; "
            f"structures without traversal modes by the BVH with traversal={bvh_default}."
        )
    notes = [note_errors(picked_rows(picks.values()))]
    if results.mixed:
        notes.append(
            "A tag X/Y means numerator and denominator come from different provenance "
            "groups: that ratio mixes builds or machines."
        )
    return TableDoc(
        f"table{number}-relative",
        f"Table {number}, relative to BVH (median)",
        caption,
        groups,
        header,
        rows,
        notes=notes,
        show_tags=results.mixed,
    )


def report_table(name, title, caption, groups, header, rows, notes, results) -> TableDoc:
    """One of the report's tables beside ours: the notes that apply (None where a note does
    not), the results' warnings, and provenance tags where the results mix builds."""
    return TableDoc(
        name,
        title,
        caption,
        groups,
        header,
        rows,
        notes=[n for n in notes if n],
        warnings=list(results.warnings),
        show_tags=results.mixed,
    )


# ---- Table 2 ----------------------------------------------------------------------------


def table2(
    results: Results, report_nums: pd.DataFrame, ablations: pd.DataFrame | None = None
) -> list[TableDoc]:
    picker = Picker(results)
    present = picker.models
    model = our_model(TABLE2_MODEL, present)
    sub = report_nums[report_nums["table"] == 2]
    settings = list(sub["setting"])
    depths = [s.split("=")[1] for s in settings if s.startswith("maxDepth=")]
    metrics = [METRIC["nodes"], METRIC["prim_tests"], METRIC["build"], METRIC["render"]]
    groups = [(m.label, 3) for m in metrics]
    header = ["report setting", "our parameters"] + SUBCOLUMNS * len(metrics)
    rows: list = [Section(f"kd-tree on the {REPORT_MODEL[TABLE2_MODEL].label}")]
    row_picks: list[Pick] = []  # the pick behind each non-section row, for the error columns
    notes: list[str] = []
    fixed_mp = None
    for setting in settings:
        spec = setting_spec(setting, "kdtree", picker, model, depths)
        if setting.startswith("maxDepth="):
            fixed_mp = dict(spec.required).get("max_prims")
        pick = picker.pick(model, spec)
        row_picks.append(pick)
        rows.append(
            [Cell(setting), Cell(kd_params_text(pick, spec))]
            + [
                c
                for m in metrics
                for c in triple(
                    pick,
                    m,
                    report_value(report_nums, TABLE2_MODEL, "kdtree", setting, m.report),
                    tag_of(pick),
                )
            ]
        )
        if not pick.ok:
            notes.append(f"{setting} ({spec.describe()}): {pick.reason}.")
        notes += [n + "." for n in pick.notes]

    extra = [s for s in picker.structures() if s.report_accel is None]
    rows.append(Section("Beyond the report: other structures on the same model (no report numbers)"))
    for s in extra:
        variants = picker.variants([model], s.spec)
        for v in variants if len(variants) > 1 else [None]:
            pick = picker.pick(model, s.spec, v)
            row_picks.append(pick)
            rows.append(
                [Cell(variant_label(s.label, v or "", variants)), Cell(s.spec.describe())]
                + [c for m in metrics for c in triple(pick, m, None, tag_of(pick))]
            )
            if not pick.ok:
                notes.append(f"{s.label} on {model}: {pick.reason}.")

    error_header = append_error_columns([r for r in rows if not isinstance(r, Section)], row_picks)
    groups.append(("Error vs the reference (ours; the report measured none)", len(error_header)))
    header += error_header

    tri, vert = model_counts(results, model)
    prims = sub["primitives"].iloc[0] if len(sub) else None
    caption = (
        f"The report's Table 2 (kd-tree parameters on the Stanford bunny) beside ours. "
        f"Model: ours {fmt_count(tri)} triangles / {fmt_count(vert)} vertices; the "
        f"report's #Primitives {fmt_count(prims)}. Each metric: our median with its 95% "
        f"CI, the report's number, ours/report."
    )
    fixed = [
        "maxPrims=K rows are our kd-tree with max_prims=K at the automatic depth "
        "(8 + 1.3 log2 N, N = triangles); maxDepth=D rows have max_depth=D at "
        + (
            f"max_prims={fixed_mp}, the value our depth sweep was run with (the report does "
            f"not state the maxPrims of its depth sweep)."
            if fixed_mp
            else "whatever max_prims our depth sweep used (none found)."
        )
    ]
    kd_default = report_value(report_nums, TABLE2_MODEL, "kdtree", "default", "nodes")
    mp1 = report_value(report_nums, TABLE2_MODEL, "kdtree", "maxPrims=1", "nodes")
    if kd_default is not None and mp1 is not None and kd_default != mp1:
        fixed.append(
            f"The report's maxPrims=1 row ({int(mp1):,} nodes) and its Table 4 kd-tree "
            f"on the same bunny with the same maxPrims=1 default ({int(kd_default):,} "
            f"nodes) differ: the report's two runs were not identical."
        )
    fixed += [
        note_prim_tests(report_nums, [TABLE2_MODEL], 2),
        note_what_n(report_nums, results, ablations),
        note_times(),
        note_errors(picked_rows(row_picks)),
    ] + note_tags(results)
    doc = report_table(
        "table2",
        "Table 2: kd-tree parameters on the Stanford bunny",
        caption,
        groups,
        header,
        rows,
        fixed + notes,
        results,
    )
    return [doc]


def append_error_columns(rows: list[list[Cell]], picks: list[Pick]) -> list[str]:
    """Appends one error column per metric to each row (rows[i] is picks[i]'s), or a single
    "not measured" column when none of the rows has error values; returns the headers."""
    picked = picked_rows(picks)
    if not any_error_values(picked):
        for cells, pick in zip(rows, picks):
            cells.append(Cell(NOT_MEASURED if pick.ok else missing_text(pick), tag_of(pick)))
        return ["errors"]
    metrics = shown_metrics(picked)
    for cells, pick in zip(rows, picks):
        cells += [error_cell(pick, m) for m in metrics]
    return [m.short for m in metrics]


def kd_params_text(pick: Pick, spec: Spec) -> str:
    if pick.ok:
        p = pick.row["param_dict"]
        return ", ".join(f"{k}={p[k]}" for k in ("max_prims", "max_depth") if k in p)
    return ", ".join(f"{k}={'auto' if v == AUTO else v}" for k, v in spec.required)


# ---- output -----------------------------------------------------------------------------


def build_tables(
    results: Results, report_nums: pd.DataFrame, ablations: pd.DataFrame | None = None
) -> dict[str, list[TableDoc]]:
    """ablations: the ablation configs' rows, which only notes read (the tables show the run
    at the report's settings)."""
    return {
        "table2": table2(results, report_nums, ablations),
        "table4": model_table(results, report_nums, 4, TABLE4_MODELS),
        "table5": model_table(results, report_nums, 5, TABLE5_MODELS, ablations),
    }


def write_tables(
    results: Results, report_nums: pd.DataFrame, out_dir: Path, ablations: pd.DataFrame | None = None
) -> list[Path]:
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for name, docs in build_tables(results, report_nums, ablations).items():
        md = out_dir / f"{name}.md"
        md.write_text("\n".join(to_markdown(d) for d in docs))
        tex = out_dir / f"{name}.tex"
        tex.write_text("\n".join(to_latex(d) for d in docs))
        written += [md, tex]
    return written
