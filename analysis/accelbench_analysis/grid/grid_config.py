"""Grid configs (configs/grid-*.yaml): a harness config with one accelerator whose parameters
are lists or ranges, plus a `grid:` section (objective, constraints, mode) the harness ignores.

The harness reads the config and expands its ranges (docs/configs.md, `accelerators`): this
module asks it, through `accelbench run --dry-run=json`, for the accelerator's axes (each value
in its canonical text) and the models, and never expands a range itself, so the grid is the
one the harness runs. The analysis reads the values the harness actually ran from the CSV;
the axes serve the coverage check, the combination counts and the second pass of successive
halving.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import re
import subprocess
from dataclasses import dataclass
from pathlib import Path

import pandas as pd
import yaml

from ..inputs.schema import normalise_value

GRID_KEYS = {"objective", "frames", "constraint", "mode", "successive_halving", "halved_from"}
HALVING_KEYS = {"keep", "repetitions", "warmup"}
MODES = ("full", "successive_halving")
REPO = Path(__file__).resolve().parents[3]


class GridConfigError(ValueError):
    """A grid config that cannot be used (names the file and the key)."""


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def typed(text: str):
    """A parameter's canonical text as the YAML scalar the harness reads back to the same value."""
    t = normalise_value(text)
    if t in ("true", "false"):
        return t == "true"
    if re.fullmatch(r"-?[0-9]+", t):
        return int(t)
    try:
        f = float(t)
    except ValueError:
        return t
    return f if math.isfinite(f) else t


# ---- the harness's expansion ---------------------------------------------------------------


def default_accelbench() -> Path:
    """$ACCELBENCH, else the build of this source tree."""
    return Path(os.environ.get("ACCELBENCH") or REPO / "build" / "accelbench")


def harness_expansion(path: Path, accelbench: Path | None = None) -> dict:
    """`accelbench run --dry-run=json CONFIG`: the config as the harness reads it (its models,
    its accelerator entries with their axes, its combinations). A config the harness refuses
    is a GridConfigError with the harness's messages (file:line:column: key: message)."""
    binary = Path(accelbench) if accelbench else default_accelbench()
    if not binary.is_file():
        raise GridConfigError(
            f"{path}: the harness expands grid configs, and {binary} is not there "
            f"(build it with `make build`, or give --accelbench / $ACCELBENCH)"
        )
    # Not one shard of a Slurm array: the whole grid.
    env = {k: v for k, v in os.environ.items() if not k.startswith("SLURM_ARRAY_TASK_")}
    done = subprocess.run(
        [str(binary), "run", "--dry-run=json", str(path)], capture_output=True, text=True, env=env
    )
    if done.returncode != 0:
        raise GridConfigError(
            done.stderr.strip() or f"{binary} run --dry-run=json {path}: exit {done.returncode}"
        )
    return json.loads(done.stdout)


# ranked.csv's columns (grid.py writes it, heatmaps.py reads it back):
PARAM_COL = "param:"  # ranked.csv's per-parameter columns, so they never meet a statistic's name
PASS_COL = "pass"
FINAL, CHEAP = "final", "cheap"  # ranked candidates; the cheap pass's rows shown as context


def final_config_name(cfg: GridConfig) -> str:
    """The name `halve` gives the second pass's config (its rows carry it in `config`)."""
    return f"{cfg.name}-final"


@dataclass
class Axis:
    """One parameter (or a zipped group of parameters) and its values, as the harness
    expands them: the cartesian product of the axes, the first axis varying slowest."""

    names: list[str]
    values: list[tuple]


def harness_axes(entry: dict) -> list[Axis]:
    """An accelerator entry's axes from the harness's expansion, values typed as YAML reads them."""
    return [Axis(list(a["names"]), [tuple(typed(v) for v in t) for t in a["values"]]) for a in entry["axes"]]


# ---- objective -------------------------------------------------------------------------------------


@dataclass
class Objective:
    """build_weight * build_s_median + render_weight * render_s_median, in seconds."""

    build_weight: float
    render_weight: float

    @property
    def label(self) -> str:
        if self.build_weight == 0:
            return "render"
        if self.render_weight == 1:
            return "build + render"
        return f"build + {self.render_weight:g} * render"

    def value(self, build: pd.Series, render: pd.Series) -> pd.Series:
        b = build if self.build_weight else 0.0
        return self.build_weight * b + self.render_weight * render


OBJECTIVE_FORMS = "render, build+render, or build + k * render (with frames: k)"


def parse_objective(text, frames, where: str) -> Objective:
    t = re.sub(r"\s+", "", str(text)).lower()
    m = re.fullmatch(r"build\+(k|[0-9.]+(?:e[+-]?[0-9]+)?)\*render", t)
    if t == "render" or t == "build+render":
        if frames is not None:
            raise GridConfigError(f"{where}.frames: objective {text!r} has no k to set")
        return Objective(0.0 if t == "render" else 1.0, 1.0)
    if not m:
        raise GridConfigError(f"{where}.objective: {text!r} is not one of: {OBJECTIVE_FORMS}")
    if m[1] == "k":
        if not _is_number(frames) or frames <= 0:
            raise GridConfigError(
                f"{where}.frames: objective {text!r} needs `frames:` (a "
                f"positive number of frames one build serves)"
            )
        return Objective(1.0, float(frames))
    if frames is not None:
        raise GridConfigError(f"{where}.frames: the objective already gives k ({m[1]})")
    return Objective(1.0, float(m[1]))


# ---- the config ---------------------------------------------------------------------------------------


