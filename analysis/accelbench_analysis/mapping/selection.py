"""Which of our CSV rows stands for which cell of the report's tables.

A cell of the report is (model, structure, setting). Our rows are (model, accel, params).
Only rows of the report's workload can stand for one (`report_rows`): camera rays (primary
and shadow together, as the report timed them), one render thread, and per model one image,
the report's 640x480 at one sample where the model has it. The mapping is explicit here and
nowhere else:

- the report's "default" setting is its Table 3 (REPORT_SETTINGS): BVH median split,
  maxPrims 1, depth 50; LBVH maxPrims 1, depth 50; kd-tree maxPrims 1 with the
  scene-dependent depth 8 + 1.3 log2(N) (pbrt's formula, which the report cites as its
  Equation 5); the report's cells require it, the figures only prefer it, so a run at
  a structure's defaults (max_prims=auto) is drawn too;
- the structures are the structure table's (structures.py, the registry's), one per
  variant it declares, labelled by it;
- Table 2's settings vary one kd-tree parameter (maxPrims or maxDepth) on the bunny;
- the table's other structures (the binned-SAH BVH, the wide BVH, Embree) have no report
  numbers but appear in every table.

Parameters a row does not have at all (its accelerator does not declare them) cannot
differ and so do not exclude it. Parameters the report does not fix are free; when several
rows differ only in free parameters, `preferred` values decide (single-threaded builds, as
in the report, and pbrt's kd-tree costs, which the report used), then the newest
timestamp, and the cell's note lists what else matched. Rows that differ in `traversal`
(ordered vs the report's fixed left-first order) are never collapsed: each becomes its own
labelled row.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import pandas as pd

from ..inputs.schema import CAMERA_SET, Results
from .structures import structure_table, variant_of_row

# The report's renders: 640x480 pixels, one sample each (its section 5), on one thread.
REPORT_IMAGE = (640, 480, 1)
IMAGE_COLUMNS = ("image_width", "image_height", "spp")


def image_text(image: tuple[int, int, int]) -> str:
    w, h, spp = image
    return f"{w}x{h}" + (f" at {spp} samples" if spp != 1 else "")


def images(rows: pd.DataFrame) -> pd.Series:
    """Each row's (width, height, spp), or None where the CSV does not record it."""
    if not all(c in rows.columns for c in IMAGE_COLUMNS):
        return pd.Series([None] * len(rows), index=rows.index, dtype=object)
    nums = [pd.to_numeric(rows[c], errors="coerce") for c in IMAGE_COLUMNS]
    return pd.Series(
        [None if any(pd.isna(v) for v in vals) else tuple(int(v) for v in vals) for vals in zip(*nums)],
        index=rows.index,
        dtype=object,
    )


def _count_text(values: pd.Series) -> str:
    counts = values.value_counts()
    return ", ".join(f"{n} {v}" for v, n in counts.items())


def report_rows(
    results: Results,
    own_image: pd.Series | None = None,
    what: str = "the report's tables, claims and figures",
) -> tuple[Results, list[str]]:
    """The rows the report's tables, their figures and the claims are made of: camera rays,
    one render thread, and per model one image: the report's 640x480 at one sample where the
    model has rows of it, else the largest it has. Rows of `own_image` (the ablations, each
    config at its own image) are not chosen between by image. Returns those rows and notes
    counting every row left out and why; what the outputs lack (a model without a row at the
    report's image, no row of the workload at all) is also a warning of the Results, which
    every output shows. No output mixes rows that are not comparable or hides what it lacks.
    `what`: the outputs made of the rows, as the notes name them."""
    rows = results.rows
    notes: list[str] = []
    lacks: list[str] = []
    sets = rows["ray_set"] != CAMERA_SET
    if sets.any():
        notes.append(
            f"left out of {what}: {int(sets.sum())} rows of ray sets "
            f"({_count_text(rows.loc[sets, 'ray_set'])}); they time camera rays, primary and shadow "
            f"together, as the report did (tables/ray_sets.md has the ray sets)"
        )
    threads = pd.to_numeric(rows["render_threads"], errors="coerce")
    several = ~sets & threads.notna() & (threads != 1)
    if several.any():
        notes.append(
            f"left out of {what}: {int(several.sum())} rows rendered on "
            f"more than one thread ({_count_text(threads[several].astype(int).astype(str) + ' threads')}); "
            f"the report rendered on one"
        )
    keep = ~sets & ~several
    own = (own_image if own_image is not None else pd.Series(False, index=rows.index)).reindex(
        rows.index, fill_value=False
    )
    image = images(rows)
    for model in dict.fromkeys(rows.loc[keep & ~own, "model"]):
        mine = keep & ~own & (rows["model"] == model) & image.notna()
        have = set(image[mine])
        if not have:
            continue
        chosen = REPORT_IMAGE if REPORT_IMAGE in have else max(have, key=lambda i: (i[0] * i[1] * i[2], i))
        other = mine & (image != chosen)
        if chosen != REPORT_IMAGE:
            lacks.append(
                f"{model} has no row at the report's {image_text(REPORT_IMAGE)}: its cells are "
                f"{image_text(chosen)} renders"
            )
        if other.any():
            notes.append(
                f"left out on {model}: {int(other.sum())} rows at another image "
                f"({_count_text(image[other].map(image_text))}); its cells are {image_text(chosen)} renders"
            )
            keep &= ~other
    if len(rows) and not keep.any():
        lacks.append(
            f"no row is of the report's workload (camera rays on one render thread): {what} have "
            f"no measurement of ours"
        )
    return replace(results, rows=rows[keep], warnings=list(results.warnings) + lacks), notes + lacks


