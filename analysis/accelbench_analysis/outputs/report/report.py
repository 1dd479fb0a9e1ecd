"""A run's REPORT.md (results/reference/, results/runs/<run>/): one page that says where the
numbers come from, sets them beside the report's and the reference run's, and links the
tables, the claims and the figures, each with a one-line caption."""

from __future__ import annotations

from pathlib import Path

from ...inputs.report_numbers import REPORT_MACHINE, REPORT_MODELS
from ...inputs.schema import FP_MODE_COLUMN, Results
from ...mapping.formatting import md_escape
from ..figures.figures import FIGURES, Skipped
from .claims import FAILS, HOLDS, NOT_COMPARABLE, ClaimRow, reference_ablation_text, summary_line
from .comparison import TIME_METRICS, ThreeWay, comparison_markdown

TABLE_CAPTIONS = {
    "table2": "Table 2: kd-tree maxPrims and maxDepth sweeps on the Stanford bunny.",
    "table4": "Table 4: BVH, LBVH and kd-tree (plus binned-SAH BVH and Embree) on bunny, Igea, "
    "dragon and Buddha; with a 'relative to BVH' table.",
    "table5": "Table 5: the complex scenes (procedural forest and city); with a 'relative to BVH' table.",
}
REGENERATE = "make reproduce-tables"


def provenance_lines(results: Results) -> list[str]:
    rows = results.rows
    ts = sorted(t for t in rows["timestamp"] if t)
    threads = sorted({f"{t:g}" for t in rows["render_threads"].dropna()})
    out = []
    for g in results.groups:
        f = g.fields
        head = f"group {g.label}: " if results.mixed else ""
        out.append(
            f"- {head}**Machine:** {f['cpu']}"
            + (f" (threads: {', '.join(threads)})" if threads and not results.mixed else "")
        )
        out.append(
            f"  **Commit:** `{f['git_sha']}`"
            + (" **(dirty work tree)**" if f["git_dirty"] == "true" else "")
            + f"; {f['compiler']}, {f['build_type']}; Embree {f['embree_version']}; {g.rows} rows"
        )
        # A ratio against Embree is also a ratio of instruction sets: say which each side ran.
        out.append(
            f"  **ISA:** our structures `{f['isa']}` (compiled for, `isa`); "
            f"Embree's kernels `{f['embree_isa']}` (its run-time choice, `embree_isa`)"
        )
    modes = rows[FP_MODE_COLUMN].value_counts()
    out.append(
        "- **Floating-point mode of the traces:** "
        + ", ".join(f"{m} ({n} rows)" if len(modes) > 1 else m for m, n in modes.items())
        + " (ieee: IEEE 754; ftz_daz: flush-to-zero and denormals-are-zero; the robustness catalogue always ieee)"
    )
    if ts:
        out.append(f"- **Measured:** {ts[0]}" + (f" to {ts[-1]}" if ts[-1] != ts[0] else ""))
    out.append("- **CSV:** " + ", ".join(f"`{f}`" for f in results.files))
    return out


def stand_in_lines() -> list[str]:
    same = [m.label for m in REPORT_MODELS if m.stand_in is None]
    out = [f"- {', '.join(same)}: the report's own models (same meshes)."]
    out += [f"- {m.label}: {m.stand_in}." for m in REPORT_MODELS if m.stand_in]
    return out


