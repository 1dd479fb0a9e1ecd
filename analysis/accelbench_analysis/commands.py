"""The analysis's commands as typed functions, one per subcommand: cli.py parses the command
line into these calls, and the main job (reproduce/) calls them directly. Each returns what
it wrote (the command line prints it) or an exit code; bad input raises one of BAD_INPUT.

{check,tables,claims,figures,report,all} read harness CSVs (`Sources`); the others are
`regress` (the CI regression check), `grid` / `grid-halve` (parameter grid search),
`scaling`, `cost-images`, `robustness` (the extreme-case catalogue's verdicts), `html`,
`compare` (two runs side by side) and `history`."""

from __future__ import annotations

import shutil
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from .grid.grid_config import GridConfigError
from .inputs.load import FileRead, load_results
from .inputs.report_numbers import DEFAULT_REPORT_NUMBERS, load_report_numbers
from .inputs.schema import ContractError, Results
from .mapping.structures import StructureTableError

EXIT_BAD_INPUT = 2
# What a command raises on input it cannot use: the command line prints it and exits 2.
BAD_INPUT = (ContractError, GridConfigError, StructureTableError, ValueError, FileNotFoundError)


@dataclass(frozen=True)
class Sources:
    """What the CSV commands read: the harness CSVs (a NAME.reps.csv beside NAME.csv is
    read too), the report's numbers and, optionally, a reference run compared with.
    `run_csvs`: other CSVs of the same run that another command analyses (the scaling
    config's), read only for what concerns the whole run: the widest gap the claims'
    spread is floored at, and the provenance the report states."""

    csvs: list[Path]
    report_numbers: Path = DEFAULT_REPORT_NUMBERS
    reference_run: Path | None = None
    run_csvs: list[Path] = field(default_factory=list)


def warn(results: Results) -> None:
    for w in results.warnings:
        print(f"warning: {w}", file=sys.stderr)


# ---- the CSV commands: check, tables, claims, figures, report, all ---------------------------


def check(src: Sources) -> int:
    """Validates the CSVs against the contract; prints provenance and warnings."""
    results = load_results(src.csvs)
    load_report_numbers(src.report_numbers)
    warn(results)
    for g in results.groups:
        print(f"provenance {g.describe()}")
    print(
        f"{len(results.rows)} rows, {int((results.rows['status'] == 'ok').sum())} ok; "
        f"error columns {'present' if results.has_error_columns() else 'absent'}"
    )
    return 0


@dataclass
class Loaded:
    """The CSVs of one analysis, read once. Ray-set and thread-scaling rows have outputs of
    their own (`everything`); the report's tables, claims and figures see only the rows of
    the report's workload (`results`; `with_ablations` adds configs/ablations.yaml's rows,
    which the claims judge), and say what they left out."""

    src: Sources
    everything: Results
    results: Results
    with_ablations: Results
    reference: Results | None
    reference_run: Results | None  # every row of the reference run named like ours: its floor
    report_nums: pd.DataFrame
    ranked: Results  # every measured row but the thread scaling's: the ranking REPORT.md opens with
    whole_run: Results  # `everything` and Sources.run_csvs: the spread's floor, the provenance
    written: list[Path] = field(default_factory=list)

    @property
    def of_the_report(self) -> bool:
        """Whether the run measured the report's models: only then are its tables, claims and
        three-way comparison written."""
        from .outputs.report.report import report_models_measured

        return report_models_measured(self.results)


