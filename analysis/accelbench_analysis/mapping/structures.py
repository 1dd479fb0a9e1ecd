"""The structure table, owned by the harness's registry: `accelbench list --json` gives, in
the registry's order, each structure's name, label, role (ours, baseline, reference,
plugin), family, whether `{name: all}` leaves it out as slow, and the variants the
report's tables show as structures of their own (the BVH's splits, the wide BVH's widths),
each with its parameters and label. The analysis holds no list of structures: it reads
this table, and a row whose accelerator the table lacks (a plugin not loaded now, a
structure since removed) is shown under its CSV `label` after the table's structures.

The binary is $ACCELBENCH, else build/accelbench beside analysis/ (as for the grid
configs); the main job names the one that measured (use_accelbench)."""

from __future__ import annotations

import json
import os
import subprocess
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

ROLES = ("ours", "baseline", "reference", "plugin")
REPO = Path(__file__).resolve().parents[3]


class StructureTableError(RuntimeError):
    """The table cannot be read: no binary, or output that is not the table."""


@dataclass(frozen=True)
class Variant:
    params: tuple[tuple[str, str], ...]  # the given parameters that make it this variant
    label: str


@dataclass(frozen=True)
class TableRow:
    name: str
    label: str  # at the defaults
    role: str
    family: str
    slow: bool
    counts_traversal: bool
    variants: tuple[Variant, ...]


_chosen: list[Path] = []


def use_accelbench(path: Path | None) -> None:
    """Read the table from this binary from now on (the main job's own build)."""
    _chosen[:] = [Path(path)] if path is not None else []


def accelbench_path() -> Path:
    if _chosen:
        return _chosen[0]
    env = os.environ.get("ACCELBENCH")
    return Path(env) if env else REPO / "build" / "accelbench"


def parse_table(text: str, source: str = "accelbench list --json") -> list[TableRow]:
    """The rows of `accelbench list --json`'s output; refuses anything else, naming it."""
    try:
        doc = json.loads(text)
        rows = []
        for s in doc["structures"]:
            if s["role"] not in ROLES:
                raise ValueError(f"{s['name']}: role {s['role']!r} is none of {', '.join(ROLES)}")
            variants = tuple(Variant(tuple(sorted(v["params"].items())), v["label"]) for v in s["variants"])
            if not variants:
                raise ValueError(
                    f"{s['name']}: no variants (a structure without any has one, of no parameters)"
                )
            rows.append(
                TableRow(
                    s["name"],
                    s["label"],
                    s["role"],
                    s["family"],
                    bool(s["slow"]),
                    bool(s["counts_traversal"]),
                    variants,
                )
            )
    except (ValueError, KeyError, TypeError) as e:
        raise StructureTableError(f"{source}: not the structure table ({e})") from None
    return rows


@lru_cache(maxsize=8)
def _table_of(binary: str) -> tuple[TableRow, ...]:
    try:
        out = subprocess.run([binary, "list", "--json"], capture_output=True, text=True)
    except OSError as e:
        raise StructureTableError(
            f"the structure table comes from `accelbench list --json`: cannot run {binary} ({e.strerror}); "
            f"build it (make build) or set ACCELBENCH"
        ) from None
    if out.returncode != 0:
        raise StructureTableError(
            f"{binary} list --json failed (exit {out.returncode}): {out.stderr.strip()}"
        )
    return tuple(parse_table(out.stdout, f"{binary} list --json"))


def structure_table() -> list[TableRow]:
    """The registry's structure table (read once per binary)."""
    return list(_table_of(str(accelbench_path())))


def table_row(accel: str) -> TableRow | None:
    return next((r for r in structure_table() if r.name == accel), None)


def role_of(accel: str) -> str:
    """The table's role of an accelerator; one the table lacks counts as ours."""
    row = table_row(accel)
    return row.role if row is not None else "ours"


def baseline_accels() -> list[str]:
    """The accelerators every ratio is taken against (Embree)."""
    return [r.name for r in structure_table() if r.role == "baseline"]


def variant_of_row(accel: str, params: dict[str, str]) -> Variant | None:
    """The table's variant a row of this accelerator and these parameters is: the first whose
    parameters the row has (a row lacking one of them, from an older build, matches it)."""
    row = table_row(accel)
    if row is None:
        return None
    for v in row.variants:
        if all(params.get(k, val) == val for k, val in v.params):
            return v
    return None


def table_labels(roles: tuple[str, ...] = ("ours", "plugin", "baseline")) -> list[str]:
    """Every variant's label in table order, of the structures of these roles."""
    return [v.label for r in structure_table() if r.role in roles for v in r.variants]
