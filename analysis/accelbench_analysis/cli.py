"""The command line: python -m accelbench_analysis {check,tables,claims,figures,report,all}
CSV... [--out DIR], plus `regress` (the CI regression check), `grid` / `grid-halve`
(parameter grid search), `scaling`, `cost-images`, `robustness` (the extreme-case
catalogue's verdicts), `html`, `history`, `compare` and `reproduce` (the main job: measure into a run
directory, then `all` over it).

The one parser of the package: each subcommand's arguments become one typed call of
commands.py (or reproduce/job.py), by one small handler per subcommand (HANDLERS)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from . import commands
from .commands import BAD_INPUT, EXIT_BAD_INPUT, Sources
from .inputs.report_numbers import DEFAULT_REPORT_NUMBERS
from .inputs.schema import ContractError
from .reproduce.job import Job, reproduce
from .reproduce.runs import ReproduceError

COMMANDS = {
    "check": "validate the CSVs against the contract and print provenance and warnings",
    "tables": "write Tables 2, 4, 5 (Markdown + LaTeX) to OUT/tables/",
    "claims": "write the claims table to OUT/tables/claims.md",
    "figures": "write the PNG figures to OUT/figures/",
    "report": "write OUT/REPORT.md linking what exists, and OUT/index.html showing it",
    "all": "tables, claims, figures, the three-way comparison, REPORT.md and index.html",
}


def parser() -> argparse.ArgumentParser:
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
        s.add_argument(
            "--run-csv",
            type=Path,
            action="append",
            default=[],
            metavar="CSV",
            help="another CSV of the same run analysed elsewhere (e.g. the scaling config's), "
            "repeatable: read only for what concerns the whole run (the claims' spread floor, "
            "the provenance)",
        )
    add_regress(sub)
    add_grid(sub)
    add_scaling(sub)
    add_robustness(sub)
    add_html(sub)
    add_history(sub)
    add_compare(sub)
    add_reproduce(sub)
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


def add_compare(sub) -> None:
    from .outputs.ci.compare import ALPHA, MIN_CHANGE

    s = sub.add_parser(
        "compare",
        help="run B against run A: medians, B/A with an interval, a Mann-Whitney U test per combination",
        description="Per combination measured in both (same machine and ISA; others are never "
        "compared): both medians of trace and build time, B/A with an interval, the U test's "
        f"p over the .reps.csv repetitions; a time is changed when p < {ALPHA:g} and B/A "
        f"lies beyond {MIN_CHANGE:.0%}. Counts that differ are listed apart.",
    )
    s.add_argument("a", type=Path, help="run A: a run directory or a results CSV")
    s.add_argument("b", type=Path, help="run B: a run directory or a results CSV")
    s.add_argument("--out", type=Path, help="write OUT/compare.md and OUT/compare.html")
    s.add_argument(
        "--fail-above",
        type=float,
        metavar="RATIO",
        help="exit 1 when a trace time changed with B/A above RATIO (for CI)",
    )


def add_regress(sub) -> None:
    from .outputs.ci.regress import DEFAULT_TIME_FACTOR, INSTRUCTIONS_TOLERANCE

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


def add_reproduce(sub) -> None:
    s = sub.add_parser(
        "reproduce",
        help="the main job: measure configs into a run directory of their own, then analyse it",
        description="Measures every CONFIG with the harness into RUNS/<UTC time>-<sha>[-TAG]/"
        "csv/ and analyses them there (tables/, figures/, REPORT.md); LATEST then "
        "points at it. Continues the newest run of the same configs only when it "
        "is unfinished, `accelbench provenance` matches what it recorded and so do the "
        "contents of its configs, model and ray files (sha256).",
    )
    s.add_argument("configs", nargs="+", type=Path, help="configs/NAME.yaml, in order")
    s.add_argument("--accelbench", type=Path, default=Path("build/accelbench"))
    s.add_argument("--scaling", type=Path, help="the config among them analysed by `scaling`")
    s.add_argument(
        "--tag", default="", help="suffix of the run directory and part of the job's identity (e.g. quick)"
    )
    s.add_argument("--runs", type=Path, default=Path("results/runs"))
    s.add_argument("--latest", type=Path, default=Path("results/latest"))
    s.add_argument(
        "--into",
        type=Path,
        help="measure from scratch into this directory instead (the committed reference run): a new or "
        "empty one, or one an earlier run wrote (its run.json lists the files it wrote, the only ones "
        "removed)",
    )
    s.add_argument(
        "--reference-run",
        type=Path,
        default=Path("results/reference"),
        help="the committed reference run compared with (default results/reference)",
    )
    s.add_argument("--report-numbers", type=Path)
    s.add_argument(
        "--cost-images",
        help="command (split at spaces) writing OUT/figures/cost-*.png; the run directory is appended",
    )
    s.add_argument("--fresh", action="store_true", help="never continue an unfinished run")
    s.add_argument(
        "--require-clean-tree",
        action="store_true",
        help="refuse when tracked files have uncommitted changes (the reference run)",
    )


# ---- one handler per subcommand: the parsed arguments as one typed call ----------------------


def printed(paths: list[Path]) -> int:
    for path in paths:
        print(path)
    return 0


def sources(args: argparse.Namespace) -> Sources:
    return Sources(args.csv, args.report_numbers, args.reference_run, args.run_csv)


def cost_args(items: list[str]) -> dict[str, Path]:
    """--cost LABEL=CSV, repeated, in display order."""
    costs = {}
    for item in items:
        label, sep, path = item.partition("=")
        if not sep or not label or not path:
            raise ContractError(f"--cost expects LABEL=CSV, got '{item}'")
        costs[label] = Path(path)
    return costs


HANDLERS = {
    "check": lambda a: commands.check(sources(a)),
    "tables": lambda a: printed(commands.tables(sources(a), a.out)),
    "claims": lambda a: printed(commands.claims(sources(a), a.out)),
    "figures": lambda a: printed(commands.figures(sources(a), a.out)),
    "report": lambda a: printed(commands.report(sources(a), a.out)),
    "all": lambda a: printed(commands.analyse_all(sources(a), a.out)),
    "regress": lambda a: commands.regress(
        a.baseline, a.current, a.history, a.time_factor, a.instructions_tolerance, a.report
    ),
    "grid": lambda a: commands.grid(a.csv, a.config, a.cheap, a.out, not a.no_heatmaps, a.accelbench),
    "grid-halve": lambda a: commands.grid_halve(a.csv, a.config, a.out, a.keep, a.accelbench),
    "scaling": lambda a: printed(commands.scaling(a.csv, a.out)),
    "cost-images": lambda a: printed(commands.cost_images(a.model, cost_args(a.cost), a.out, a.shaded)),
    "robustness": lambda a: printed(commands.robustness(a.csv, a.out)),
    "html": lambda a: printed(commands.html(a.run_dir)),
    "history": lambda a: commands.history(a.results, a.out, a.repo),
    "compare": lambda a: commands.compare(a.a, a.b, a.out, a.fail_above),
    "reproduce": lambda a: run_reproduce(a),
}


def run_reproduce(args: argparse.Namespace) -> int:
    job = Job(
        accelbench=args.accelbench,
        configs=list(args.configs),
        scaling=args.scaling,
        tag=args.tag,
        runs=args.runs,
        latest=args.latest,
        into=args.into,
        reference_run=args.reference_run,
        report_numbers=args.report_numbers,
        cost_images=args.cost_images.split() if args.cost_images else None,
        fresh=args.fresh,
        require_clean_tree=args.require_clean_tree,
    )
    try:
        rc, _ = reproduce(job)
    except ReproduceError as e:
        print(f"reproduce: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        # The harness got the same signal; what it finished is in the CSVs.
        print(
            "\nreproduce: interrupted; run the job again with the same build to continue it", file=sys.stderr
        )
        return 130
    return rc


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    try:
        return HANDLERS[args.command](args)
    except BAD_INPUT as e:
        print(f"error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