def load(src: Sources) -> Loaded:
    from .mapping.selection import report_rows
    from .outputs.figures.workloads import without_thread_scaling
    from .outputs.report.claims import is_ablation, without_ablations

    files: dict[Path, FileRead] = {}  # each CSV read once, though several of the sets below share it
    everything = load_results(src.csvs, files)
    report_nums = load_report_numbers(src.report_numbers)
    reference = load_reference_run(src.reference_run, src.csvs, files)
    # The reference's verdicts are judged against the widest gap of its whole run, as ours are.
    reference_run = (
        load_reference_run(src.reference_run, [*src.csvs, *src.run_csvs], files)
        if src.run_csvs
        else reference
    )
    warn(everything)
    ranked, left_out = without_thread_scaling(everything)
    results, notes = report_rows(ranked, own_image=is_ablation(ranked.rows))
    for note in left_out + notes:
        print(f"note: {note}", file=sys.stderr)
    if reference is not None:  # compared like with like: the same workload
        reference, _ = without_thread_scaling(reference)
        reference, _ = report_rows(reference, own_image=is_ablation(reference.rows))
    # Ablation rows are judged by the claims only: the tables and figures show the run at
    # the report's settings.
    # A run of thread scaling only is ranked at its thread counts (one column each).
    ranked = ranked if not ranked.measured_rows().empty else everything
    whole_run = load_results([*src.csvs, *src.run_csvs], files) if src.run_csvs else everything
    return Loaded(
        src,
        everything,
        without_ablations(results),
        results,
        reference,
        reference_run,
        report_nums,
        ranked,
        whole_run,
    )


def load_reference_run(
    run_dir: Path | None, csvs: list[Path], files: dict[Path, FileRead] | None = None
) -> Results | None:
    """The reference run's CSVs named like the given ones (like compared with like: its
    table4.csv beside this run's table4.csv); None when it has none of them. `files`: as
    load_results's cache."""
    if run_dir is None:
        return None
    mine = [run_dir / "csv" / p.name for p in csvs]
    if any(m.resolve() == p.resolve() for m, p in zip(mine, csvs)):
        return None  # this is the reference run
    present = [m for m in mine if m.is_file()]
    return load_results(present, files) if present else None


def copy_report_numbers(report_numbers: Path, out: Path) -> None:
    """Keep OUT/report/ (the report's numbers and their README) beside the outputs that cite it."""
    target = out / "report"
    src_dir = report_numbers.parent
    if target.resolve() == src_dir.resolve():
        return
    target.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(report_numbers, target / "report-tables.csv")
    if (src_dir / "README.md").is_file():
        shutil.copyfile(src_dir / "README.md", target / "README.md")


def write_tables_of(data: Loaded, out: Path) -> list[Path]:
    from .outputs.report.claims import is_ablation
    from .outputs.report.tables import write_tables

    ablation_rows = data.with_ablations.rows[is_ablation(data.with_ablations.rows)]
    written = write_tables(data.results, data.report_nums, out / "tables", ablation_rows)
    if not data.results.case_rows().empty:
        from .outputs.report.robustness import write_robustness

        written.append(write_robustness(data.results, out / "tables"))
    return written


def write_claims_of(data: Loaded, out: Path):
    from .outputs.report.claims_output import write_claims

    # The spread's floor is the widest gap anywhere in the run: ray sets, thread scaling and
    # the run's other CSVs (Sources.run_csvs: the scaling config's) too, though the claims
    # judge none of them.
    return write_claims(
        data.with_ablations,
        data.report_nums,
        out / "tables",
        data.reference,
        data.whole_run,
        data.reference_run,
    )


def write_comparison_of(data: Loaded, out: Path):
    from .outputs.report.comparison import three_way, write_comparison

    comparison = three_way(data.results, data.reference, data.report_nums)
    path = write_comparison(comparison, data.results, data.reference, data.src.reference_run, out / "tables")
    return path, comparison


def write_figures_of(data: Loaded, out: Path):
    from .outputs.figures.figures import write_figures

    figures = write_figures(data.results, data.report_nums, out / "figures")
    written = []
    for name, f in figures.items():
        if isinstance(f, Path):
            written.append(f)
        else:
            print(f"figure {name} skipped: {f.reason}", file=sys.stderr)
    return written, figures


def write_report_of(data: Loaded, out: Path, claims, figures, comparison) -> list[Path]:
    from .outputs.pages.run_page import write_run_page
    from .outputs.report.report import write_report

    if data.of_the_report:
        copy_report_numbers(data.src.report_numbers, out)
    report = write_report(
        data.results, out, claims, figures, comparison, data.reference, data.ranked, data.whole_run
    )
    return [report, write_run_page(out)]


def tables(src: Sources, out: Path) -> list[Path]:
    """Tables 2, 4, 5 (Markdown + LaTeX) to OUT/tables/."""
    return write_tables_of(load(src), out)


