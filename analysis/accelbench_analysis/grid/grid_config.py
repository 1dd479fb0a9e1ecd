"""Grid configs (configs/grid-*.yaml): a harness config with one accelerator whose parameters
are lists or ranges, plus a `grid:` section (objective, constraints, mode) the harness ignores.

Ranges are expanded here exactly as the harness expands them (analysis/README.md, "Grid
search"): `{from: a, to: b, step: s}` gives a, a+s, ... up to b; `{from: a, to: b, scale:
log2}` gives a, 2a, 4a, ... up to b (`log10`: a, 10a, ...). Integer endpoints and steps give
integers; other values are rounded to 12 significant digits so that 0.1 steps read 0.3, not
0.30000000000000004. The analysis itself reads the values the harness actually ran from the
CSV; the expansion here serves the coverage check, the combination counts and the second
pass of successive halving.
"""

from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass
from pathlib import Path

import pandas as pd
import yaml

from ..inputs.schema import normalise_value

GRID_KEYS = {"objective", "frames", "constraint", "mode", "successive_halving", "halved_from"}
HALVING_KEYS = {"keep", "repetitions", "warmup"}
MODES = ("full", "successive_halving")
RANGE_SCALES = {"log2": 2, "log10": 10}
RANGE_SIGNIFICANT = 12
MAX_RANGE_VALUES = 10000  # a typo like step: 0.0001 should not hang the expansion
NAME_PATTERN = re.compile(r"^[A-Za-z0-9._-]+$")  # the harness uses `name` in file names


class GridConfigError(ValueError):
    """A grid config that cannot be used (names the file and the key)."""


# ---- ranges and axes ---------------------------------------------------------------------------


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _round(v: float) -> float:
    return float(f"{v:.{RANGE_SIGNIFICANT}g}")


def expand_range(spec: dict, where: str) -> list:
    """The values of a `{from, to, step}` or `{from, to, scale}` range (see module doc)."""
    unknown = set(spec) - {"from", "to", "step", "scale"}
    if unknown:
        raise GridConfigError(
            f"{where}: unknown range keys {sorted(unknown)} (a range has "
            f"from, to and either step or scale: log2/log10)"
        )
    lo, hi = spec.get("from"), spec.get("to")
    if not (_is_number(lo) and _is_number(hi)):
        raise GridConfigError(f"{where}: a range needs numeric `from` and `to`")
    if lo > hi:
        raise GridConfigError(f"{where}: `from` ({lo}) is above `to` ({hi})")
    if ("step" in spec) == ("scale" in spec):
        raise GridConfigError(f"{where}: give exactly one of `step` or `scale` (log2, log10)")
    if "step" in spec:
        step = spec["step"]
        if not _is_number(step) or step <= 0:
            raise GridConfigError(f"{where}: `step` must be a positive number")
        n = math.floor((hi - lo) / step + 1e-9) + 1
        integral = all(isinstance(v, int) for v in (lo, hi, step))
        values = [
            lo + i * step if integral else _round(lo + i * step) for i in range(min(n, MAX_RANGE_VALUES + 1))
        ]
    else:
        base = RANGE_SCALES.get(spec["scale"])
        if base is None:
            raise GridConfigError(f"{where}: scale must be one of {', '.join(RANGE_SCALES)}")
        if lo <= 0:
            raise GridConfigError(f"{where}: a {spec['scale']} range starts above 0")
        n = math.floor(math.log(hi / lo, base) + 1e-9) + 1
        integral = isinstance(lo, int)
        values = [
            lo * base**i if integral else _round(lo * base**i) for i in range(min(n, MAX_RANGE_VALUES + 1))
        ]
    if len(values) > MAX_RANGE_VALUES:
        raise GridConfigError(f"{where}: more than {MAX_RANGE_VALUES} values")
    return values


@dataclass
class Axis:
    """One parameter (or a zipped group of parameters) and its values, as the harness
    expands them: the cartesian product of the axes, the first axis varying slowest."""

    names: list[str]
    values: list[tuple]


def _scalar(v, where: str):
    if isinstance(v, (dict, list)):
        raise GridConfigError(f"{where}: expected a single value, got a {type(v).__name__}")
    return v


def parse_axis(key: str, node, where: str) -> Axis:
    if key.startswith("[") and key.endswith("]"):
        names = [n.strip() for n in key[1:-1].split(",")]
        if len(names) < 2 or not all(names):
            raise GridConfigError(f"{where}: a zipped group names two or more parameters")
        if not isinstance(node, list) or not node:
            raise GridConfigError(f"{where}: a zipped group takes a non-empty list of tuples")
        tuples = []
        for i, t in enumerate(node):
            if not isinstance(t, list) or len(t) != len(names):
                raise GridConfigError(f"{where}[{i}]: expected a tuple of {len(names)} values")
            tuples.append(tuple(_scalar(v, f"{where}[{i}]") for v in t))
        return Axis(names, tuples)
    if isinstance(node, dict):
        values = expand_range(node, where)
    elif isinstance(node, list):
        if not node:
            raise GridConfigError(f"{where}: an empty list of values")
        values = [_scalar(v, f"{where}[{i}]") for i, v in enumerate(node)]
    else:
        values = [node]
    texts = [normalise_value(str(v)) for v in values]
    if len(set(texts)) != len(texts):
        raise GridConfigError(f"{where}: a value is listed twice ({values})")
    return Axis([key], [(v,) for v in values])


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


def load_grid_config(path: str | Path) -> GridConfig:
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
    name = str(raw.get("name", path.stem))
    if not NAME_PATTERN.match(name):
        raise GridConfigError(f"{where}: name {name!r} must use letters, digits, '.', '_', '-'")
    models = raw.get("models")
    if not isinstance(models, list) or not models:
        raise GridConfigError(f"{where}: models: expected a non-empty list")
    accels = raw.get("accelerators")
    if (
        not isinstance(accels, list)
        or len(accels) != 1
        or not isinstance(accels[0], dict)
        or "name" not in accels[0]
    ):
        raise GridConfigError(
            f"{where}: accelerators: a grid config has exactly one accelerator "
            f"(a mapping with `name` and `params`)"
        )
    accel = str(accels[0]["name"])
    params = accels[0].get("params") or {}
    if not isinstance(params, dict):
        raise GridConfigError(f"{where}: accelerators[0].params: expected a mapping")
    axes = [parse_axis(str(k), v, f"{where}: accelerators[0].{accel}.{k}") for k, v in params.items()]
    names = [n for a in axes for n in a.names]
    if len(set(names)) != len(names):
        raise GridConfigError(f"{where}: accelerators[0].params: a parameter is given twice")

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
    return GridConfig(
        path=path,
        raw=raw,
        name=name,
        accel=accel,
        axes=axes,
        objective=objective,
        constraints={str(k): float(v) for k, v in constraint.items()},
        mode=mode,
        keep=_int_setting(halving, "keep", hw),
        final_repetitions=_int_setting(halving, "repetitions", hw),
        final_warmup=_int_setting(halving, "warmup", hw),
        models=len(models),
    )
