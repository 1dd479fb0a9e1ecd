"""Every column name once, in the harness's table, in schema.py, in the docs and in every
committed CSV: pandas.read_csv renames a repeated name `name.1` and csv.DictReader keeps
only the last of them, so a repeat is read wrongly by everyone but our own loader."""

from __future__ import annotations

import csv
import re
import subprocess
from pathlib import Path

import pandas as pd
import pytest

from accelbench_analysis.inputs.schema import (
    BUILD_IDENTITY,
    MIXING_COLUMNS,
    PROVENANCE_IDENTITY,
    REQUIRED_COLUMNS,
    RESULT_CSV_COLUMNS,
    read_csv,
)

REPO = Path(__file__).resolve().parents[2]
ACCELBENCH = REPO / "build" / "accelbench"


def committed_csvs() -> list[Path]:
    """The CSVs git tracks under results/ (not the runs this machine made, which .gitignore
    keeps out and older builds may have written); every CSV there outside a git checkout."""
    try:
        out = subprocess.run(
            ["git", "-C", str(REPO), "ls-files", "-z", "--", "results"],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
    except (OSError, subprocess.CalledProcessError):
        return sorted(p for p in (REPO / "results").rglob("*.csv") if p.is_file() and "runs" not in p.parts)
    return sorted(REPO / f for f in out.split("\0") if f.endswith(".csv"))


COMMITTED_CSVS = committed_csvs()
needs_binary = pytest.mark.skipif(not ACCELBENCH.is_file(), reason=f"{ACCELBENCH} not built")


def harness_columns() -> list[tuple[str, str, str, str]]:
    """`accelbench columns`: (name, kind, unit, text) per column, in file order."""
    out = subprocess.run([str(ACCELBENCH), "columns"], check=True, capture_output=True, text=True).stdout
    lines = out.splitlines()
    assert lines[0] == "name\tkind\tunit\ttext"
    return [tuple(line.split("\t")) for line in lines[1:]]


def is_results_file(header: list[str]) -> bool:
    """A harness results file (not a .reps.csv, a derived table or a grid ranking)."""
    return header[:2] == ["config", "combo_id"] and "status" in header


def documented_columns() -> list[str]:
    """The results CSV's columns as the analysis documents them (schema.py), plus the
    harness's own table when it is built: a column either lists is one every file needs."""
    names = [name for name, _ in RESULT_CSV_COLUMNS]
    if ACCELBENCH.is_file():
        names += [c[0] for c in harness_columns() if c[1] != "parameter" and c[0] not in names]
    return names


def test_there_are_committed_csvs_to_check():
    assert sum(1 for p in COMMITTED_CSVS if is_results_file(next(csv.reader(p.open(newline=""))))) >= 8


@pytest.mark.parametrize("path", COMMITTED_CSVS, ids=lambda p: str(p.relative_to(REPO)))
def test_every_committed_csv_reads_by_name_with_pandas_and_dictreader(path):
    with path.open(newline="") as fh:
        header = next(csv.reader(fh))
    repeated = sorted({h for h in header if header.count(h) > 1})
    assert not repeated, f"{path}: column names more than once: {repeated}"
    df = pd.read_csv(path, dtype=str, keep_default_na=False)
    assert list(df.columns) == header  # no `name.1` renames
    assert not [c for c in df.columns if re.search(r"\.\d+$", c)]
    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        rows = list(reader)
        assert reader.fieldnames == header
    assert len(rows) == len(df)
    assert all(len(r) == len(header) and None not in r for r in rows)  # no field lost or extra
    if is_results_file(header):
        missing = [c for c in documented_columns() if c not in header]
        assert not missing, f"{path}: documented columns missing: {missing}"
        # The analysis's loader reads it; DictReader and pandas agree on every cell.
        loaded = read_csv(path)
        assert len(loaded) == len(rows)
        for i in (0, len(rows) - 1):
            assert [rows[i][c] for c in header] == list(df.iloc[i])


@needs_binary
def test_schema_section_is_the_harness_column_table():
    table = harness_columns()
    names = [c[0] for c in table]
    assert len(names) == len(set(names)), "the harness's table repeats a name"
    assert [(c[0], c[1]) for c in table if c[1] != "parameter"] == RESULT_CSV_COLUMNS
    # The parameters sit between `params` and `status`, as the loader assumes.
    kinds = [c[1] for c in table]
    lo, hi = names.index("params"), names.index("status")
    assert set(kinds[lo + 1 : hi]) == {"parameter"} and "parameter" not in kinds[:lo] + kinds[hi:]
    assert set(REQUIRED_COLUMNS) <= set(names)
    assert all(c[3] for c in table), "a column without its text"


@needs_binary
def test_docs_results_table_lists_the_harness_columns_in_order():
    text = (REPO / "docs" / "configs.md").read_text()
    section = text[text.index("## The results CSV") :]
    section = section[: section.index("\n## ", 1)] if "\n## " in section[1:] else section
    documented = []
    for line in section.splitlines():
        if line.startswith("| `"):
            documented += re.findall(r"`([a-z0-9_]+)`", line.split("|")[1])
    assert documented == [c[0] for c in harness_columns() if c[1] != "parameter"]


@needs_binary
def test_analysis_readme_names_only_harness_columns():
    text = (REPO / "analysis" / "README.md").read_text()
    contract = text[text.index("## The CSV contract") :]
    contract = contract[: contract.index("\n## ", 1)]
    names = {c[0] for c in harness_columns()}
    for new in ("tree_depth", "image_width", "image_height", "render_threads"):
        assert f"`{new}" in contract or f" {new}" in contract, new
    for group in re.findall(r"- (?:identity|provenance): `([^`]+)`", contract):
        for name in (n.strip() for n in group.split(",")):
            assert name in names, name


@needs_binary
@pytest.mark.parametrize("option, names", [("--identity", BUILD_IDENTITY), ("--mixing", MIXING_COLUMNS)])
def test_the_mixing_rule_is_the_harness_rule(option, names):
    """The build's identity and the mixing rule are the harness's lists (provenance.h), name
    for name and in order: a column added on one side alone fails here."""
    out = subprocess.run(
        [str(ACCELBENCH), "columns", option], check=True, capture_output=True, text=True
    ).stdout
    assert out.splitlines() == names
    table = {c[0] for c in harness_columns()}
    assert set(names) <= table and set(names) <= set(PROVENANCE_IDENTITY)