def claims(src: Sources, out: Path) -> list[Path]:
    """The claims table to OUT/tables/claims.md."""
    path, _ = write_claims_of(load(src), out)
    return [path]


def figures(src: Sources, out: Path) -> list[Path]:
    """The figures to OUT/figures/."""
    written, _ = write_figures_of(load(src), out)
    return written


def report(src: Sources, out: Path) -> list[Path]:
    """OUT/REPORT.md linking what exists, and OUT/index.html showing it."""
    data = load(src)
    if not data.of_the_report:
        return write_report_of(data, out, None, None, None)
    _, claim_rows = write_claims_of(data, out)
    path, comparison = write_comparison_of(data, out)
    return [path] + write_report_of(data, out, claim_rows, None, comparison)


def analyse_all(src: Sources, out: Path) -> list[Path]:
    """Tables, claims, figures, the three-way comparison, REPORT.md and index.html, plus the
    ray-set and thread-scaling outputs and, when plugins were measured, the peers'."""
    from .outputs.figures.workloads import write_workloads
    from .outputs.report.peers import write_peers

    data = load(src)
    written = write_workloads(data.everything, out) + write_peers(data.everything, out)
    claim_rows = comparison = None
    if data.of_the_report:  # the report's tables, claims and comparison have rows to show
        written += write_tables_of(data, out)
        path, claim_rows = write_claims_of(data, out)
        written.append(path)
        path, comparison = write_comparison_of(data, out)
        written.append(path)
    elif not data.results.case_rows().empty:
        from .outputs.report.robustness import write_robustness

        written.append(write_robustness(data.results, out / "tables"))
    figure_paths, figure_results = write_figures_of(data, out)
    written += figure_paths
    return written + write_report_of(data, out, claim_rows, figure_results, comparison)


# ---- the other commands ------------------------------------------------------------------------


def html(run_dirs: list[Path]) -> list[Path]:
    """RUN_DIR/index.html for each run directory (computes nothing)."""
    from .outputs.pages.run_page import write_run_page

    return [write_run_page(d) for d in run_dirs]


def compare(a: Path, b: Path, out: Path | None = None, fail_above: float | None = None) -> int:
    """Run B against run A (run directories or results CSVs): prints the Markdown, writes
    OUT/compare.md and OUT/compare.html when OUT is given. Exit 1 when --fail-above is given
    and a trace time changed by more than that ratio (B/A), else 0."""
    from .outputs.ci.compare import compare_markdown, compare_runs, load_run, worst_ratio
    from .outputs.pages.markdown_html import to_html
    from .outputs.pages.page import page, write_page

    result = compare_runs(load_run(a), load_run(b), str(a), str(b))
    text = compare_markdown(result)
    print(text, end="")
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        (out / "compare.md").write_text(text)
        write_page(out / "compare.html", page(f"accelbench: {b} against {a}", to_html(text)))
        print(f"wrote {out / 'compare.md'} and {out / 'compare.html'}", file=sys.stderr)
    if fail_above is not None and worst_ratio(result) > fail_above:
        print(
            f"compare: a trace time changed by {worst_ratio(result):.3f}x, above {fail_above:g}",
            file=sys.stderr,
        )
        return 1
    return 0


def history(results: Path = Path("results"), out: Path | None = None, repo: Path = Path(".")) -> int:
    """Every run under RESULTS across commits into OUT (default RESULTS/history/)."""
    from .outputs.ci.history import update
    from .outputs.pages.history_page import write_history_page
    from .outputs.pages.runs_page import write_runs_page

    out = out or results / "history"
    c = update(results, out, repo)
    for n in c.notes:
        print(f"note: {n}", file=sys.stderr)
    print(
        f"history: {len(c.rows)} rows from {c.rows['run'].nunique() if len(c.rows) else 0} runs, "
        f"{c.history['commit'].nunique() if len(c.history) else 0} commits, {len(c.history)} rows in "
        f"{out / 'history.csv'}"
    )
    print(write_history_page(c, out, results))
    print(write_runs_page(results))
    return 0