@dataclass
class GridConfig:
    path: Path
    raw: dict
    name: str
    accel: str
    axes: list[Axis]
    objective: Objective
    constraints: dict[str, float]
    mode: str = "full"
    keep: int | None = None
    final_repetitions: int | None = None
    final_warmup: int | None = None
    models: int = 1

    @property
    def given(self) -> list[str]:
        return [n for a in self.axes for n in a.names]

    def points(self) -> list[dict]:
        """Every parameter combination of the grid (for one model)."""
        out = []
        for combo in itertools.product(*(a.values for a in self.axes)):
            point = {}
            for axis, values in zip(self.axes, combo):
                point.update(zip(axis.names, values))
            out.append(point)
        return out

    def combinations(self) -> int:
        return self.models * math.prod(len(a.values) for a in self.axes)


def _int_setting(node: dict, key: str, where: str, default=None):
    v = node.get(key, default)
    if v is not None and (not isinstance(v, int) or isinstance(v, bool) or v < (0 if key == "warmup" else 1)):
        raise GridConfigError(
            f"{where}.{key}: expected a whole number {'>= 0' if key == 'warmup' else '>= 1'}, got {v!r}"
        )
    return v


# Integers PyYAML (YAML 1.1) and the harness's yaml-cpp read differently: a leading zero
# (010: 8 here, 10 there), a 0x/0o/0b prefix, digit groups (1_000) and base 60 (1:30 is 90).
# Refused here as the harness refuses them (base/params.h, number_form_problem).
AMBIGUOUS_INT = re.compile(r"^[-+]?(0[0-9_]|0[xXoObB]|[0-9][0-9_]*_|[0-9]+:)")


class _GridLoader(yaml.SafeLoader):
    """safe_load with the harness's one rule for how an integer is written."""


def _construct_int(loader: _GridLoader, node: yaml.ScalarNode) -> int:
    if AMBIGUOUS_INT.match(node.value):
        raise GridConfigError(
            f"line {node.start_mark.line + 1}: {node.value!r} is written in a form YAML readers read "
            f"differently (010 is 8 in PyYAML and 10 in yaml-cpp; 0x, 0o, 0b, 1_000, 1:30): write it in "
            f"plain decimal"
        )
    return yaml.SafeLoader.construct_yaml_int(loader, node)


_GridLoader.add_constructor("tag:yaml.org,2002:int", _construct_int)


def load_grid_config(path: str | Path, accelbench: Path | None = None) -> GridConfig:
    """The grid config at `path`, its axes as the harness (`accelbench`, default
    default_accelbench()) expands them."""
    path = Path(path)
    try:
        raw = yaml.load(path.read_text(), Loader=_GridLoader)  # noqa: S506 (a SafeLoader)
    except FileNotFoundError:
        raise GridConfigError(f"{path}: no such file") from None
    except yaml.YAMLError as e:
        raise GridConfigError(f"{path}: not valid YAML ({e})") from None
    except GridConfigError as e:
        raise GridConfigError(f"{path}: {e}") from None
    if not isinstance(raw, dict):
        raise GridConfigError(f"{path}: expected a mapping at the top level")
    where = str(path)
    accels = raw.get("accelerators")
    if (
        not isinstance(accels, list)
        or len(accels) != 1
        or not isinstance(accels[0], dict)
        or accels[0].get("name") in (None, "all")
    ):
        raise GridConfigError(
            f"{where}: accelerators: a grid config has exactly one accelerator "
            f"(a mapping with `name` and `params`)"
        )

    grid = raw.get("grid")
    gw = f"{where}: grid"
    if not isinstance(grid, dict):
        raise GridConfigError(f"{gw}: a grid config needs a `grid:` section with the objective")
    unknown = set(grid) - GRID_KEYS
    if unknown:
        raise GridConfigError(f"{gw}: unknown keys {sorted(unknown)} (known: {sorted(GRID_KEYS)})")
    if "objective" not in grid:
        raise GridConfigError(f"{gw}.objective: missing; one of {OBJECTIVE_FORMS}")
    objective = parse_objective(grid["objective"], grid.get("frames"), gw)
    constraint = grid.get("constraint") or {}
    if not isinstance(constraint, dict) or not all(_is_number(v) for v in constraint.values()):
        raise GridConfigError(
            f"{gw}.constraint: expected a mapping column: largest allowed value, e.g. {{false_misses: 0}}"
        )
    mode = grid.get("mode", "full")
    if mode not in MODES:
        raise GridConfigError(f"{gw}.mode: {mode!r} is not one of {', '.join(MODES)}")
    halving = grid.get("successive_halving") or {}
    if not isinstance(halving, dict) or set(halving) - HALVING_KEYS:
        raise GridConfigError(f"{gw}.successive_halving: a mapping with {sorted(HALVING_KEYS)}")
    if halving and mode != "successive_halving":
        raise GridConfigError(f"{gw}.successive_halving: settings given but mode is {mode!r}")
    hw = f"{gw}.successive_halving"
    keep = _int_setting(halving, "keep", hw)
    final_repetitions = _int_setting(halving, "repetitions", hw)
    final_warmup = _int_setting(halving, "warmup", hw)
    expansion = harness_expansion(path, accelbench)
    (entry,) = expansion["accelerators"]
    return GridConfig(
        path=path,
        raw=raw,
        name=expansion["config"],
        accel=entry["name"],
        axes=harness_axes(entry),
        objective=objective,
        constraints={str(k): float(v) for k, v in constraint.items()},
        mode=mode,
        keep=keep,
        final_repetitions=final_repetitions,
        final_warmup=final_warmup,
        models=len(expansion["models"]),
    )