def claims_lines(rows: list[ClaimRow] | None) -> list[str]:
    if not rows:
        return ["- [The report's claims, checked](tables/claims.md)"]
    n = {v: sum(r.ours.verdict == v for r in rows) for v in (HOLDS, FAILS, NOT_COMPARABLE)}
    out = [
        f"- [The report's claims, checked](tables/claims.md) ([CSV](tables/claims.csv)): each "
        f"claim of sections 5.1-6 evaluated on the report's numbers and on ours, with a class "
        f"and a measured reason for each that does not hold. Ours: **{n[HOLDS]} hold, "
        f"{n[FAILS]} do not hold, {n[NOT_COMPARABLE]} not comparable**. {summary_line(rows)}"
    ]
    fails = [r for r in rows if r.ours.verdict == FAILS]
    if fails:
        out.append(
            "  Not holding here: "
            + "; ".join(
                f"{r.claim.id} {md_escape(r.claim.text)} [{r.cls}: {md_escape(r.reason)}]" for r in fails
            )
            + "."
        )
    dependent = [r for r in rows if r.machine_dependent]
    if dependent:
        out.append(
            "  Machine-dependent (the verdict differs on the committed reference run): "
            + "; ".join(
                f"{r.claim.id} (here {r.ours.verdict}, reference run {r.reference.verdict}: "
                + (
                    "within this run's timing spread, so noise)"
                    if r.flip_within_noise
                    else "beyond this run's timing spread)"
                )
                for r in dependent
            )
            + "."
        )
    elif any(r.reference is not None for r in rows):
        out.append(
            "  Every claim judged on both has the same verdict here as on the committed reference run."
        )
    if any(r.reference is not None for r in rows):
        out.append("  " + reference_ablation_text(rows))
    unsupported = [r for r in rows if r.report.verdict == FAILS]
    if unsupported:
        out.append(
            "  Not supported by the report's own numbers: "
            + "; ".join(f"{r.claim.id} ({md_escape(r.report.evidence)})" for r in unsupported)
            + "."
        )
    return out


def cost_model_section(out_dir: Path) -> list[str]:
    """The claims' cost model (tables/cost_model.md, written with the claims), shown here
    with its links made relative to REPORT.md."""
    path = out_dir / "tables" / "cost_model.md"
    if not path.is_file():
        return []
    body = [line for line in path.read_text().splitlines() if not line.startswith("# ")]
    body = [line.replace("](cost_model.csv)", "](tables/cost_model.csv)") for line in body]
    while body and not body[0]:
        body = body[1:]
    return ["", "## Cost model", ""] + body


def figure_lines(out_dir: Path, figures: dict | None) -> list[str]:
    out = []
    for name, (caption, _) in FIGURES.items():
        rel = f"figures/{name}.png"
        result = (figures or {}).get(name)
        if isinstance(result, Skipped):
            out.append(f"- {caption}: not drawn, {result.reason}.")
        elif (out_dir / rel).is_file():
            out.append(f"- [{caption}]({rel})")
        else:
            out.append(f"- {caption}: not generated yet (`python -m accelbench_analysis figures ...`).")
    return out


def beyond_report_lines(out_dir: Path) -> list[str]:
    """Links to the scaling and cost-image outputs (written by the `scaling` and
    `cost-images` commands) when they exist in out_dir."""
    out = []
    if (out_dir / "figures" / "scaling.png").is_file():
        out.append(
            "- [Build and render time against triangles, log-log, with fitted slopes per "
            "structure](figures/scaling.png) ([slopes](tables/scaling.md)): the Stanford "
            "dragon decimated with OpenMesh and the bunny Loop-subdivided."
        )
    # `make robustness` writes results/robustness/ (beside results/reference/, the committed
    # run); `tables`/`all` write tables/robustness.md when given a robustness run's CSV.
    for rel in (
        "robustness/robustness.md",
        "tables/robustness.md",
        "robustness.md",
        "../robustness/robustness.md",
    ):
        if (out_dir / rel).is_file():
            out.append(
                f"- [Robustness]({rel}): a pass/FAIL verdict per extreme case "
                f"(configs/robustness.yaml) and accelerator, the failures with their "
                f"counts, and the stiff-parameter runs with memory and errors."
            )
            break
    if (out_dir / "tables" / "ray_sets.md").is_file():
        out.append(
            "- [Mrays/s per ray set](tables/ray_sets.md) (primary, shadow, ambient "
            "occlusion, diffuse bounces, random rays; each structure also as a ratio to "
            "Embree), the [ranking of structures by ray set](tables/ray_set_ranking.md) "
            "marking where their order changes, and [the figure](figures/ray_sets.png)."
        )
    if (out_dir / "tables" / "thread_scaling.md").is_file():
        out.append(
            "- [Thread scaling](tables/thread_scaling.md): build and render wall time, the "
            "render's CPU time, both speedups and the render's parallel efficiency at 1..nproc "
            "threads "
            "([figure](figures/thread_scaling.png))."
        )
    for png in sorted((out_dir / "figures").glob("cost-*.png")):
        model = png.stem[len("cost-") :]
        out.append(
            f"- [Cost images, {model}](figures/{png.name}): node visits and triangle "
            f"tests per pixel for each structure beside the shaded image — where each "
            f"structure spends its work."
        )
    return ["", "## Beyond the report", ""] + out if out else []


