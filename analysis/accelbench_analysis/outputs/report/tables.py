"""Tables 2, 4 and 5 of the report, with our numbers beside the report's.

Tables 4 and 5 are laid out as in the report: models as columns, metrics as rows, one row
per structure. Each model has three sub-columns: our median with its CI (the coverage it has), the report's
number, and ours/report. Table 2 keeps the report's layout too: one row per kd-tree
setting, metrics as column groups.

The traps in the report's numbers are stated in each table's notes, computed from the data
rather than asserted: its "#Primitives" are vertex counts, its BVH node counts are
2 x #Primitives - 1, its "#int. tests" are never defined, and its times come
from another machine (so the ratio column of a time says more about the machines than
about the structures; the "relative to BVH" table is the comparison that carries over).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from ...inputs.report_numbers import (
    REPORT_MODEL,
    TABLE2_MODEL,
    TABLE4_MODELS,
    TABLE5_MODELS,
    our_model,
    report_value,
)
from ...inputs.schema import Results
from ...mapping.errors import (
    COMPACT_HEADER,
    NOT_MEASURED,
    any_error_values,
    compact_errors,
    error_text,
    note_errors,
    shown_metrics,
)
from ...mapping.formatting import (
    Cell,
    Section,
    TableDoc,
    ci_label,
    fmt_count,
    fmt_measure,
    fmt_sig,
    is_missing,
    repetitions_text,
    to_latex,
    to_markdown,
)
from ...mapping.metrics import METRIC, METRICS, Metric, StructureRow, preferred_variant, ratio, structure_rows
from ...mapping.selection import AUTO, Pick, Picker, Spec, setting_spec, variant_label
from .table_notes import (
    model_counts,
    note_bvh_nodes,
    note_complete_trees,
    note_prim_tests,
    note_primitives,
    note_stand_ins,
    note_structures,
    note_tags,
    note_times,
    note_what_n,
)

SUBCOLUMNS = ["ours [CI]", "report", "ours/report"]


def run_ci_label(results: Results) -> str:
    """ "CI" with the coverage the run's intervals really have (ci_label)."""
    return ci_label(results.ok().get("ci_coverage", pd.Series(dtype=float)))


def ci_caption(results: Results, shown: pd.DataFrame) -> str:
    """The caption's words for the intervals: their coverage, or that there are none, and
    how the rows the table shows (`shown`) were measured (repetitions, processes)."""
    label = run_ci_label(results)
    reps = repetitions_text(shown[~shown.index.duplicated()])
    return f"no interval; {reps}" if label == "CI" else f"{label[3:]} coverage; {reps}"


def subcolumns(results: Results) -> list[str]:
    return [f"ours [{run_ci_label(results)}]", *SUBCOLUMNS[1:]]


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


# ---- Tables 4 and 5 ---------------------------------------------------------------------


def primitive_rows(
    results: Results, report_nums: pd.DataFrame, number: int, report_models: list[str], ours: list[str]
) -> list:
    """The section comparing the report's #Primitives with our triangle and vertex counts."""
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
    srows = structure_rows(picker, ours, report=True)
    groups = [
        (REPORT_MODEL[rm].label + (f" → {o}" if REPORT_MODEL[rm].stand_in else ""), 3)
        for rm, o in zip(report_models, ours)
    ]
    header = [""] + subcolumns(results) * len(report_models)
    rows: list = primitive_rows(results, report_nums, number, report_models, ours)

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
                    picks[key] = picker.pick(o, sr.structure.table_spec, sr.variant)
                pick = picks[key]
                rep = (
                    report_value(report_nums, rm, sr.structure.report_accel, "default", metric.report)
                    if sr.structure.report_accel
                    else None
                )
                cells += triple(pick, metric, rep, tag_of(pick))
                if (
                    sr.structure.role == "baseline"
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
        f"(plus the binned-SAH BVH and Embree). Each model: our median with its "
        f"confidence interval ({ci_caption(results, picked_rows(picks.values()))}), the report's number, "
        f"and ours/report."
    )
    main = report_table(f"table{number}", title, caption, groups, header, rows, fixed + notes, results)
    return [main, relative_table(results, report_nums, number, report_models, picker, srows, ours)]


def relative_doc(results: Results, number: int, groups, header, rows, picks, bvh_variants) -> TableDoc:
    """The relative table's caption and notes around its rows."""
    bvh_default = preferred_variant(bvh_variants)
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
    bvh = picker.structure("bvh")
    bvh_variants = picker.variants(ours, bvh.table_spec)
    bvh_default = preferred_variant(bvh_variants)

    def denominator_variant(variant: str | None) -> str | None:
        # Same traversal as the numerator where the BVH has it, else the report's order.
        return (
            variant
            if variant in bvh_variants and len(bvh_variants) > 1
            else (bvh_default if len(bvh_variants) > 1 else None)
        )

    denominators = {
        (o, v): picker.pick(o, bvh.table_spec, v)
        for o in ours
        for v in {denominator_variant(sr.variant) for sr in srows}
    }
    groups = [
        (REPORT_MODEL[rm].label + (f" → {o}" if REPORT_MODEL[rm].stand_in else ""), 2)
        for rm, o in zip(report_models, ours)
    ]
    header = [""] + ["ours", "report"] * len(report_models)
    picks = {
        (o, sr.structure.key, sr.variant): picker.pick(o, sr.structure.table_spec, sr.variant)
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
    return relative_doc(results, number, groups, header, rows, picks, bvh_variants)


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


def table2_notes(
    results: Results,
    report_nums: pd.DataFrame,
    ablations: pd.DataFrame | None,
    fixed_mp,
    row_picks: list[Pick],
) -> list[str]:
    """Table 2's notes: what its rows are, where the report disagrees with itself, and the
    notes every table has."""
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
    return fixed


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
    header = ["report setting", "our parameters"] + subcolumns(results) * len(metrics)
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
        f"report's #Primitives {fmt_count(prims)}. Each metric: our median with its "
        f"confidence interval ({ci_caption(results, picked_rows(row_picks))}), the report's number, ours/report."
    )
    fixed = table2_notes(results, report_nums, ablations, fixed_mp, row_picks)
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
