"""A run directory's run.json as every reader of run folders reads it (the runs page,
history, the main job): a file that cannot be read, is no JSON or holds no JSON object is
skipped with one line on stderr naming it and why, never a crash; a field of the wrong
type reads as absent."""

from __future__ import annotations

import json
import sys
from pathlib import Path

RUN_JSON = "run.json"


def skipped(path: Path, why: str) -> None:
    """The one line a reader of run folders prints for a file it leaves out."""
    print(f"skipped {path}: {why}", file=sys.stderr)


def read_run_json(run_dir: Path) -> dict | None:
    """run_dir/run.json as a dict; None when there is none or it is unusable (said so)."""
    path = run_dir / RUN_JSON
    if not path.exists():
        return None
    try:
        meta = json.loads(path.read_text())
    except (OSError, ValueError) as e:
        skipped(path, f"{type(e).__name__}: {e}")
        return None
    if not isinstance(meta, dict):
        skipped(path, f"a JSON {type(meta).__name__}, not an object")
        return None
    return meta


def field(meta: dict, key: str, kind: type, default):
    """meta[key] when it is a `kind`, else `default` (a run.json edited or cut by hand)."""
    value = meta.get(key, default)
    return value if isinstance(value, kind) else default
