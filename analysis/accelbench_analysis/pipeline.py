"""The analysis commands over CSVs that the command line (cli.py) and the main job
(reproduce.py, which runs `scaling` and `all` over its run directory) share:
{check,tables,claims,figures,report,all} CSV... [--out DIR], plus `regress` (the CI
regression check), `grid` / `grid-halve` (parameter grid search), `scaling`, `cost-images`
and `robustness` (the extreme-case catalogue's verdicts)."""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

from .inputs.report_numbers import DEFAULT_REPORT_NUMBERS, load_report_numbers
from .inputs.schema import ContractError, Results, load_results

EXIT_BAD_INPUT = 2

COMMANDS = {
    "check": "validate the CSVs against the contract and print provenance and warnings",
    "tables": "write Tables 2, 4, 5 (Markdown + LaTeX) to OUT/tables/",
    "claims": "write the claims table to OUT/tables/claims.md",
    "figures": "write the PNG figures to OUT/figures/",
    "report": "write OUT/REPORT.md linking what exists, and OUT/index.html showing it",
    "all": "tables, claims, figures, the three-way comparison, REPORT.md and index.html",
}


def parser(more_commands=()) -> argparse.ArgumentParser:
    """The analysis commands' parser; each of `more_commands` adds its subcommand to it."""
    p = argparse.ArgumentParser(
        prog="python -m accelbench_analysis",
        description="Turn the accelbench harness's CSV into the report's tables, claims, "
        "figures and REPORT.md.",
    )
    sub = p.add_subparsers(dest="command", required=True)
    for name, help_text in COMMANDS.items():
        s = sub.add_parser(name, help=help_text, description=help_text)
        s.add_argument(
            "csv", nargs="+", type=Path, help="harness CSV(s); a NAME.reps.csv beside NAME.csv is read too"
        )
        s.add_argument(
            "--out", type=Path, default=Path("results"), help="output directory (default: results/)"
        )
        s.add_argument(
            "--report-numbers",
            type=Path,
            default=DEFAULT_REPORT_NUMBERS,
            help="the report's numbers (default: results/report/report-tables.csv)",
        )
        s.add_argument(
            "--reference-run",
            type=Path,
            metavar="DIR",
            help="a reference run (e.g. results/reference): its csv/ files of the "
            "same names as CSV are compared with these (claims, three-way table)",
        )
    add_regress(sub)
    add_grid(sub)
    add_scaling(sub)
    add_robustness(sub)
    add_html(sub)
    add_history(sub)
    for add in more_commands:
        add(sub)
    return p


def add_robustness(sub) -> None:
    s = sub.add_parser(
        "robustness",
        help="OUT/robustness.md: verdicts per catalogue case and accelerator, failures, stiff-parameter rows",
        description="Reads a configs/robustness.yaml run: a pass/FAIL table of "
        "case x accelerator setting, every failure with its counts "
        "and message, and the timed stiff-parameter rows with "
        "memory and errors.",
    )
    s.add_argument("--csv", nargs="+", type=Path, required=True, help="the robustness run's CSV(s)")
    s.add_argument("--out", type=Path, required=True, help="output directory")


def add_html(sub) -> None:
    s = sub.add_parser(
        "html",
        help="write RUN_DIR/index.html: the run's REPORT.md, tables and figures as one offline page",
        description="Renders a run directory (REPORT.md, the tables/*.md and figures/*.png it "
        "links, the interactive figures/*.vl.json) as one self-contained page, as `all` "
        "does at its end. Computes nothing: run it after changing the directory's outputs.",
    )
    s.add_argument(
        "run_dir", nargs="+", type=Path, help="run directories (results/runs/<run>, results/reference)"
    )


def run_html(args: argparse.Namespace) -> int:
    from .outputs.run_page import write_run_page

    for d in args.run_dir:
        print(write_run_page(d))
    return 0


def add_history(sub) -> None:
    s = sub.add_parser(
        "history",
        help="every run on this machine across commits: results/history/{history.csv,index.html}",
        description="Collects the harness CSVs of every run under RESULTS (runs/*, the "
        "regression check's, reference/, the grid searches) into OUT/history.csv, one row per "
        "commit x combination x measure, keeping what earlier calls collected "
        "(OUT/collected.csv), and draws OUT/index.html; also writes RESULTS/index.html, the "
        "list of runs.",
    )
    s.add_argument("--results", type=Path, default=Path("results"), help="default: results/")
    s.add_argument("--out", type=Path, help="default: RESULTS/history/")
    s.add_argument(
        "--repo", type=Path, default=Path("."), help="the git checkout that orders commits (default: .)"
    )