def comparison_lines(
    comparison: list[ThreeWay] | None, results: Results, reference: Results | None, reference_dir: Path | None
) -> list[str]:
    """The times of the three-way comparison inline; every metric in tables/comparison.md."""
    if comparison is None:
        return []
    out = [
        "",
        "## This run beside the report and the committed reference run",
        "",
        "Per structure and model: the report's number, this run's, the committed reference "
        "run's, and this/report, this/reference. A time ratio this/reference near 1 means "
        "this machine reproduces ours; compare the report by orderings (its machine and "
        "implementation were much slower). The counts (primitive tests, nodes), which must "
        "equal the reference run's: [tables/comparison.md](tables/comparison.md).",
        "",
    ]
    return out + comparison_markdown(comparison, results, reference, reference_dir, metrics=TIME_METRICS)[:-1]


def report_markdown(
    results: Results,
    out_dir: Path,
    claims: list[ClaimRow] | None,
    figures: dict | None,
    comparison: list[ThreeWay] | None = None,
    reference: Results | None = None,
    reference_dir: Path | None = None,
) -> str:
    out = [
        "# accelbench results",
        "",
        'A reproduction of the report "Implementation and Analysis of Acceleration Data '
        'Structures in Ray Tracing" (Freiburg 2022): its Tables 2, 4 and 5 and the claims '
        "of its sections 5.1-6, measured again, plus structures it did not have (binned-SAH "
        "BVH, Embree).",
        "",
    ]
    out += [f"> **Warning:** {md_escape(w)}\n" for w in results.warnings]
    out += ["## Where these numbers come from", ""] + provenance_lines(results)
    out += comparison_lines(comparison, results, reference, reference_dir)
    out += ["", "## Stand-ins", ""] + stand_in_lines()
    out += ["", "## Tables", ""]
    for name, caption in TABLE_CAPTIONS.items():
        if (out_dir / "tables" / f"{name}.md").is_file():
            out.append(f"- [{caption}](tables/{name}.md) ([LaTeX](tables/{name}.tex))")
        else:
            out.append(f"- {caption} Not generated yet.")
    out += claims_lines(claims)
    out += ["- [The report's numbers](report/report-tables.csv) as printed ([provenance](report/README.md))."]
    out += cost_model_section(out_dir)
    out += ["", "## Figures", ""] + figure_lines(out_dir, figures)
    out += beyond_report_lines(out_dir)
    out += [
        "",
        "## Reading the comparison",
        "",
        f"- The report measured on another machine ({REPORT_MACHINE}) with a much slower "
        f"implementation: compare orderings and ratios (the 'relative to BVH' tables and "
        f"figure), not seconds.",
        '- The report\'s "#Primitives" are vertex counts (bunny, Igea) and its Table 4 BVH '
        "node counts are 2 x #Primitives - 1; the tables show our triangle and vertex counts "
        "side by side and check both facts in their notes.",
        '- Our "#int. tests" are primitive tests summed over all rays (primary + shadow); '
        "the report does not define its count.",
        "",
        "## Regenerate",
        "",
        f"`{REGENERATE}` (measures on this machine into a new results/runs/<time>-<sha>/, "
        f"then `python -m accelbench_analysis all <csv> --out <that directory>`; see "
        f"README.md and analysis/README.md).",
        "",
    ]
    return "\n".join(out)


def write_report(
    results: Results,
    out_dir: Path,
    claims: list[ClaimRow] | None = None,
    figures: dict | None = None,
    comparison: list[ThreeWay] | None = None,
    reference: Results | None = None,
    reference_dir: Path | None = None,
) -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "REPORT.md"
    path.write_text(report_markdown(results, out_dir, claims, figures, comparison, reference, reference_dir))
    return path
