"""Command line: python -m accelbench_analysis {check,tables,claims,figures,report,all} CSV...
[--out DIR], plus `regress` (the CI regression check), `grid` / `grid-halve` (parameter
grid search), `scaling`, `cost-images`, `robustness` (the extreme-case catalogue's verdicts)
and `reproduce` (the main job: measure into a run directory, then `all` over it).

The analysis commands live in pipeline.py, which reproduce.py uses too; this file adds
`reproduce` on top, so that neither of the two imports the other's command line."""

from __future__ import annotations

import argparse

from .pipeline import dispatch
from .pipeline import parser as pipeline_parser
from .reproduce import add_reproduce, run_reproduce


def parser() -> argparse.ArgumentParser:
    return pipeline_parser(more_commands=[add_reproduce])


def main(argv: list[str] | None = None) -> int:
    return dispatch(parser().parse_args(argv), {"reproduce": run_reproduce})