def run_history(args: argparse.Namespace) -> int:
    from .outputs.history import update
    from .outputs.history_page import write_history_page
    from .outputs.runs_page import write_runs_page

    out = args.out or args.results / "history"
    c = update(args.results, out, args.repo)
    for n in c.notes:
        print(f"note: {n}", file=sys.stderr)
    print(
        f"history: {len(c.rows)} rows from {c.rows['run'].nunique() if len(c.rows) else 0} runs, "
        f"{c.history['commit'].nunique() if len(c.history) else 0} commits, {len(c.history)} rows in "
        f"{out / 'history.csv'}"
    )
    print(write_history_page(c, out, args.results))
    print(write_runs_page(args.results))
    return 0


def run_robustness(args: argparse.Namespace) -> int:
    from .outputs.robustness import write_robustness

    results = load_results(args.csv)
    for w in results.warnings:
        print(f"warning: {w}", file=sys.stderr)
    print(write_robustness(results, args.out))
    return 0


def add_regress(sub) -> None:
    from .outputs.regress import DEFAULT_TIME_FACTOR, INSTRUCTIONS_TOLERANCE

    s = sub.add_parser(
        "regress",
        help="compare a CI run with the committed baseline (exit 0 pass, 1 "
        "regression, 2 bad input, 3 time needs a second measurement)",
        description="Three tiers: deterministic counts equal, instruction counts within "
        "+10%%, render time relative to Embree within a factor of the baseline's "
        "in two consecutive measurements. Exit codes: 0 pass, 1 regression, 2 bad "
        "input, 3 a time exceedance needs a second measurement (rerun with "
        "--history).",
    )
    s.add_argument("--baseline", type=Path, required=True, help="e.g. results/baseline/ci.csv")
    s.add_argument("--current", type=Path, required=True, help="the fresh run's CSV")
    s.add_argument(
        "--history",
        type=Path,
        help="the previous run's CSV (or a re-measurement): a time exceedance fails "
        "only if it exceeded there too",
    )
    s.add_argument(
        "--time-factor",
        type=float,
        default=DEFAULT_TIME_FACTOR,
        help=f"allowed growth of the ratio to Embree (default {DEFAULT_TIME_FACTOR})",
    )
    s.add_argument(
        "--instructions-tolerance",
        type=float,
        default=INSTRUCTIONS_TOLERANCE,
        help=f"allowed relative change of instruction counts (default {INSTRUCTIONS_TOLERANCE})",
    )
    s.add_argument("--report", type=Path, help="also write the Markdown report here")


def add_grid(sub) -> None:
    s = sub.add_parser(
        "grid",
        help="rank a grid search's rows: best.yaml, ranked.csv, heatmaps",
        description="Reads the grid config's objective and constraints, ranks "
        "the CSV's candidates per model and writes OUT/best.yaml, "
        "OUT/ranked.csv, OUT/heatmap-*.png and OUT/summary.md. With "
        "successive halving, give the second pass as CSV and the "
        "first with --cheap: only the second is ranked, the first "
        "fills the heatmaps and ranked.csv over the whole grid.",
    )
    s.add_argument(
        "csv",
        nargs="+",
        type=Path,
        help="the CSV(s) whose rows are ranked (several: shards of one pass; a "
        "candidate measured twice counts with its most repetitions)",
    )
    s.add_argument("--config", type=Path, required=True, help="configs/grid-NAME.yaml")
    s.add_argument(
        "--cheap",
        nargs="+",
        type=Path,
        metavar="CSV",
        help="the cheap first pass of successive halving: context for the heatmaps "
        "and ranked.csv (same constraints), never ranked; a candidate also in "
        "CSV shows CSV's values",
    )
    s.add_argument("--out", type=Path, help="output directory (default: results/grid/NAME/)")
    s.add_argument("--no-heatmaps", action="store_true", help="skip the PNGs")
    s.add_argument(
        "--accelbench",
        type=Path,
        help="the accelbench binary that expands the config's axes (default: $ACCELBENCH, else build/accelbench)",
    )
    h = sub.add_parser(
        "grid-halve",
        help="successive halving: write the second pass's config (top K per model)",
        description="From the first (cheap) pass's CSV, writes a config that runs "
        "only the top K candidates of each model, at the repetitions "
        "of grid.successive_halving.repetitions.",
    )
    h.add_argument("csv", nargs="+", type=Path, help="the first pass's CSV(s)")
    h.add_argument("--config", type=Path, required=True, help="configs/grid-NAME.yaml")
    h.add_argument(
        "--keep", type=int, help="candidates per model to keep (default: grid.successive_halving.keep)"
    )
    h.add_argument("--out", type=Path, required=True, help="the second pass's config (YAML)")
    h.add_argument(
        "--accelbench",
        type=Path,
        help="the accelbench binary that expands the config's axes (default: $ACCELBENCH, else build/accelbench)",
    )


