"""Beyond the report's one workload: Mrays/s per ray set (primary, shadow, ao,
diffuse, random) and thread scaling.

Rows of ray-set runs carry `ray_set` != camera (configs/ray-sets.yaml); rows of
thread-scaling runs are camera rows of a config whose render `threads` vary
(configs/thread-scaling.yaml). Neither kind fills the report's tables (`without_thread_scaling`
and mapping.selection.report_rows leave them out, saying so). A ratio to Embree divides by
Embree's row of the same model, set and workload (thread count, image), never by another's.

Outputs (when the input has such rows):
- tables/ray_sets.md, .csv: each structure's Mrays/s per set and its ratio to Embree's
  on the same model and set, and, where the two were timed alternately in the same
  processes, the worse of the processes' ratios;
- tables/ray_set_ranking.md: per model, the structures ranked by Mrays/s in each set, a
  rank marked * where it differs from the rank in the first set (primary);
- figures/ray_sets.png: Mrays/s per set, structure and model;
- tables/thread_scaling.md, .csv and figures/thread_scaling.png: build wall time and render
  wall and CPU time per thread count, the speedups = wall(1 thread) / wall(t) of both and the
  render's parallel efficiency = speedup / t. A structure with a `threads` parameter (Embree,
  bvh, wbvh, kdtree, lbvh) builds on the render's thread count (the harness gives it that);
  the others build on one thread whatever the count.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pandas as pd

from ...inputs.schema import CAMERA_SET, RAY_SETS, RENDER_SETTING_COLUMNS, Results
from ...mapping.formatting import md_escape
from ...mapping.interleaved import process_medians, worse_process_ratio
from ...mapping.selection import EMBREE_PREFERRED, label_of
from ...mapping.structures import baseline_accels, table_row
from ...mapping.styles import Styles
from .interactive import ray_sets_spec, thread_scaling_spec, write_figure


def _thread_scaling_configs(rows: pd.DataFrame) -> pd.Series:
    """Per row: its config measures more than one render thread count."""
    return rows.groupby("config")["render_threads"].transform("nunique") > 1


def without_thread_scaling(results: Results) -> tuple[Results, list[str]]:
    """Every row but those of thread-scaling runs (the report's tables do not take them),
    and a note counting what was left out."""
    mask = _thread_scaling_configs(results.rows)
    if not mask.any():
        return results, []
    configs = ", ".join(sorted(set(results.rows.loc[mask, "config"])))
    # Camera rows go to the thread-scaling table, ray-set rows to the ray-set table (a
    # section per thread count): say where each kind is, not where it is not.
    camera = mask & (results.rows["ray_set"] == CAMERA_SET)
    counts = {
        "camera rays in tables/thread_scaling.md": int(camera.sum()),
        "ray sets in tables/ray_sets.md": int((mask & ~camera).sum()),
    }
    where = ", ".join(f"{n} rows of {what}" for what, n in counts.items() if n)
    note = (
        f"left out of the report's tables, claims and figures: {int(mask.sum())} rows of "
        f"thread-scaling runs ({configs}; {where})"
    )
    return replace(results, rows=results.rows[~mask]), [note]


def table_or_csv_label(accel: str, params: dict, csv_label) -> str:
    """The structure table's label of a row's structure; for an accelerator the table lacks
    (a plugin's, not loaded when the table was read) the row's own `label` column."""
    if table_row(accel) is None and isinstance(csv_label, str) and csv_label:
        return csv_label
    return label_of(accel, params)


def structure_labels(rows: pd.DataFrame) -> pd.Series:
    """The structure table's label of each row's structure ("wide BVH (8, SIMD)"), plus the
    parameters that vary among the rows of one label ("Embree [robust=true]"), so that two
    settings never share a label. A `threads` parameter follows the render thread count (a
    workload setting, not the structure's)."""
    csv_labels = rows["label"] if "label" in rows.columns else pd.Series("", index=rows.index)
    base = pd.Series(
        [table_or_csv_label(a, p, c) for a, p, c in zip(rows["accel"], rows["param_dict"], csv_labels)],
        index=rows.index,
        dtype=object,
    )
    labels = base.copy()
    for _, group in rows.groupby(base):
        dicts = group["param_dict"]
        keys = sorted({k for d in dicts for k in d})
        varying = [k for k in keys if k != "threads" and len({d.get(k) for d in dicts}) > 1]
        for i, d in dicts.items():
            extra = ",".join(f"{k}={d.get(k, '')}" for k in varying)
            labels[i] = f"{base[i]} [{extra}]" if extra else base[i]
    return labels


def workload_labels(rows: pd.DataFrame) -> pd.Series:
    """The render settings (threads, image, light, ...) that vary among the rows, as text
    ("render_threads=2; image_width=320"), "" where none varies: rows of different workloads
    are never compared or divided by each other."""
    settings = [c for c in RENDER_SETTING_COLUMNS if c in rows.columns]
    varying = [c for c in settings if rows[c].astype(str).nunique() > 1]
    if not varying:
        return pd.Series("", index=rows.index, dtype=object)

    def text(v) -> str:
        return str(int(v)) if isinstance(v, float) and v == int(v) else str(v)

    return rows[varying].apply(lambda r: "; ".join(f"{c}={text(r[c])}" for c in varying), axis=1)


def ray_set_rows(results: Results) -> pd.DataFrame:
    rows = results.ok()
    rows = rows[rows["ray_set"].isin(RAY_SETS)].copy()
    if rows.empty:
        return rows
    rows["structure"] = structure_labels(rows)
    rows["workload"] = workload_labels(rows)
    # One panel of the tables and the figure per model and workload.
    rows["panel"] = [m if not w else f"{m} ({w})" for m, w in zip(rows["model"], rows["workload"])]
    rows["ray_set"] = pd.Categorical(
        rows["ray_set"], categories=[s for s in RAY_SETS if s in set(rows["ray_set"])], ordered=True
    )
    return rows


def baseline_row(group: pd.DataFrame) -> pd.Series | None:
    """Embree's row of one model, set and workload: the only one, else the one at Embree's
    defaults; None when there is none or no single one."""
    embree = group[group["accel"].isin(baseline_accels())]
    if len(embree) <= 1:
        return None if embree.empty else embree.iloc[0]
    score = embree["param_dict"].map(lambda p: sum(p.get(k) == v for k, v in EMBREE_PREFERRED))
    best = embree[score == score.max()]
    return best.iloc[0] if len(best) == 1 else None


# The counts of `verdict_counts` that are rays a catalogue case leaked: rays that must hit
# and missed, as a failure (`leaks`) or tolerated by a labelled ablation (`leaks_tolerated`).
LEAK_COUNTS = ("leaks", "leaks_tolerated")


def catalogue_leaks(results: Results) -> dict[tuple[str, str], int]:
    """Per structure (accel, canonical params), the rays the extreme-case catalogue's cases
    in this input leaked, summed over its cases: what a structure's guarantees buy, beside
    what they cost in the ray-set table. Empty without catalogue rows among the input
    (configs/ray-sets.yaml and configs/robustness.yaml have them)."""
    cases = results.case_rows()
    out: dict[tuple[str, str], int] = {}
    for accel, params, counts in zip(cases["accel"], cases["params"], cases["verdict_counts"]):
        fields = dict(f.split("=", 1) for f in str(counts).split() if "=" in f)
        out[(accel, params)] = out.get((accel, params), 0) + sum(int(fields.get(k, 0)) for k in LEAK_COUNTS)
    return out


def ray_set_table(
    rows: pd.DataFrame,
    leaks: dict[tuple[str, str], int] | None = None,
    reps: pd.DataFrame | None = None,
) -> pd.DataFrame:
    """One row per model, workload, structure and set: Mrays/s and its ratio to Embree's row
    of the same model, set and workload (threads, image, ...): never to another thread
    count's, never to a median of several. `ratio_to_embree_worse_process`: where the row
    was timed alternately with that Embree row, the worse over their processes of the ratio
    of the two per-process medians (`reps`, the repetitions; mapping/interleaved.py), else
    NaN. `baseline`: the row is that Embree row. `catalogue_leaks`: the structure's leaks
    over the extreme-case catalogue (catalogue_leaks) where the input has its cases, else
    empty."""
    cols = [
        "model",
        "workload",
        "panel",
        "structure",
        "ray_set",
        "mrays_per_s",
        "rays",
        "false_misses",
        "false_hits",
    ]
    parts, worse = [], pd.Series(float("nan"), index=rows.index)
    medians = process_medians(reps)
    for _, g in rows.groupby(["model", "workload", "ray_set"], observed=True, sort=False):
        t = g[cols].copy()
        base = baseline_row(g)
        t["embree_mrays_per_s"] = float("nan") if base is None else base["mrays_per_s"]
        t["baseline"] = False if base is None else t.index == base.name
        for i, r in g.iterrows():
            worse[i] = worse_process_ratio(medians, r, base)
        parts.append(t)
    t = pd.concat(parts) if parts else pd.DataFrame(columns=cols + ["embree_mrays_per_s", "baseline"])
    t["ratio_to_embree"] = t["mrays_per_s"] / t["embree_mrays_per_s"]
    t["ratio_to_embree_worse_process"] = worse  # aligned on the rows' index, as below
    leak = pd.Series(
        [(leaks or {}).get(k, float("nan")) for k in zip(rows["accel"], rows["params"])], rows.index
    )
    t["catalogue_leaks"] = leak  # aligned on the rows' index, which the parts keep
    return t.sort_values(["model", "workload", "structure", "ray_set"]).reset_index(drop=True)


def ranking(rows: pd.DataFrame) -> pd.DataFrame:
    """Per panel (model and workload) and set, each structure's rank by Mrays/s (1 =
    fastest), and whether it differs from its rank in the first set listed."""
    r = rows[["panel", "structure", "ray_set", "mrays_per_s"]].copy()
    r["rank"] = (
        r.groupby(["panel", "ray_set"], observed=True)["mrays_per_s"]
        .rank(ascending=False, method="min")
        .astype(int)
    )
    first = r["ray_set"].cat.categories[0]
    ref = r[r["ray_set"] == first].set_index(["panel", "structure"])["rank"].rename("first_rank")
    r = r.join(ref, on=["panel", "structure"])
    r["changed"] = r["rank"] != r["first_rank"]
    return r


def md_table(header: list[str], body: list[list[str]]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(row) + " |" for row in body]
    return out


def cells_per_set(rows: pd.DataFrame, sets: list[str], cell) -> list[str]:
    """One structure's cells, one per ray set: `cell` of its row in that set, "-" where it
    has none."""
    out = []
    for rs in sets:
        hit = rows[rows["ray_set"] == rs]
        out.append("-" if hit.empty else cell(hit.iloc[0]))
    return out


def _mrays_cell(r: pd.Series) -> str:
    cell = f"{r['mrays_per_s']:.3g}"
    if pd.notna(r["ratio_to_embree"]):
        # The Embree row's own worse process is 1 by definition: not shown.
        worse = r["ratio_to_embree_worse_process"] if not r["baseline"] else float("nan")
        cell += f" ({r['ratio_to_embree']:.2f}x" + (
            f"; worse process {worse:.2f}x)" if pd.notna(worse) else ")"
        )
    wrong = (r["false_misses"] if pd.notna(r["false_misses"]) else 0) + (
        r["false_hits"] if pd.notna(r["false_hits"]) else 0
    )
    return cell + (f" [{int(wrong)} wrong]" if wrong else "")


def ray_set_markdown(table: pd.DataFrame) -> str:
    sets = (
        list(table["ray_set"].cat.categories)
        if hasattr(table["ray_set"], "cat")
        else sorted(set(table["ray_set"]))
    )
    out = [
        "# Mrays/s per ray set",
        "",
        "Each structure's Mrays/s on each ray set (configs/ray-sets.yaml; every set made "
        "once per model from the reference's hits, so every structure traces the same rays), "
        "and in parentheses its ratio to Embree's row of the same model, set and workload "
        "(threads, image: a model measured at several has a section for each; > 1: faster than "
        "Embree; none where there is no single such Embree row). Where a structure was timed "
        "alternately with that Embree row in the same processes (`interleave: true`), the "
        "ratio is followed by the worse process's: in each process the ratio of the two "
        "medians timed there turn by turn, the smallest of them (the structure's worse "
        "process). Wrong answers against the reference (false misses + false hits) are shown "
        "where there are any.",
        "",
    ]
    with_leaks = table["catalogue_leaks"].notna().any()
    if with_leaks:
        out += [
            "`catalogue leaks`: the rays that must hit and missed over the extreme-case "
            "catalogue's cases (its rows in this input: configs/ray-sets.yaml runs it for "
            "its own structures, configs/robustness.yaml for every option), summed: 0 "
            "for a watertight structure, what an ablation gives up for its speed; - where the "
            "catalogue did not run the structure.",
            "",
        ]
    for panel, g in table.groupby("panel"):
        out += [f"## {md_escape(panel)}", ""]
        body = []
        for structure, s in g.groupby("structure"):
            leak = s["catalogue_leaks"].iloc[0]
            extra = [f"{int(leak):,}" if pd.notna(leak) else "-"] if with_leaks else []
            body.append([md_escape(structure), *cells_per_set(s, sets, _mrays_cell), *extra])
        out += md_table(["structure"] + sets + (["catalogue leaks"] if with_leaks else []), body) + [""]
    return "\n".join(out)


def ranking_markdown(rank: pd.DataFrame) -> str:
    sets = list(rank["ray_set"].cat.categories)
    out = [
        "# Ranking by ray set",
        "",
        f"Per model and workload, each structure's rank by Mrays/s in each ray set (1 = fastest). A rank "
        f"marked * differs from its rank on `{sets[0]}` rays: there the order of structures "
        f"changes. The last column lists the sets in which the order changes.",
        "",
    ]
    for panel, g in rank.groupby("panel"):
        out += [f"## {md_escape(panel)}", ""]
        body = []
        order = g[g["ray_set"] == sets[0]].sort_values("rank")["structure"].tolist()
        order += sorted(set(g["structure"]) - set(order))
        for structure in order:
            s = g[g["structure"] == structure]
            rank = cells_per_set(s, sets, lambda r: f"{int(r['rank'])}" + ("*" if r["changed"] else ""))
            body.append([md_escape(structure), *rank])
        changed = [rs for rs in sets if g[(g["ray_set"] == rs)]["changed"].any()]
        out += md_table(["structure"] + sets, body)
        out += ["", "Order changes in: " + (", ".join(changed) if changed else "none") + ".", ""]
    return "\n".join(out)


def hue_palette(labels: pd.Series) -> dict[str, str]:
    """The structures' colours (mapping/styles.py, the structure table's order), the same as
    in every other figure; written out so that the interactive version draws the same."""
    return Styles(labels).palette()


def thread_scaling_rows(results: Results) -> pd.DataFrame:
    rows = results.ok()
    rows = rows[(rows["ray_set"] == CAMERA_SET) & _thread_scaling_configs(rows)].copy()
    if rows.empty:
        return rows
    rows["structure"] = structure_labels(rows)
    # Per file too: the 1-thread row of another run of the same config is not this one's.
    keys = ["source", "config", "model", "structure"]
    first = rows[rows["render_threads"] == 1].set_index(keys)
    rows = rows.join(first["render_s_median"].rename("wall_1"), on=keys)
    rows = rows.join(first["build_s_median"].rename("build_1"), on=keys)
    rows["speedup"] = rows["wall_1"] / rows["render_s_median"]
    rows["efficiency"] = rows["speedup"] / rows["render_threads"]
    rows["build_speedup"] = rows["build_1"] / rows["build_s_median"]
    if "render_cpu_s_median" in rows.columns:
        rows["cpu_per_wall"] = rows["render_cpu_s_median"] / rows["render_s_median"]
    return rows.sort_values(keys + ["render_threads"]).reset_index(drop=True)


def thread_scaling_markdown(rows: pd.DataFrame) -> str:
    out = [
        "# Thread scaling",
        "",
        "Build wall time, render wall time and the render's process CPU time per thread count "
        "(medians; configs/thread-scaling.yaml); speedup = wall time at 1 thread / wall time at "
        "t threads, of the build and of the render; parallel efficiency = render speedup / t. "
        "A structure with a `threads` parameter (Embree, bvh, wbvh, kdtree, lbvh) builds on t "
        "threads, the others on one. CPU / wall near t means the threads were busy; a speedup "
        "below that means they competed (memory, the machine's other load).",
        "",
    ]
    has_cpu = "render_cpu_s_median" in rows.columns
    for model, g in rows.groupby("model"):
        out += [f"## {md_escape(model)}", ""]
        body = []
        for _, r in g.iterrows():
            body.append(
                [
                    md_escape(r["structure"]),
                    f"{int(r['render_threads'])}",
                    f"{r['build_s_median'] * 1e3:.2f}",
                    f"{r['build_speedup']:.2f}" if pd.notna(r["build_speedup"]) else "-",
                    f"{r['render_s_median'] * 1e3:.2f}",
                    f"{r['render_cpu_s_median'] * 1e3:.2f}"
                    if has_cpu and pd.notna(r["render_cpu_s_median"])
                    else "-",
                    f"{r['speedup']:.2f}" if pd.notna(r["speedup"]) else "-",
                    f"{r['efficiency']:.2f}" if pd.notna(r["efficiency"]) else "-",
                ]
            )
        out += md_table(
            [
                "structure",
                "threads",
                "build ms",
                "build speedup",
                "render wall ms",
                "render CPU ms",
                "render speedup",
                "efficiency",
            ],
            body,
        ) + [""]
    return "\n".join(out)


def thread_scaling_long(rows: pd.DataFrame) -> pd.DataFrame:
    """The build's and the render's speedups as rows of one column, `measure` saying which."""
    keep = ["model", "structure", "render_threads"]
    both = [
        rows[keep].assign(measure="build", speedup=rows["build_speedup"], wall_s=rows["build_s_median"]),
        rows[keep].assign(measure="render", speedup=rows["speedup"], wall_s=rows["render_s_median"]),
    ]
    return pd.concat(both, ignore_index=True)


def write_workloads(results: Results, out_dir: Path) -> list[Path]:
    """Writes the ray-set and thread-scaling outputs that the rows allow; [] when the
    input has neither kind of row."""
    written: list[Path] = []
    tables, figures = out_dir / "tables", out_dir / "figures"
    rows = ray_set_rows(results)
    if not rows.empty:
        tables.mkdir(parents=True, exist_ok=True)
        figures.mkdir(parents=True, exist_ok=True)
        table = ray_set_table(rows, catalogue_leaks(results), results.reps)
        palette = hue_palette(rows["structure"])
        (tables / "ray_sets.md").write_text(ray_set_markdown(table))
        table = table.drop(columns=["baseline"])  # the markdown's, not a column of the outputs
        table.drop(columns=["panel"]).to_csv(tables / "ray_sets.csv", index=False)
        (tables / "ray_set_ranking.md").write_text(ranking_markdown(ranking(rows)))
        written += [
            tables / "ray_sets.md",
            tables / "ray_sets.csv",
            tables / "ray_set_ranking.md",
            write_figure(
                figures / "ray_sets.png", ray_sets_spec(table, list(rows["ray_set"].cat.categories), palette)
            ),
        ]
    ts = thread_scaling_rows(results)
    if not ts.empty:
        tables.mkdir(parents=True, exist_ok=True)
        figures.mkdir(parents=True, exist_ok=True)
        cols = [
            c
            for c in [
                "config",
                "model",
                "structure",
                "render_threads",
                "build_s_median",
                "build_speedup",
                "render_s_median",
                "render_cpu_s_median",
                "speedup",
                "efficiency",
                "cpu_per_wall",
            ]
            if c in ts.columns
        ]
        ts[cols].to_csv(tables / "thread_scaling.csv", index=False)
        (tables / "thread_scaling.md").write_text(thread_scaling_markdown(ts))
        written += [
            tables / "thread_scaling.md",
            tables / "thread_scaling.csv",
            write_figure(
                figures / "thread_scaling.png",
                thread_scaling_spec(thread_scaling_long(ts), hue_palette(ts["structure"])),
            ),
        ]
    return written
