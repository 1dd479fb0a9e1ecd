"""A run's REPORT.md (results/reference/, results/runs/<run>/, any run of any scenes): it
opens with the answer the run gives (each structure against Embree on each scene and ray
set, ranked), then the claims' counts when the report's models were measured, the figures
the data allow, and last where the numbers come from. The report's tables and claims are a
section only when the run measured the report's models; the three-way comparison only when
a reference run is given. Every document is linked once, so the page (run_page.py) shows
each once."""

from __future__ import annotations

from pathlib import Path

from ...inputs.report_numbers import REPORT_MACHINE, REPORT_MODELS
from ...inputs.schema import FP_MODE_COLUMN, Results
from ...mapping.formatting import ci_label, md_escape, repetitions_text
from ..figures.figures import FIGURES, Skipped
from .claim_verdicts import summary_with_matrix
from .claims_output import ClaimsResult, plain_statements
from .comparison import ThreeWay
from .peers import PEERS_CSV, PEERS_DOC, PEERS_FIGURE
from .ranking import RANKING_DOC, full_ranking_markdown, ranking_markdown

TABLE_CAPTIONS = {
    "table2": "Table 2: kd-tree maxPrims and maxDepth sweeps on the Stanford bunny.",
    "table4": "Table 4: BVH, LBVH and kd-tree (plus binned-SAH BVH and Embree) on bunny, Igea, "
    "dragon and Buddha; with a 'relative to BVH' table.",
    "table5": "Table 5: the complex scenes (procedural forest and city); with a 'relative to BVH' table.",
}
REGENERATE = "make reproduce-tables"


REPORT_SECTION = "The report's tables and claims"
REPORT_SECTION_ANCHOR = "#the-report-s-tables-and-claims"  # run_page's slug of the heading


def report_models_measured(results: Results) -> bool:
    """Whether the run measured any of the report's models (or their stand-ins): only then
    do its tables and claims have rows to show."""
    ours = {name for m in REPORT_MODELS for name in m.ours}
    return bool(ours & set(results.rows["model"]))


def provenance_line(results: Results) -> str:
    """The one line the report opens with: machine, commit, ISA and render threads, named as
    what they are (several provenance groups: their count, detailed at the end)."""
    if results.mixed:
        return f"**{len(results.groups)} builds or machines** (see [where these numbers come from](#where-these-numbers-come-from))."
    f = results.groups[0].fields
    threads = sorted({f"{t:g}" for t in results.rows["render_threads"].dropna()})
    dirty = " (dirty tree)" if f["git_dirty"] == "true" else ""
    return (
        f"**Machine:** {md_escape(f['cpu'])} · **commit** `{f['git_sha'][:12]}`{dirty} · **ISA** `{f['isa']}` "
        f"(Embree's kernels `{f['embree_isa']}`) · **render threads:** {', '.join(threads) or '—'}"
    )


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
            + f"; {f['compiler']}, {f['build_type']} (flags `{f['compile_flags']}`)"
            + f"; Embree {f['embree_version']}; {g.rows} rows"
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
    out += timing_lines(results)
    out.append("- **CSV:** " + ", ".join(f"`{f}`" for f in results.files))
    return out


def timing_lines(results: Results) -> list[str]:
    """How each config's timed rows were measured (repetitions, the processes they were
    pooled from, the intervals' coverage), configs measured alike on one line."""
    rows = results.ok()
    if rows.empty or "config" not in rows:
        return []
    alike: dict[str, list[str]] = {}
    for config, part in rows.groupby("config", sort=False):
        how = f"{repetitions_text(part)}; {ci_label(part.get('ci_coverage', []))}"
        alike.setdefault(how, []).append(str(config))
    return [
        "- **Timed rows:** each time is the median of its row's repetitions, its interval the "
        "median's order-statistics interval (CI: its exact coverage, `ci_coverage`)"
    ] + [f"  - {', '.join(configs)}: {how}" for how, configs in alike.items()]


def stand_in_lines() -> list[str]:
    same = [m.label for m in REPORT_MODELS if m.stand_in is None]
    out = [f"- {', '.join(same)}: the report's own models (same meshes)."]
    out += [f"- {m.label}: {m.stand_in}." for m in REPORT_MODELS if m.stand_in]
    return out


