"""`pip install ./analysis` (pyproject.toml): the console script is the cli's main, every
third-party module the package imports is a declared dependency whose range holds the venv's
pin (requirements.txt), and the files the pages read are package data."""

from __future__ import annotations

import ast
import importlib
import re
import sys
import tomllib
from pathlib import Path

from packaging.requirements import Requirement

ANALYSIS = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((ANALYSIS / "pyproject.toml").read_text())["project"]
# Import names that differ from their distribution's name.
DISTRIBUTION_OF = {"yaml": "pyyaml", "vl_convert": "vl-convert-python"}


def declared() -> dict[str, Requirement]:
    return {Requirement(r).name.lower(): Requirement(r) for r in PROJECT["dependencies"]}


def test_console_script_is_the_cli_main():
    assert PROJECT["scripts"] == {"accelbench-analysis": "accelbench_analysis.cli:main"}
    module, _, name = PROJECT["scripts"]["accelbench-analysis"].partition(":")
    assert callable(getattr(importlib.import_module(module), name))


def test_every_third_party_import_is_a_dependency():
    imported = set()
    for path in (ANALYSIS / "accelbench_analysis").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                imported |= {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                imported.add(node.module.split(".")[0])
    third_party = {m for m in imported if m not in sys.stdlib_module_names and m != "accelbench_analysis"}
    missing = {DISTRIBUTION_OF.get(m, m) for m in third_party} - set(declared())
    assert not missing, f"imported but not in pyproject.toml's dependencies: {sorted(missing)}"


def test_the_pins_are_within_the_declared_ranges():
    pins = {}
    for line in (ANALYSIS / "requirements.txt").read_text().splitlines():
        if m := re.match(r"^([A-Za-z0-9_.-]+)==(\S+)", line):
            pins[m.group(1).lower()] = m.group(2)
    for name, req in declared().items():
        assert name in pins, f"{name}: a dependency the venv does not pin"
        assert req.specifier.contains(pins[name]), f"{name}=={pins[name]} is outside {req.specifier}"


def test_package_data_exists():
    data = tomllib.loads((ANALYSIS / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    for package, globs in data.items():
        folder = ANALYSIS / package.replace(".", "/")
        for g in globs:
            assert list(folder.glob(g)), f"{package}: {g} matches no file"