AUTO = "<auto>"  # the kd-tree's scene-dependent default depth (see kd_auto_depths)
AUTO_TEXT = {"", "auto", "default"}

SINGLE_THREAD = (("threads", "1"),)
# pbrt-v4's kd-tree defaults, which the report (section 4.2.1) adopted.
KD_PREFERRED = SINGLE_THREAD + (("isect_cost", "80"), ("traversal_cost", "1"), ("empty_bonus", "0.5"))
EMBREE_PREFERRED = SINGLE_THREAD + (("quality", "medium"), ("robust", "false"), ("compact", "false"))
SPLIT_BY = ("traversal",)


def kd_auto_depth_pbrt(triangles: float) -> int:
    """pbrt's automatic kd-tree depth (maxdepth -1): round(8 + 1.3 * Log2Int(N)), integer log2."""
    return math.floor(8 + 1.3 * math.floor(math.log2(triangles)) + 0.5)


def kd_auto_depth_report(triangles: float) -> int:
    """The report's Equation 5, depth = 8 + 1.3 log(N), with the real log2, rounded."""
    return math.floor(8 + 1.3 * math.log2(triangles) + 0.5)


def kd_auto_depths(triangles: float) -> set[int]:
    """Depths that count as the kd-tree's automatic default for a scene of N triangles.

    pbrt-v4 uses round(8 + 1.3 * Log2Int(N)); the report writes 8 + 1.3 log(N). Both
    roundings (integer and real log2) are accepted because the harness may record either.
    """
    if not triangles or triangles <= 0 or math.isnan(triangles):
        return set()
    return {kd_auto_depth_pbrt(triangles), kd_auto_depth_report(triangles)}


@dataclass(frozen=True)
class Spec:
    accel: str
    required: tuple[tuple[str, str], ...] = ()
    preferred: tuple[tuple[str, str], ...] = SINGLE_THREAD

    def describe(self) -> str:
        req = ", ".join(f"{k}={'auto' if v == AUTO else v}" for k, v in self.required)
        return f"{self.accel}" + (f" ({req})" if req else "")


@dataclass(frozen=True)
class Structure:
    key: str  # the report's name for a structure it measured, else "NAME[ PARAM=VALUE]"
    label: str
    spec: Spec  # its identity (the table variant's parameters), the report's setting preferred
    report_accel: str | None  # the report's accelerator name; None: no report numbers
    role: str = "ours"  # the structure table's: ours, baseline, plugin
    report_spec: Spec | None = None  # the report's setting of it (its Table 3), required

    @property
    def table_spec(self) -> Spec:
        """What a cell of the report's tables requires: the report's setting where it has one."""
        return self.report_spec or self.spec


# The report's setting of each structure it measured (its Table 3), by the report's name:
# BVH median split, maxPrims 1, depth 50; LBVH maxPrims 1, depth 50; kd-tree maxPrims 1
# with the scene-dependent depth. The report's cells require it; every other output
# prefers it among a structure's rows.
REPORT_SETTINGS = {
    "bvh": Spec("bvh", (("split", "median"), ("max_prims", "1"), ("max_depth", "50"))),
    "lbvh": Spec("lbvh", (("max_prims", "1"), ("max_depth", "50"))),
    "kdtree": Spec("kdtree", (("max_prims", "1"), ("max_depth", AUTO)), KD_PREFERRED),
}
# Free parameters preferred where several rows of one structure fit (beyond one build
# thread): pbrt's kd-tree costs, which the report used; Embree's defaults.
PREFERRED = {"kdtree": KD_PREFERRED, "embree": EMBREE_PREFERRED}


def report_name(accel: str, variant_params: tuple[tuple[str, str], ...]) -> str | None:
    """The report's name of the structure a table variant is, where the report measured it."""
    for name, spec in REPORT_SETTINGS.items():
        if spec.accel == accel and all(p in spec.required for p in variant_params):
            return name
    return None