def claims_count_lines(result: ClaimsResult | None) -> list[str]:
    """The claims' one summary near the top, as claims.md has it: what a reader must know
    first, the counts at default and faithful, then every claim under every setting."""
    if result is None or not result.rows:
        return []
    return [
        "",
        "## The report's claims",
        "",
        *plain_statements(result),
        *summary_with_matrix(result.rows, result.matrix),
        "",
        f"Why each does not hold, and the report's tables: [{REPORT_SECTION}]({REPORT_SECTION_ANCHOR}); "
        "[the claims one by one](tables/claims.md).",
    ]


def claims_lines(result: ClaimsResult | None) -> list[str]:
    """The claims' link in the tables list."""
    link = "- [The report's claims, checked](tables/claims.md)"
    if result is None:
        return [link]
    return [
        link + " ([CSV](tables/claims.csv); every claim under every setting: "
        "[tables/claims_factors.csv](tables/claims_factors.csv), [heat map](figures/claims_factors.png))"
    ]


def claims_section(result: ClaimsResult | None) -> list[str]:
    """The claims whose default verdict differs on the committed reference run (the summary
    stands at the top)."""
    if result is None or result.reference is None:
        return []
    dependent = result.machine_dependent()
    return [
        "",
        "Machine-dependent claims (hold at default on one run, not on the committed reference run, "
        "each outside its run's noise): " + (", ".join(dependent) if dependent else "none") + ".",
    ]


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


def figure_lines(out_dir: Path, figures: dict | None, say_skipped: bool = True) -> list[str]:
    """A line per figure drawn; with say_skipped (a run of the report's models), also why a
    figure of the report's study was not drawn."""
    out = []
    for name, (caption, _) in FIGURES.items():
        rel = f"figures/{name}.png"
        result = (figures or {}).get(name)
        if isinstance(result, Skipped):
            if say_skipped:
                out.append(f"- {caption}: not drawn, {result.reason}.")
        elif (out_dir / rel).is_file():
            out.append(f"- [{caption}]({rel})")
        elif say_skipped:
            out.append(f"- {caption}: not generated yet (`python -m accelbench_analysis figures ...`).")
    return out


