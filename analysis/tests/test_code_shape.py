"""No Python function over 80 lines and no module over 600 in analysis/ (the package and its
tests), as core/tests/code_shape_test.cpp holds the C++ to 120 lines a function: past that
a reader cannot hold the piece in view, and the seams a long function already marks (its
stages, its cases) deserve names. A function's lines run from its `def` (decorators not
counted) to its last line; a module's are its lines. The measure is checked on small texts
first, so that the size test cannot pass by finding nothing."""

from __future__ import annotations

import ast
from pathlib import Path

ANALYSIS = Path(__file__).resolve().parent.parent
MAX_FUNCTION_LINES, MAX_MODULE_LINES = 80, 600

# Offenders still to be split, as "path" or "path: function" (paths relative to analysis/);
# empty, and each must still offend (the test says when one no longer does).
NOT_YET_SPLIT: set[str] = set()


def offenders(text: str, name: str) -> list[str]:
    """ "NAME" when the module is too long, "NAME: function" for each function too long."""
    found = [name] if text.count("\n") + (not text.endswith("\n")) > MAX_MODULE_LINES else []
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            if node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES:
                found.append(f"{name}: {node.name}")
    return found


def test_the_measure_finds_long_functions_and_modules():
    body = "".join(f"    x{i} = {i}\n" for i in range(MAX_FUNCTION_LINES - 1))
    ok = "def f():\n" + body
    long = "def g():\n" + body + "    return 1\n"
    assert offenders(ok, "m.py") == []
    assert offenders(long, "m.py") == ["m.py: g"]
    nested = (
        "class C:\n    def h(self):\n"
        + "".join(f"    {line}" for line in body.splitlines(True))
        + "        pass\n"
    )
    assert offenders(nested, "m.py") == ["m.py: h"]
    assert offenders("x = 1\n" * MAX_MODULE_LINES, "m.py") == []
    assert offenders("x = 1\n" * (MAX_MODULE_LINES + 1), "m.py") == ["m.py"]


def test_no_function_or_module_is_too_long():
    found = set()
    for path in sorted(ANALYSIS.rglob("*.py")):
        if any(part.startswith(".") for part in path.relative_to(ANALYSIS).parts):
            continue
        found |= set(offenders(path.read_text(), str(path.relative_to(ANALYSIS))))
    assert sorted(found - NOT_YET_SPLIT) == [], "split these (or their seams)"
    assert sorted(NOT_YET_SPLIT - found) == [], "no longer too long: take them off NOT_YET_SPLIT"
