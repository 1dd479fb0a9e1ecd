"""Command line: python -m accelbench_analysis {check,tables,claims,figures,report,all} CSV... [--out DIR]"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

from .reference import DEFAULT_REFERENCE, load_reference
from .schema import ContractError, load_results

COMMANDS = {
    "check": "validate the CSVs against the contract and print provenance and warnings",
    "tables": "write Tables 2, 4, 5 (Markdown + LaTeX) to OUT/tables/",
    "claims": "write the claims table to OUT/tables/claims.md",
    "figures": "write the PNG figures to OUT/figures/",
    "report": "write OUT/REPORT.md linking what exists",
    "all": "tables, claims, figures and REPORT.md",
}


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m accelbench_analysis",
        description="Turn the accelbench harness's CSV into the report's tables, claims, "
                    "figures and REPORT.md.")
    sub = p.add_subparsers(dest="command", required=True)
    for name, help_text in COMMANDS.items():
        s = sub.add_parser(name, help=help_text, description=help_text)
        s.add_argument("csv", nargs="+", type=Path,
                       help="harness CSV(s); a NAME.reps.csv beside NAME.csv is read too")
        s.add_argument("--out", type=Path, default=Path("results"),
                       help="output directory (default: results/)")
        s.add_argument("--reference", type=Path, default=DEFAULT_REFERENCE,
                       help="the report's numbers (default: results/report/report-tables.csv)")
    return p


def copy_reference(reference: Path, out: Path) -> None:
    """Keep OUT/report/ (the report's numbers and their README) beside the outputs that cite it."""
    target = out / "report"
    src_dir = reference.parent
    if target.resolve() == src_dir.resolve():
        return
    target.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(reference, target / "report-tables.csv")
    if (src_dir / "README.md").is_file():
        shutil.copyfile(src_dir / "README.md", target / "README.md")


def run(args: argparse.Namespace) -> list[Path]:
    # Imported here so that `check` and --help stay fast (matplotlib is slow to import).
    from .claims import write_claims
    from .figures import write_figures
    from .report import write_report
    from .tables import write_tables

    results = load_results(args.csv)
    ref = load_reference(args.reference)
    for w in results.warnings:
        print(f"warning: {w}", file=sys.stderr)
    if args.command == "check":
        for g in results.groups:
            print(f"provenance {g.describe()}")
        print(f"{len(results.rows)} rows, {int((results.rows['status'] == 'ok').sum())} ok; "
              f"error columns {'present' if results.has_error_columns() else 'absent'}")
        return []
    out: Path = args.out
    written: list[Path] = []
    claims = figures = None
    if args.command in ("tables", "all"):
        written += write_tables(results, ref, out / "tables")
    if args.command in ("claims", "all", "report"):
        path, claims = write_claims(results, ref, out / "tables")
        if args.command != "report":
            written.append(path)
    if args.command in ("figures", "all"):
        figures = write_figures(results, ref, out / "figures")
        for name, f in figures.items():
            if isinstance(f, Path):
                written.append(f)
            else:
                print(f"figure {name} skipped: {f.reason}", file=sys.stderr)
    if args.command in ("report", "all"):
        copy_reference(args.reference, out)
        written.append(write_report(results, out, claims, figures))
    return written


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    try:
        for path in run(args):
            print(path)
    except ContractError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0