def table_structures() -> list[Structure]:
    """The structures of the comparison (not the references), one per variant, in the
    structure table's order."""
    out = []
    for row in structure_table():
        if row.role == "reference":
            continue
        for v in row.variants:
            report = report_name(row.name, v.params)
            key = report or " ".join([row.name] + [f"{k}={val}" for k, val in v.params])
            prefer = PREFERRED.get(row.name, SINGLE_THREAD)
            if report is not None:
                prefer = REPORT_SETTINGS[report].required + prefer
            spec = Spec(row.name, v.params, prefer)
            out.append(Structure(key, v.label, spec, report, row.role, REPORT_SETTINGS.get(report)))
    return out


def label_of(accel: str, params: dict[str, str]) -> str:
    """The structure table's label of a row's structure (the variant its parameters are);
    the accelerator's name where the table has none."""
    v = variant_of_row(accel, params)
    return v.label if v is not None else accel


def parse_setting(setting: str) -> tuple[str, str] | None:
    """The report's Table 2 setting text ("maxPrims=10") as (our parameter, value)."""
    if setting == "default":
        return None
    name, _, value = setting.partition("=")
    ours = {"maxPrims": "max_prims", "maxDepth": "max_depth"}.get(name)
    if ours is None:
        raise ValueError(f"unknown report setting {setting!r}")
    return ours, value


def param_matches(params: dict[str, str], triangles: float, name: str, want: str) -> bool:
    if name not in params:
        return True  # the accelerator has no such parameter: it cannot differ
    have = params[name]
    if want == AUTO:
        if have.lower() in AUTO_TEXT:
            return True
        try:
            return int(float(have)) in kd_auto_depths(triangles)
        except ValueError:
            return False
    return have == want


@dataclass
class Pick:
    row: pd.Series | None
    reason: str = ""  # why there is no row (when row is None)
    notes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.row is not None

    def value(self, column: str) -> float | None:
        if self.row is None:
            return None
        v = self.row.get(column)
        return None if v is None or pd.isna(v) else float(v)


def _fmt_params(params: dict[str, str]) -> str:
    return ";".join(f"{k}={v}" for k, v in params.items()) or "(none)"