def add_scaling(sub) -> None:
    s = sub.add_parser(
        "scaling",
        help="time vs triangles: OUT/figures/scaling.png and OUT/tables/scaling.md (fitted log-log slopes)",
        description="Reads a configs/scaling.yaml run and fits log(time) = a + "
        "slope * log(triangles) per structure and source model.",
    )
    s.add_argument("csv", nargs="+", type=Path, help="the scaling run's CSV(s)")
    s.add_argument("--out", type=Path, default=Path("results"), help="default: results/")
    c = sub.add_parser(
        "cost-images",
        help="one figure per model: shaded image + per-pixel cost heatmaps per structure",
        description="From `accelbench render --cost-out PREFIX` files: the "
        "shaded image and each structure's node visits and triangle "
        "tests per pixel on a shared scale, to "
        "OUT/figures/cost-MODEL.png.",
    )
    c.add_argument("--model", required=True, help="the model's name (title and file name)")
    c.add_argument("--shaded", type=Path, help="the shaded image (accelbench render --out)")
    c.add_argument(
        "--cost",
        action="append",
        required=True,
        metavar="LABEL=CSV",
        help="a structure's PREFIX-cost.csv; repeat, in display order",
    )
    c.add_argument("--out", type=Path, default=Path("results"), help="default: results/")


def run_scaling(args: argparse.Namespace) -> int:
    from .mapping.selection import report_rows
    from .outputs.scaling import write_scaling

    # The report's workload: camera rays on one thread, one image per model.
    results, notes = report_rows(load_results(args.csv), what="the scaling fit")
    for w in results.warnings:
        print(f"warning: {w}", file=sys.stderr)
    for note in notes:
        print(f"note: {note}", file=sys.stderr)
    for path in write_scaling(results, args.out):
        print(path)
    return 0


def run_cost_images(args: argparse.Namespace) -> int:
    from .outputs.scaling import cost_figure

    costs = {}
    for item in args.cost:
        label, sep, path = item.partition("=")
        if not sep or not label or not path:
            raise ContractError(f"--cost expects LABEL=CSV, got '{item}'")
        costs[label] = Path(path)
    safe = "".join(ch if ch.isalnum() or ch in "-_." else "-" for ch in args.model)
    print(cost_figure(args.model, args.shaded, costs, args.out / "figures" / f"cost-{safe}.png"))
    return 0


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


def load_reference_run(run_dir: Path | None, csvs: list[Path]) -> Results | None:
    """The reference run's CSVs named like the given ones (like compared with like: its
    table4.csv beside this run's table4.csv); None when it has none of them."""
    if run_dir is None:
        return None
    mine = [run_dir / "csv" / p.name for p in csvs]
    if any(m.resolve() == p.resolve() for m, p in zip(mine, csvs)):
        return None  # this is the reference run
    present = [m for m in mine if m.is_file()]
    return load_results(present) if present else None