def robustness(csvs: list[Path], out: Path) -> list[Path]:
    """OUT/robustness.md from a configs/robustness.yaml run."""
    from .outputs.report.robustness import write_robustness

    results = load_results(csvs)
    warn(results)
    return [write_robustness(results, out)]


def scaling(csvs: list[Path], out: Path) -> list[Path]:
    """Time vs triangles: OUT/figures/scaling.png and OUT/tables/scaling.md."""
    from .mapping.selection import report_rows
    from .outputs.figures.scaling import write_scaling

    # The report's workload: camera rays on one thread, one image per model.
    results, notes = report_rows(load_results(csvs), what="the scaling fit")
    warn(results)
    for note in notes:
        print(f"note: {note}", file=sys.stderr)
    return write_scaling(results, out)


def cost_images(model: str, costs: dict[str, Path], out: Path, shaded: Path | None = None) -> list[Path]:
    """OUT/figures/cost-MODEL.png: the shaded image and each structure's per-pixel cost
    (`costs`: label -> `accelbench render --cost-out` CSV, in display order)."""
    from .outputs.figures.scaling import cost_figure

    safe = "".join(ch if ch.isalnum() or ch in "-_." else "-" for ch in model)
    return [cost_figure(model, shaded, costs, out / "figures" / f"cost-{safe}.png")]


def regress(
    baseline: Path,
    current: Path,
    history: Path | None = None,
    time_factor: float | None = None,
    instructions_tolerance: float | None = None,
    report: Path | None = None,
) -> int:
    """A CI run against the committed baseline; the exit code of the three tiers."""
    from .outputs.ci.regress import DEFAULT_TIME_FACTOR, INSTRUCTIONS_TOLERANCE, compare, to_markdown

    cmp = compare(
        baseline,
        current,
        history,
        DEFAULT_TIME_FACTOR if time_factor is None else time_factor,
        INSTRUCTIONS_TOLERANCE if instructions_tolerance is None else instructions_tolerance,
    )
    text = to_markdown(cmp)
    print(text, end="")
    if report:
        report.parent.mkdir(parents=True, exist_ok=True)
        report.write_text(text)
    return cmp.exit_code


def grid(
    csvs: list[Path],
    config: Path,
    cheap: list[Path] | None = None,
    out: Path | None = None,
    heatmaps: bool = True,
    accelbench: Path | None = None,
) -> int:
    """Ranks a grid search's rows: OUT/best.yaml, ranked.csv, heatmaps, summary.md."""
    from .grid.grid import analyse, write_outputs
    from .grid.grid_config import load_grid_config

    cfg = load_grid_config(config, accelbench)
    results = load_results(csvs)
    cheap_results = load_results(cheap) if cheap else None
    for w in results.warnings + (cheap_results.warnings if cheap_results else []):
        print(f"warning: {w}", file=sys.stderr)
    a = analyse(results, cfg, cheap_results)
    out = out or Path("results") / "grid" / cfg.name
    written = write_outputs(a, out, heatmaps=heatmaps)
    print((out / "summary.md").read_text(), end="")
    for path in written:
        print(path)
    # 1: no model has a candidate that satisfies the constraints (nothing to recommend).
    return 0 if any(a.best(m) is not None for m in a.models()) else 1


def grid_halve(
    csvs: list[Path], config: Path, out: Path, keep: int | None = None, accelbench: Path | None = None
) -> int:
    """Successive halving: OUT, the second pass's config (the top KEEP per model)."""
    from .grid.grid import analyse, dump_yaml, halve
    from .grid.grid_config import load_grid_config

    cfg = load_grid_config(config, accelbench)
    keep = keep if keep is not None else cfg.keep
    if keep is None:
        raise GridConfigError("give --keep or grid.successive_halving.keep in the config")
    a = analyse(load_results(csvs), cfg)
    doc, text = halve(a, keep, [str(p) for p in csvs])
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(
        dump_yaml(
            doc,
            [
                f"Second pass of successive halving for {cfg.path} (python -m accelbench_analysis "
                f"grid-halve): {text}."
            ],
        )
    )
    for n in a.notes:
        print(f"note: {n}", file=sys.stderr)
    print(text)
    print(out)
    return 0
