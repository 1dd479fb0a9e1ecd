"""The analysis package's layout: subpackages by role, imported in one direction
(inputs <- mapping <- outputs/{figures <- report, ci} <- outputs/pages <- grid <- commands
<- reproduce <- cli), and no private name (`_x`) imported from another module."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "accelbench_analysis"

# A part may import itself and the parts before it. `mapping` holds what every output
# shares; the outputs by role: figures (what is drawn), report (REPORT.md's tables,
# claims and comparison, which link the figures), ci (the regression check and the history
# across commits), pages (HTML of what the others wrote). grid stands beside the outputs
# and uses figures; commands are the typed calls the command line (cli) and the main job
# (reproduce) make.
ORDER = [
    "inputs",
    "mapping",
    "outputs.figures",
    "outputs.report",
    "outputs.ci",
    "outputs.pages",
    "grid",
    "commands",
    "reproduce",
    "cli",
    "__main__",
]
# Outputs that must not reach into one another although the order alone would let them.
APART = {("outputs.ci", "outputs.report"), ("outputs.ci", "outputs.figures")}


def module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def part_of(module: str) -> str:
    """accelbench_analysis.outputs.report.tables -> outputs.report; accelbench_analysis.cli
    -> cli; the package's and outputs/'s __init__ -> "" (they hold nothing)."""
    parts = module.split(".")
    if parts[1:] == ["outputs"]:
        return ""
    if len(parts) > 2 and parts[1] == "outputs":
        return ".".join(parts[1:3])
    return parts[1] if len(parts) > 1 else ""


def imports(path: Path) -> list[tuple[int, str, list[str]]]:
    """(line, absolute module, imported names) for each import of the package in a file."""
    module = module_name(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != PACKAGE.name:
                continue
            if node.module is None:  # `from .. import commands`: each name is a module
                found += [(node.lineno, f"{target}.{a.name}", []) for a in node.names]
            else:
                found.append((node.lineno, target, [a.name for a in node.names]))
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == PACKAGE.name:
                    found.append((node.lineno, a.name, []))
    return found


def sources() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def test_every_module_is_in_a_declared_part() -> None:
    parts = {part_of(module_name(p)) for p in sources()} - {""}
    assert parts <= set(ORDER), f"modules outside the declared parts: {sorted(parts - set(ORDER))}"
    assert set(ORDER) - {"__main__"} <= parts | {"cli"}


def test_imports_point_to_the_same_part_or_an_earlier_one() -> None:
    violations = []
    for path in sources():
        here = part_of(module_name(path))
        if here == "":
            continue  # the package's __init__ imports nothing of its own
        for line, target, _ in imports(path):
            there = part_of(target)
            if there not in ORDER:
                violations.append(f"{path.relative_to(PACKAGE)}:{line} imports {target}, not in a part")
            elif ORDER.index(there) > ORDER.index(here):
                violations.append(
                    f"{path.relative_to(PACKAGE)}:{line} ({here}) imports a later part: {target}"
                )
            elif (here, there) in APART:
                violations.append(f"{path.relative_to(PACKAGE)}:{line} ({here}) imports {target}")
    assert violations == []


def test_no_import_cycle_between_parts() -> None:
    edges: dict[str, set[str]] = {}
    for path in sources():
        here = part_of(module_name(path))
        for _, target, _ in imports(path):
            there = part_of(target)
            if there != here:
                edges.setdefault(here, set()).add(there)

    def reaches(start: str, goal: str, seen: set[str]) -> bool:
        for nxt in edges.get(start, ()):
            if nxt == goal or (nxt not in seen and reaches(nxt, goal, seen | {nxt})):
                return True
        return False

    cycles = sorted(p for p in edges if reaches(p, p, {p}))
    assert cycles == [], f"parts on an import cycle: {cycles}"


@pytest.mark.parametrize("path", sources(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_private_name_imported_from_another_module(path: Path) -> None:
    private = [
        f"line {line}: {name} from {target}"
        for line, target, names in imports(path)
        for name in names
        if name.startswith("_") and target != module_name(path)
    ]
    assert private == []