def run(args: argparse.Namespace) -> list[Path]:
    # Imported here so that `check` and --help stay fast (matplotlib is slow to import).
    from .outputs.claims import write_claims
    from .outputs.comparison import three_way, write_comparison
    from .outputs.figures import write_figures
    from .outputs.report import write_report
    from .outputs.tables import write_tables

    results = load_results(args.csv)
    report_nums = load_report_numbers(args.report_numbers)
    reference = load_reference_run(args.reference_run, args.csv)
    for w in results.warnings:
        print(f"warning: {w}", file=sys.stderr)
    if args.command == "check":
        for g in results.groups:
            print(f"provenance {g.describe()}")
        print(
            f"{len(results.rows)} rows, {int((results.rows['status'] == 'ok').sum())} ok; "
            f"error columns {'present' if results.has_error_columns() else 'absent'}"
        )
        return []
    out: Path = args.out
    written: list[Path] = []
    claims = figures = comparison = None
    # Ray-set and thread-scaling rows have outputs of their own; the report's tables,
    # claims and figures see only the rows of the report's workload (report_rows), and say
    # what they left out.
    from .mapping.selection import report_rows
    from .outputs.claims import is_ablation, without_ablations
    from .outputs.workloads import without_thread_scaling, write_workloads

    if args.command == "all":
        written += write_workloads(results, out)
    results, left_out = without_thread_scaling(results)
    results, notes = report_rows(results, own_image=is_ablation(results.rows))
    for note in left_out + notes:
        print(f"note: {note}", file=sys.stderr)
    if reference is not None:  # compared like with like: the same workload
        reference, _ = without_thread_scaling(reference)
        reference, _ = report_rows(reference, own_image=is_ablation(reference.rows))
    # Ablation rows (configs/ablations.yaml) are judged by the claims only: the tables and
    # figures show the run at the report's settings.
    with_ablations, results = results, without_ablations(results)
    if args.command in ("tables", "all"):
        ablation_rows = with_ablations.rows[is_ablation(with_ablations.rows)]
        written += write_tables(results, report_nums, out / "tables", ablation_rows)
        if not results.case_rows().empty:
            from .outputs.robustness import write_robustness

            written.append(write_robustness(results, out / "tables"))
    if args.command in ("claims", "all", "report"):
        path, claims = write_claims(with_ablations, report_nums, out / "tables", reference)
        if args.command != "report":
            written.append(path)
    if args.command in ("all", "report"):
        comparison = three_way(results, reference, report_nums)
        written.append(write_comparison(comparison, results, reference, args.reference_run, out / "tables"))
    if args.command in ("figures", "all"):
        figures = write_figures(results, report_nums, out / "figures")
        for name, f in figures.items():
            if isinstance(f, Path):
                written.append(f)
            else:
                print(f"figure {name} skipped: {f.reason}", file=sys.stderr)
    if args.command in ("report", "all"):
        copy_report_numbers(args.report_numbers, out)
        written.append(write_report(results, out, claims, figures, comparison, reference, args.reference_run))
        from .outputs.run_page import write_run_page

        written.append(write_run_page(out))
    return written


def run_regress(args: argparse.Namespace) -> int:
    from .outputs.regress import compare, to_markdown

    cmp = compare(args.baseline, args.current, args.history, args.time_factor, args.instructions_tolerance)
    text = to_markdown(cmp)
    print(text, end="")
    if args.report:
        args.report.parent.mkdir(parents=True, exist_ok=True)
        args.report.write_text(text)
    return cmp.exit_code


def run_grid(args: argparse.Namespace) -> int:
    from .grid.grid import analyse, write_outputs
    from .grid.grid_config import load_grid_config

    cfg = load_grid_config(args.config, args.accelbench)
    results = load_results(args.csv)
    cheap = load_results(args.cheap) if args.cheap else None
    for w in results.warnings + (cheap.warnings if cheap else []):
        print(f"warning: {w}", file=sys.stderr)
    a = analyse(results, cfg, cheap)
    out = args.out or Path("results") / "grid" / cfg.name
    written = write_outputs(a, out, heatmaps=not args.no_heatmaps)
    print((out / "summary.md").read_text(), end="")
    for path in written:
        print(path)
    # 1: no model has a candidate that satisfies the constraints (nothing to recommend).
    return 0 if any(a.best(m) is not None for m in a.models()) else 1


def run_grid_halve(args: argparse.Namespace) -> int:
    from .grid.grid import analyse, dump_yaml, halve
    from .grid.grid_config import GridConfigError, load_grid_config

    cfg = load_grid_config(args.config, args.accelbench)
    keep = args.keep if args.keep is not None else cfg.keep
    if keep is None:
        raise GridConfigError("give --keep or grid.successive_halving.keep in the config")
    results = load_results(args.csv)
    a = analyse(results, cfg)
    doc, text = halve(a, keep, [str(p) for p in args.csv])
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(
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
    print(args.out)
    return 0


def main(argv: list[str] | None = None) -> int:
    return dispatch(parser().parse_args(argv))


def dispatch(args: argparse.Namespace, more_handlers=None) -> int:
    """Runs the parsed command; `more_handlers` maps further command names to functions."""
    from .grid.grid_config import GridConfigError

    handlers = {
        "regress": run_regress,
        "grid": run_grid,
        "grid-halve": run_grid_halve,
        "scaling": run_scaling,
        "cost-images": run_cost_images,
        "robustness": run_robustness,
        "html": run_html,
        "history": run_history,
        **(more_handlers or {}),
    }
    try:
        if args.command in handlers:
            return handlers[args.command](args)
        for path in run(args):
            print(path)
    except (ContractError, GridConfigError, ValueError, FileNotFoundError) as e:
        print(f"error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    return 0