def beyond_report_lines(out_dir: Path) -> list[str]:
    """Links to the scaling and cost-image outputs (written by the `scaling` and
    `cost-images` commands) when they exist in out_dir, and the full ranking."""
    out = []
    if (out_dir / RANKING_DOC).is_file():
        out.append(
            f"- [Every structure at every setting against Embree]({RANKING_DOC}), per scene and ray set, ranked."
        )
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
                f"- [Robustness]({rel}): a pass/FAIL verdict per extreme case and "
                f"accelerator setting the run judged (configs/robustness.yaml: every option; "
                f"configs/ray-sets.yaml: its own structures), the failures with their counts, "
                f"and any stiff-parameter runs with memory and errors."
            )
            break
    if (out_dir / "tables" / "ray_sets.md").is_file():
        out.append(
            "- [Mrays/s per ray set](tables/ray_sets.md) (primary, shadow, ambient "
            "occlusion, diffuse bounces, random rays; each structure also as a ratio to "
            "Embree), the [ranking of structures by ray set](tables/ray_set_ranking.md) "
            "marking where their order changes, and [the figure](figures/ray_sets.png)."
        )
    if (out_dir / PEERS_DOC).is_file():
        out.append(
            f"- [The open peers beside ours and Embree]({PEERS_DOC}): the structures loaded "
            "from plugins (tinybvh, bvh v2, ...) and every other structure of the same models, "
            "ranked per ray set by trace time over Embree's, with the build time over Embree's "
            f"and every wrong answer ([CSV]({PEERS_CSV}), [figure]({PEERS_FIGURE}))."
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
    return ["", "## More of this run", ""] + out if out else []


def comparison_lines(comparison: list[ThreeWay] | None, reference: Results | None) -> list[str]:
    """The three-way comparison (tables/comparison.md), linked once; only when a reference
    run was given and holds rows like this run's."""
    if comparison is None or reference is None:
        return []
    out = [
        "",
        "## This run beside the report and the committed reference run",
        "",
        "Per structure and model: the report's number, this run's, the committed reference "
        "run's, and this/report, this/reference. A time ratio this/reference near 1 means "
        "this machine reproduces ours; compare the report by orderings (its machine and "
        "implementation were much slower). Every metric, the counts (primitive tests, nodes) too, which must "
        "equal the reference run's: [the comparison](tables/comparison.md).",
    ]
    return out


def report_section(out_dir: Path, claims: ClaimsResult | None, warnings: list[str]) -> list[str]:
    """The report's tables and claims: only for a run of the report's models."""
    out = [
        "",
        f"## {REPORT_SECTION}",
        "",
        *[f"> **Note:** {md_escape(w)}\n" for w in warnings],
        'This run measured the models of the report "Implementation and Analysis of Acceleration '
        'Data Structures in Ray Tracing" (Freiburg 2022): its Tables 2, 4 and 5 and the claims of '
        "its sections 5.1-6, measured again, beside structures it did not have (binned-SAH BVH, "
        "Embree).",
        "",
        "Stand-ins:",
        "",
        *stand_in_lines(),
        "",
        "Tables and claims:",
        "",
    ]
    for name, caption in TABLE_CAPTIONS.items():
        if (out_dir / "tables" / f"{name}.md").is_file():
            out.append(f"- [{caption}](tables/{name}.md) ([LaTeX](tables/{name}.tex))")
    out += claims_lines(claims)
    out += ["- [The report's numbers](report/report-tables.csv) as printed ([provenance](report/README.md))."]
    out += [
        "",
        "Reading the comparison:",
        "",
        f"- The report measured on another machine ({REPORT_MACHINE}) with a much slower "
        f"implementation: compare orderings and ratios (the 'relative to BVH' tables and "
        f"figure), not seconds.",
        '- The report\'s "#Primitives" are vertex counts (bunny, Igea) and its Table 4 BVH '
        "node counts are 2 x #Primitives - 1; the tables show our triangle and vertex counts "
        "side by side and check both facts in their notes.",
        '- Our "#int. tests" are primitive tests summed over all rays (primary + shadow); '
        "the report does not define its count.",
    ]
    return out + claims_section(claims) + cost_model_section(out_dir)


def report_markdown(
    results: Results,
    out_dir: Path,
    claims: ClaimsResult | None,
    figures: dict | None,
    comparison: list[ThreeWay] | None = None,
    reference: Results | None = None,
    ranked: Results | None = None,
    everything: Results | None = None,
) -> str:
    """`ranked`: the rows the ranking shows (every measured row of the run but the thread
    scaling's); `results` those of the report's workload, which the figures drew;
    `everything`: every row of the run, whose provenance (machine, threads, floating-point
    mode, times, how each config was measured, files) the report states, also for a run of
    ray sets only (configs/peers.yaml), which has none of the report's workload."""
    ranked = ranked if ranked is not None else results
    everything = everything if everything is not None else results
    out = [f"# accelbench results: {md_escape(out_dir.resolve().name)}", "", provenance_line(everything), ""]
    out += [f"> **Warning:** {md_escape(w)}\n" for w in ranked.warnings]
    out += ranking_markdown(ranked)
    measured = report_models_measured(results)
    if measured:
        out += claims_count_lines(claims)
    drawn = figure_lines(out_dir, figures, say_skipped=measured)
    out += ["", "## Figures", ""] + drawn if drawn else []
    out += beyond_report_lines(out_dir)
    if measured:
        # What choosing the report's workload left out (report_rows) concerns its tables only.
        out += report_section(out_dir, claims, [w for w in results.warnings if w not in ranked.warnings])
    out += comparison_lines(comparison, reference)
    out += ["", "## Where these numbers come from", ""] + provenance_lines(everything)
    out += [
        "",
        "## Regenerate",
        "",
        f"`{REGENERATE}` (measures on this machine into a new results/runs/<time>-<sha>/, "
        f"then `python -m accelbench_analysis all <csv> --run-csv <its scaling csv> --out <that directory>`; see "
        f"README.md and analysis/README.md).",
        "",
    ]
    return "\n".join(out)


def write_report(
    results: Results,
    out_dir: Path,
    claims: ClaimsResult | None = None,
    figures: dict | None = None,
    comparison: list[ThreeWay] | None = None,
    reference: Results | None = None,
    ranked: Results | None = None,
    everything: Results | None = None,
) -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "tables").mkdir(exist_ok=True)
    (out_dir / RANKING_DOC).write_text(full_ranking_markdown(ranked if ranked is not None else results))
    path = out_dir / "REPORT.md"
    path.write_text(
        report_markdown(results, out_dir, claims, figures, comparison, reference, ranked, everything)
    )
    return path