class Picker:
    """Finds the row for a (model, spec[, traversal variant]) cell."""

    def __init__(self, results: Results):
        self.results = results
        # Robustness-catalogue verdicts are not measurements of a structure on a model.
        self.rows = results.measured_rows()
        self.models = set(self.rows["model"])
        self._structures: list[Structure] | None = None
        # The rows of each (model, accel), in the rows' order, and the answers already
        # given: a claim asks for the same cell thousands of times (once per noise draw).
        self._of = dict(tuple(self.rows.groupby(["model", "accel"], sort=False))) if len(self.rows) else {}
        self._candidates: dict[tuple, pd.DataFrame] = {}
        self._picks: dict[tuple, Pick] = {}
        self._depth_sweeps: dict[tuple, str | None] = {}

    def rows_of(self, model: str, accel: str) -> pd.DataFrame:
        """The rows of one structure on one model (none: an empty frame)."""
        return self._of.get((model, accel), self.rows.iloc[0:0])

    def depth_sweep_max_prims(self, model: str, depths: list[str]) -> str | None:
        """depth_sweep_max_prims on the kd-tree's rows of `model`."""
        key = (model, tuple(depths))
        if key not in self._depth_sweeps:
            self._depth_sweeps[key] = depth_sweep_max_prims(self.rows_of(model, "kdtree"), depths)
        return self._depth_sweeps[key]

    def structures(self) -> list[Structure]:
        """The structure table's structures of the comparison, then one structure at its
        defaults for every accelerator the data holds that the table lacks (a plugin not
        loaded now), labelled by the rows' `label` column where the CSV has it."""
        if self._structures is None:
            self._structures = self._find_structures()
        return self._structures

    def _find_structures(self) -> list[Structure]:
        out = table_structures()
        known = {r.name for r in structure_table()}
        for accel in dict.fromkeys(self.rows["accel"]) if len(self.rows) else []:
            if accel in known:
                continue
            rows = self.rows[self.rows["accel"] == accel]
            label = (
                str(rows["label"].dropna().iloc[0])
                if "label" in rows and rows["label"].notna().any()
                else accel
            )
            out.append(Structure(accel, label, Spec(accel), None))
            known.add(accel)
        return out

    def structure(self, key: str) -> Structure:
        """The structure of this key ("bvh": the report's BVH, median split)."""
        return next(s for s in self.structures() if s.key == key)

    def candidates(self, model: str, spec: Spec, variant: str | None = None) -> pd.DataFrame:
        key = (model, spec, variant)
        if key not in self._candidates:
            df = self.rows_of(model, spec.accel)
            keep = [
                all(param_matches(p, tri, k, v) for k, v in spec.required)
                and (variant is None or variant_of(p) == variant)
                for p, tri in zip(df["param_dict"], df["triangles"])
            ]
            self._candidates[key] = df[keep] if len(df) else df
        return self._candidates[key]

    def variants(self, models: list[str], spec: Spec) -> list[str]:
        """Traversal variants present for this spec on any of the models."""
        seen = {variant_of(p) for m in models for p in self.candidates(m, spec)["param_dict"]}
        return sorted(seen, key=lambda v: (v != "", v != "ordered", v))

    def pick(self, model: str, spec: Spec, variant: str | None = None) -> Pick:
        """The row of the cell (the same Pick every time it is asked: read it, never change it)."""
        key = (model, spec, variant)
        if key not in self._picks:
            self._picks[key] = self._pick(model, spec, variant)
        return self._picks[key]

    def _pick(self, model: str, spec: Spec, variant: str | None) -> Pick:
        cands = self.candidates(model, spec, variant)
        if cands.empty:
            return Pick(None, "no row", self._what_exists(model, spec))
        ok = cands[cands["status"] == "ok"]
        if ok.empty:
            r = cands.iloc[0]
            msg = str(r.get("message", "")).strip()
            return Pick(None, r["status"] + (f": {msg}" if msg else ""))
        score = pd.Series(
            [
                sum(1 for k, v in spec.preferred if k in p and param_matches(p, tri, k, v))
                for p, tri in zip(ok["param_dict"], ok["triangles"])
            ],
            index=ok.index,
        )
        best = ok[score == score.max()]
        best = best.sort_values("timestamp", ascending=False, kind="stable")
        chosen = best.iloc[0]
        notes = []
        if len(best) > 1:
            distinct = {r["params"] for _, r in best.iterrows()}
            where = f"{spec.accel} on {model}"
            if len(distinct) > 1:
                notes.append(
                    f"{len(best)} rows fit {where} equally well "
                    f"({'; '.join(sorted('[' + d + ']' for d in distinct))}); "
                    f"used [{chosen['params']}] (newest)"
                )
            else:
                runs = sorted(f"{r['config']} in {r['source']}" for _, r in best.iterrows())
                notes.append(
                    f"{where} [{chosen['params']}] was measured {len(best)} times "
                    f"({'; '.join(runs)}); used the newest ({chosen['timestamp']}, "
                    f"{chosen['config']})"
                )
        return Pick(chosen, notes=notes)

    def _what_exists(self, model: str, spec: Spec) -> list[str]:
        df = self.rows_of(model, spec.accel)
        if df.empty:
            return []
        shown = sorted(set(df["params"]))[:3]
        more = f" and {len(set(df['params'])) - 3} more" if len(set(df["params"])) > 3 else ""
        return [
            f"no {spec.describe()} row on {model}; its {spec.accel} rows have "
            f"{'; '.join('[' + s + ']' for s in shown)}{more}"
        ]


def variant_of(params: dict[str, str]) -> str:
    return params.get("traversal", "")


def variant_label(label: str, variant: str, variants: list[str]) -> str:
    if len(variants) <= 1 or not variant:
        return label
    return f"{label} [traversal={variant}]"


def depth_sweep_max_prims(rows: pd.DataFrame, depths: list[str]) -> str | None:
    """The max_prims value at which our kd-tree depth sweep was run (`rows`: the kd-tree's
    rows on one model).

    The report does not state the maxPrims of its depth sweep. Ours is whichever max_prims
    covers the most of the report's depths on this model (ties: the smallest value).
    """
    cover: dict[str, set[str]] = {}
    for p in rows["param_dict"]:
        if p.get("max_depth") in depths and "max_prims" in p:
            cover.setdefault(p["max_prims"], set()).add(p["max_depth"])
    if not cover:
        return None
    return min(cover, key=lambda mp: (-len(cover[mp]), float(mp)))


def setting_spec(setting: str, structure: str, picker: Picker, model: str, depths: list[str]) -> Spec:
    """Our spec for one of the report's settings ("default" or a Table 2 setting)."""
    parsed = parse_setting(setting)
    if parsed is None:
        if structure in REPORT_SETTINGS:
            return REPORT_SETTINGS[structure]
        return next(s for s in picker.structures() if s.key == structure).spec
    if structure != "kdtree":
        raise ValueError(f"Table 2 settings apply to the kd-tree only, not {structure}")
    name, value = parsed
    if name == "max_prims":
        return Spec("kdtree", (("max_prims", value), ("max_depth", AUTO)), KD_PREFERRED)
    fixed = picker.depth_sweep_max_prims(model, depths)
    req = (("max_depth", value),) + ((("max_prims", fixed),) if fixed is not None else ())
    return Spec("kdtree", req, KD_PREFERRED)
