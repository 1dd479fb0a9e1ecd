"""The notes under Tables 2, 4 and 5: the traps in the report's numbers, computed from the
data rather than asserted (its "#Primitives" are vertex counts, its BVH node counts are
2 x #Primitives - 1, its "#int. tests" are never defined, its times come from another
machine), and what stands in for what."""

from __future__ import annotations

import pandas as pd

from ...inputs.report_numbers import (
    REPORT_MACHINE,
    REPORT_MODEL,
    REPORT_PRIMARY_RAYS,
    TABLE2_MODEL,
    our_model,
    report_value,
)
from ...inputs.schema import Results
from ...mapping.selection import kd_auto_depth_report


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
