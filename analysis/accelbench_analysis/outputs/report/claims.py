"""The report's claims (sections 5.1 to 6), checked against its own numbers and against ours.

Each claim is a small function over a *source* of numbers: the report's (report-tables.csv)
or ours (the harness CSV, through the same cell mapping as the tables). The same function
computes both columns, so a verdict is never typed in: it follows from the data. A claim
whose numbers are missing on one side, or whose rows on our side come from different
builds/machines, is "not comparable", with the reason.

Tolerances (what "~", "about the same" and "best" mean here) are the constants below.
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import pandas as pd

from ...inputs.report_numbers import REPORT_MODEL, TABLE4_MODELS, TABLE5_MODELS, our_model, report_value
from ...inputs.schema import Results
from ...mapping.formatting import fmt_sig, md_escape
from ...mapping.metrics import METRIC, preferred_variant
from ...mapping.selection import Picker, setting_spec
from .cost_model import AdjustedSource, FlooredSource, cost_model_lines, fit_all, write_cost_model

# "~N x": the measured factor must lie within a factor APPROX_FACTOR of N, and never closer
# to 1 than APPROX_MIN_EFFECT of the claimed effect in log terms, so that "~1.2x" is not
# satisfied by "no change" (1.2x accepts 1.10x-1.31x, 2x accepts 1.60x-2.50x).
APPROX_FACTOR = 1.25
APPROX_MIN_EFFECT = 0.5
# "about the same": the two values within this factor of each other.
SIMILAR_FACTOR = 1.25
# "the same tree" (depth saturation): node counts within 1%.
SAME_TREE_RTOL = 0.01
# "best of the settings tried": within 5% of the smallest total.
BEST_TOL = 0.05
# Monotone trends over a sweep may reverse by at most this much between two steps
# (timing noise where the tree no longer changes).
TREND_NOISE = 0.05

HOLDS, FAILS, NOT_COMPARABLE = "holds", "does not hold", "not comparable"
STRUCTURE_SHORT = {"bvh": "BVH", "lbvh": "LBVH", "kdtree": "kd-tree"}
ALL_MODELS = TABLE4_MODELS + TABLE5_MODELS
LARGE_MODELS = ["asian-dragon", "happy-buddha"]
SMALL_MODELS = ["stanford-bunny", "igea"]
BUNNY = "stanford-bunny"


class Missing(Exception):
    """A number the claim needs is not there (or a premise does not carry over)."""


# ---- sources ----------------------------------------------------------------------------


class ReportSource:
    name = "report"

    def __init__(self, report_nums: pd.DataFrame):
        self.report_nums = report_nums

    def begin(self) -> None:
        pass

    def groups(self) -> set[str]:
        return set()

    def primitives(self, model: str) -> float:
        v = self.report_nums.loc[self.report_nums["model"] == model, "primitives"]
        if v.empty:
            raise Missing(f"#Primitives of {model}")
        return float(v.iloc[0])

    def get(self, model: str, structure: str, metric: str, setting: str = "default") -> float:
        if metric == "total":
            return self.get(model, structure, "build", setting) + self.get(
                model, structure, "render", setting
            )
        v = report_value(self.report_nums, model, structure, setting, METRIC[metric].report)
        if v is None or math.isnan(v):
            raise Missing(f"report has no {metric} for {structure} {setting} on {model}")
        return v


# The configs whose rows are ablations (configs/ablations.yaml and its QUICK=1 variant):
# the claims are judged on the other rows, and each ablation again on these.
ABLATION_CONFIGS = ("ablations", "quick-ablations", "ablations-primary", "quick-ablations-primary")


def is_ablation(rows: pd.DataFrame) -> pd.Series:
    return rows["config"].isin(ABLATION_CONFIGS) if "config" in rows else pd.Series(False, index=rows.index)


def without_ablations(results: Results) -> Results:
    return replace(results, rows=results.rows[~is_ablation(results.rows)])


class OurSource:
    name = "ours"

    def __init__(
        self,
        results: Results,
        report_nums: pd.DataFrame,
        extra: dict | None = None,
        traversal: str | None = None,
        models: dict[str, str] | None = None,
    ):
        """extra: structure -> ((param, value), ...) every row of that structure must also
        have (an ablation's setting): those structures are read from the ablation configs'
        rows, every other structure from the run at the report's settings, so an ablation
        changes one structure and compares it with the others as measured. Without extra,
        the run's non-ablation rows. traversal: the BVH/LBVH traversal variant to read
        (default: the report's own order where both were measured). models: report model ->
        our model label, where an ablation measures another stand-in (e.g. the bunny
        decimated to the report's N)."""
        self.extra = extra or {}
        self.traversal = traversal
        self.models = models or {}
        rows = results.rows
        if extra:
            ablated = rows["accel"].isin(list(extra)) if "accel" in rows else False
            rows = rows[is_ablation(rows) == ablated]
        else:
            rows = rows[~is_ablation(rows)]
        self.results = replace(results, rows=rows)
        results = self.results
        self.picker = Picker(results)
        self.depths = [
            s.split("=")[1]
            for s in report_nums.loc[report_nums["table"] == 2, "setting"]
            if s.startswith("maxDepth=")
        ]
        self._groups: set[str] = set()
        self.variants_used: set[str] = set()

    def begin(self) -> None:
        self._groups = set()

    def groups(self) -> set[str]:
        return self._groups

    def model(self, report_model: str) -> str:
        return self.models.get(report_model) or our_model(report_model, self.picker.models)

    def primitives(self, model: str) -> float:
        rows = self.results.rows[self.results.rows["model"] == self.model(model)]
        if rows.empty:
            raise Missing(f"no rows for {self.model(model)}")
        return float(rows["triangles"].iloc[0])

    def get(self, model: str, structure: str, metric: str, setting: str = "default") -> float:
        if metric == "total":
            return self.get(model, structure, "build", setting) + self.get(
                model, structure, "render", setting
            )
        ours = self.model(model)
        spec = setting_spec(setting, structure, self.picker, ours, self.depths)
        if structure in self.extra:
            spec = replace(spec, required=spec.required + tuple(self.extra[structure]))
        variants = self.picker.variants([ours], spec)
        variant = self.traversal if self.traversal in variants else preferred_variant(variants)
        pick = self.picker.pick(ours, spec, variant)
        what = f"{STRUCTURE_SHORT.get(structure, structure)} ({setting}) on {ours}"
        if not pick.ok:
            raise Missing(f"{what}: {pick.reason}")
        v = pick.value(METRIC[metric].ours)
        if v is None:
            raise Missing(f"{what} has no {metric}")
        self._groups.add(str(pick.row["prov_group"]))
        if variant:
            self.variants_used.add(variant)
        return v


# ---- building blocks (each returns (holds, evidence)) -------------------------------------


def short(model: str) -> str:
    return REPORT_MODEL[model].short


def approx_range(target: float) -> tuple[float, float]:
    half = min(math.log(APPROX_FACTOR), APPROX_MIN_EFFECT * abs(math.log(target)))
    return target * math.exp(-half), target * math.exp(half)


def approx(x: float, target: float) -> bool:
    lo, hi = approx_range(target)
    return x > 0 and lo <= x <= hi


def quantify(flags: list[bool], quantifier: str) -> bool:
    if quantifier == "all":
        return all(flags)
    if quantifier == "most":
        return sum(flags) * 2 > len(flags)
    raise ValueError(quantifier)


def count_text(flags: list[bool], quantifier: str) -> str:
    need = "all" if quantifier == "all" else "more than half"
    return f"{sum(flags)}/{len(flags)} (needs {need})"


def ranking(
    src, models, metric, winner, extreme="min", quantifier="all", structures=("bvh", "lbvh", "kdtree")
):
    flags, parts = [], []
    for m in models:
        vals = {s: src.get(m, s, metric) for s in structures}
        order = sorted(vals, key=vals.get)
        best = order[0] if extreme == "min" else order[-1]
        flags.append(best == winner)
        parts.append(
            f"{short(m)} {'✓' if flags[-1] else '✗'} "
            + " < ".join(f"{STRUCTURE_SHORT[s]} {fmt_sig(vals[s])}" for s in order)
        )
    return quantify(flags, quantifier), f"{count_text(flags, quantifier)}: " + "; ".join(parts)


def factor(src, pairs, target, label):
    """pairs: list of (numerator, denominator) thunks; geometric mean of the ratios vs ~target."""
    ratios = [num() / den() for num, den in pairs]
    gm = math.exp(sum(math.log(r) for r in ratios) / len(ratios))
    lo, hi = approx_range(target)
    each = (
        "" if len(ratios) == 1 else " (geometric mean of " + ", ".join(f"{fmt_sig(r)}" for r in ratios) + ")"
    )
    return approx(gm, target), (
        f"{label} {fmt_sig(gm)}x{each}; ~{target:g}x accepts {fmt_sig(lo)}-{fmt_sig(hi)}x"
    )


def similar(src, models, a, b, metric, quantifier, within=SIMILAR_FACTOR):
    flags, parts = [], []
    for m in models:
        r = src.get(m, a, metric) / src.get(m, b, metric)
        flags.append(1 / within <= r <= within)
        parts.append(f"{short(m)} {fmt_sig(r)}{'' if flags[-1] else ' ✗'}")
    return quantify(flags, quantifier), (
        f"{STRUCTURE_SHORT[a]}/{STRUCTURE_SHORT[b]} {metric}: {', '.join(parts)}; "
        f"within {within}x on {count_text(flags, quantifier)}"
    )


def compare(src, models, a, b, metric, quantifier="all"):
    """a < b on the models."""
    flags, parts = [], []
    for m in models:
        va, vb = src.get(m, a, metric), src.get(m, b, metric)
        flags.append(va < vb)
        parts.append(f"{short(m)} {fmt_sig(va)} {'<' if flags[-1] else '≥'} {fmt_sig(vb)}")
    return quantify(flags, quantifier), (
        f"{STRUCTURE_SHORT[a]} vs {STRUCTURE_SHORT[b]} {metric}: {'; '.join(parts)}; "
        f"{count_text(flags, quantifier)}"
    )


def more_than(src, model, num, den, metric, minimum):
    ratios = {d: src.get(model, num, metric) / src.get(model, d, metric) for d in den}
    ok = all(r > minimum for r in ratios.values())
    return ok, (
        f"{short(model)}: "
        + ", ".join(
            f"{STRUCTURE_SHORT[num]}/{STRUCTURE_SHORT[d]} {metric} {fmt_sig(r)}x" for d, r in ratios.items()
        )
        + f" (needs > {minimum}x each)"
    )


def kd(src, metric, setting):
    return src.get(BUNNY, "kdtree", metric, setting)


def kd_factor(src, metric, num, den, target):
    """A Table 2 claim "num vs den changes metric ~target x" (kd-tree on the bunny)."""
    label = f"{metric}({num.split('=')[1]})/{metric}({den.split('=')[1]})"
    return factor(src, [(lambda: kd(src, metric, num), lambda: kd(src, metric, den))], target, label)


def best_setting(src, settings, winner, metric="total"):
    vals = {s: kd(src, metric, s) for s in settings}
    low = min(vals.values())
    ok = vals[winner] <= low * (1 + BEST_TOL)
    return ok, (
        ", ".join(f"{s}: {fmt_sig(v)}" for s, v in vals.items())
        + f" (build + render; best within {BEST_TOL:.0%} of the lowest)"
    )


def trend(src, settings, metric, rising):
    vals = [kd(src, metric, s) for s in settings]
    ok = all(
        (b >= a * (1 - TREND_NOISE)) if rising else (b <= a * (1 + TREND_NOISE))
        for a, b in zip(vals, vals[1:])
    )
    return ok, f"{metric} " + " → ".join(fmt_sig(v) for v in vals)


def large_models(src) -> list[str]:
    """The "large" models of a large-vs-small claim that are larger than every "small" one on
    this side: our stand-in for the Happy Buddha (happy-buddha-100k, 100k triangles) is
    smaller than Igea, so on our side it drops out, and with no large model left the claim's
    premise does not carry over."""
    small = max(src.primitives(m) for m in SMALL_MODELS)
    large = [m for m in LARGE_MODELS if src.primitives(m) > small]
    if not large:
        raise Missing(f"no large model has more primitives than the small ones ({fmt_sig(small)})")
    return large


# ---- the claims -------------------------------------------------------------------------


@dataclass(frozen=True)
class Claim:
    id: str
    section: str
    text: str
    check: Callable
    # Set where the claim cannot fail for any implementation of the report's description:
    # why. A claim that holds is then reported "by construction", not "holds".
    by_construction: str = ""
    # The report models of the part of the claim that can fail here, where the rest holds
    # on the report's own models (the large half of a large-vs-small claim): a claim that
    # fails is decided by stand-ins when these are all read on stand-ins.
    decisive: tuple[str, ...] = ()


CLAIMS: list[Claim] = []


def claim(id_: str, section: str, text: str, by_construction: str = "", decisive: tuple[str, ...] = ()):
    def register(fn):
        CLAIMS.append(Claim(id_, section, text, fn, by_construction, decisive))
        return fn

    return register


MP = ("maxPrims=1", "maxPrims=10", "maxPrims=100")
DEPTHS = ("maxDepth=5", "maxDepth=10", "maxDepth=28", "maxDepth=100")


# Table 2 claims of the form "setting A -> B changes a metric ~N x": (id, text, metric,
# numerator setting, denominator setting, N).
KD_FACTOR_CLAIMS = [
    (
        "5.1-a",
        "maxPrims 1 → 100 cuts kd-tree build time ~2x (the text says 'increased'; its table shows a fall)",
        "build",
        "maxPrims=1",
        "maxPrims=100",
        2,
    ),
    ("5.1-b", "maxPrims 1 → 100 cuts #nodes ~418x", "nodes", "maxPrims=1", "maxPrims=100", 418),
    ("5.1-c", "maxPrims 1 → 100 raises #int. tests ~61x", "prim_tests", "maxPrims=100", "maxPrims=1", 61),
    ("5.1-d", "maxPrims 1 → 100 raises render time ~1.2x", "render", "maxPrims=100", "maxPrims=1", 1.2),
    (
        "5.1-g",
        "max_depth 5 → 10 cuts total (build + render) time ~3x",
        "total",
        "maxDepth=5",
        "maxDepth=10",
        3,
    ),
    ("5.1-h", "max_depth 10 → 28 improves total time ~1.2x", "total", "maxDepth=10", "maxDepth=28", 1.2),
]
for _id, _text, _metric, _num, _den, _target in KD_FACTOR_CLAIMS:
    claim(_id, "5.1", _text)(lambda src, m=_metric, n=_num, d=_den, t=_target: kd_factor(src, m, n, d, t))


@claim("5.1-e", "5.1", "maxPrims=10 is the best trade-off of 1/10/100 (lowest build + render)")
def _(src):
    return best_setting(src, MP, "maxPrims=10")


@claim("5.1-f", "5.1", "A deeper kd-tree (depth 5 → 10 → 28 → 100) builds slower and renders faster")
def _(src):
    ok_b, ev_b = trend(src, DEPTHS, "build", rising=True)
    ok_r, ev_r = trend(src, DEPTHS, "render", rising=False)
    return ok_b and ok_r, (f"{ev_b}; {ev_r} (steps may reverse by ≤ {TREND_NOISE:.0%})")


@claim("5.1-i", "5.1", "Depth saturates above ~28: depth 28 and 100 give the same tree (#nodes)")
def _(src):
    a, b = kd(src, "nodes", "maxDepth=28"), kd(src, "nodes", "maxDepth=100")
    return abs(b - a) <= SAME_TREE_RTOL * a, (
        f"nodes {fmt_sig(a)} vs {fmt_sig(b)} (same within {SAME_TREE_RTOL:.0%})"
    )


@claim("5.1-j", "5.1", "Depth 28 (Equation 5) gives the best total of the depths tried")
def _(src):
    return best_setting(src, DEPTHS, "maxDepth=28")


@claim("5.2-a", "5.2", "BVH builds fastest (Table 4 models)")
def _(src):
    return ranking(src, TABLE4_MODELS, "build", "bvh")


@claim("5.2-b", "5.2", "kd-tree builds slowest (Table 4 models)")
def _(src):
    return ranking(src, TABLE4_MODELS, "build", "kdtree", extreme="max")


@claim("5.2-c", "5.2", "LBVH builds ~2x slower than BVH")
def _(src):
    return factor(
        src,
        [
            ((lambda m=m: src.get(m, "lbvh", "build")), (lambda m=m: src.get(m, "bvh", "build")))
            for m in TABLE4_MODELS
        ],
        2,
        "LBVH/BVH build",
    )


@claim("5.2-d", "5.2", "BVH and LBVH render about the same")
def _(src):
    return similar(src, TABLE4_MODELS, "lbvh", "bvh", "render", "most")


@claim("5.2-e", "5.2", "BVH spends less build + render time than LBVH")
def _(src):
    return compare(src, TABLE4_MODELS, "bvh", "lbvh", "total", "most")


@claim("5.2-f", "5.2", "kd-tree spends the most build + render time (its expensive build)")
def _(src):
    return ranking(src, TABLE4_MODELS, "total", "kdtree", extreme="max", quantifier="most")


@claim(
    "5.2-g",
    "5.2",
    "BVH and LBVH build trees of about the same size (#nodes)",
    by_construction="a binary BVH with one primitive per leaf has 2N-1 nodes, whatever its splits",
)
def _(src):
    return similar(src, TABLE4_MODELS, "lbvh", "bvh", "nodes", "all", within=1.1)


@claim(
    "5.2-h",
    "5.2",
    "kd-tree has more nodes than BVH on the small models (bunny, Igea) and "
    "fewer on the large ones (Dragon, Buddha)",
    decisive=tuple(LARGE_MODELS),
)
def _(src):
    large = large_models(src)
    ok_s, ev_s = compare(src, SMALL_MODELS, "bvh", "kdtree", "nodes")
    ok_l, ev_l = compare(src, large, "kdtree", "bvh", "nodes")
    return ok_s and ok_l, f"{ev_s}. {ev_l}"


@claim("5.2-i", "5.2", "kd-tree needs fewer #int. tests than BVH on the large models (Dragon, Buddha)")
def _(src):
    return compare(src, large_models(src), "kdtree", "bvh", "prim_tests")


@claim("5.3-a", "5.3", "kd-tree renders fastest on complex scenes (Trees, City)")
def _(src):
    return ranking(src, TABLE5_MODELS, "render", "kdtree")


@claim("5.3-b", "5.3", "kd-tree renders more than 2x faster than BVH and LBVH on Trees")
def _(src):
    ratios = {
        s: src.get("trees", s, "render") / src.get("trees", "kdtree", "render") for s in ("bvh", "lbvh")
    }
    return all(r > 2 for r in ratios.values()), (
        "Trees: "
        + ", ".join(f"{STRUCTURE_SHORT[s]}/kd-tree render {fmt_sig(r)}x" for s, r in ratios.items())
        + " (needs > 2x each)"
    )


@claim("5.3-c", "5.3", "kd-tree takes more than twice as long to build as BVH and LBVH on Trees")
def _(src):
    return more_than(src, "trees", "kdtree", ("bvh", "lbvh"), "build", 2)


@claim("5.3-d", "5.3", "BVH and LBVH spend about the same build + render time on Trees and City")
def _(src):
    return similar(src, TABLE5_MODELS, "lbvh", "bvh", "total", "all")


@claim("5.3-e", "5.3", "City: BVH builds faster than LBVH, but LBVH renders faster than BVH")
def _(src):
    ok_b, ev_b = compare(src, ["sci-fi-city"], "bvh", "lbvh", "build")
    ok_r, ev_r = compare(src, ["sci-fi-city"], "lbvh", "bvh", "render")
    return ok_b and ok_r, f"{ev_b}. {ev_r}"


@claim("5.3-f", "5.3", "BVH and LBVH render the City slower than Igea although it has fewer primitives")
def _(src):
    pc, pi = src.primitives("sci-fi-city"), src.primitives("igea")
    if pc >= pi:
        raise Missing(f"the premise fails: City {fmt_sig(pc)} ≥ Igea {fmt_sig(pi)} primitives")
    parts, flags = [], []
    for s in ("bvh", "lbvh"):
        r = src.get("sci-fi-city", s, "render") / src.get("igea", s, "render")
        flags.append(r > 1)
        parts.append(f"{STRUCTURE_SHORT[s]} City/Igea render {fmt_sig(r)}x")
    return all(flags), f"{', '.join(parts)} (primitives {fmt_sig(pc)} vs {fmt_sig(pi)})"


@claim("6-a", "6", "BVH builds fastest in most scenes (all six)")
def _(src):
    return ranking(src, ALL_MODELS, "build", "bvh", quantifier="most")


@claim("6-b", "6", "BVH and LBVH render about the same in most scenes (all six)")
def _(src):
    return similar(src, ALL_MODELS, "lbvh", "bvh", "render", "most")


@claim("6-c", "6", "kd-tree renders faster than BVH and LBVH (most scenes of all six)")
def _(src):
    return ranking(src, ALL_MODELS, "render", "kdtree", quantifier="most")


@claim("6-d", "6", "kd-tree invests the most build time (all six)")
def _(src):
    return ranking(src, ALL_MODELS, "build", "kdtree", extreme="max")


CLAIMS.sort(key=lambda c: (c.section, c.id))  # ids follow the report's sections


# ---- ablations ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Ablation:
    """One measured cause: the claims it tests, judged again on the rows of the ablation
    configs that have these parameters (every other structure as measured at the report's
    settings), or, for `cost_model`, on those numbers with the report's render floor
    (outputs/cost_model.py). `models`: report model -> our model the ablation measures
    instead of the stand-in of the tables."""

    name: str
    params: dict[str, tuple[tuple[str, str], ...]]
    claims: tuple[str, ...]
    why: str
    config: str = "configs/ablations.yaml"
    cost_model: bool = False
    models: tuple[tuple[str, str], ...] = ()

    def describe(self) -> str:
        settings = "; ".join(
            f"{s} " + (",".join(f"{k}={v}" for k, v in ps) if ps else "at Table 3's settings")
            for s, ps in self.params.items()
        )
        on = "".join(f" on {ours} for {REPORT_MODEL[m].short}" for m, ours in self.models)
        if self.cost_model:
            floor = "tables/cost_model.csv: render − a_ours + b_ours × a_report / b_report per Table 2 sweep"
            return floor + (f", on {self.config}: {settings}{on}" if settings else "")
        return f"{self.config}: {settings}{on}"

    def base(self, results: Results, report_nums: pd.DataFrame) -> OurSource:
        return OurSource(results, report_nums, self.params or None, models=dict(self.models))

    def source(self, results: Results, report_nums: pd.DataFrame, fits) -> OurSource | FlooredSource | None:
        """The numbers to judge its claims on, or None where this run has no such rows."""
        rows = results.rows
        if self.params and (
            "accel" not in rows or not (is_ablation(rows) & rows["accel"].isin(list(self.params))).any()
        ):
            return None
        if self.models and not rows["model"].isin([ours for _, ours in self.models]).any():
            return None
        if not self.cost_model:
            return self.base(results, report_nums)
        report_fits, our_fits = fits
        base = self.base(results, report_nums)
        if self.params or self.models:  # our floor is fitted on the rows the ablation reads
            our_fits = fit_all(base, Missing)
        try:
            return FlooredSource(base, our_fits, report_fits, Missing)
        except ValueError:
            return None


TABLE2_CLAIMS = ("5.1-a", "5.1-b", "5.1-c", "5.1-d", "5.1-e", "5.1-f", "5.1-g", "5.1-h", "5.1-i", "5.1-j")
LBVH_BUILD_CLAIMS = ("5.2-a", "5.2-c", "5.2-e", "5.3-d", "5.3-e", "6-a")
KD_PRIMARY = {"kdtree": (("empty_bonus", "0"), ("build", "nlogn"), ("mailbox", "true"))}
REPORT_N = (("stanford-bunny", "bunny-35947"),)
PRIMARY_WHY = (
    "b_e = 0, and #int. tests counted as the report seems to: camera rays only (no light, so no "
    "shadow rays) and each triangle tested once per ray"
)
FLOOR_WHY = (
    "the report's renderer pays a fixed floor of tens of millions of primitive tests' worth per "
    "render, which compresses its render ratios; ours replayed with that floor"
)
# The order matters where several test one claim: the first that holds is the claim's
# ablation; where none holds, the last one (the most faithful) is shown.
ABLATIONS = [
    Ablation(
        "kd-tree empty bonus 0",
        {"kdtree": (("empty_bonus", "0"), ("build", "nlogn"), ("mailbox", "false"))},
        TABLE2_CLAIMS,
        "the report never gives b_e; at b_e = 0 its Table 2 trees come out (its published code "
        "keeps b_e in a char, so its 0.5 is 0)",
    ),
    Ablation(
        "kd-tree empty bonus 0 on primary rays with mailboxes",
        KD_PRIMARY,
        TABLE2_CLAIMS,
        PRIMARY_WHY,
        config="configs/ablations-primary.yaml",
    ),
    Ablation(
        "kd-tree empty bonus 0 on primary rays with mailboxes, at the report's N",
        KD_PRIMARY,
        TABLE2_CLAIMS,
        PRIMARY_WHY + "; on the bunny decimated to the report's N = 35,947 (its #Primitives)",
        config="configs/ablations-primary.yaml",
        models=REPORT_N,
    ),
    Ablation(
        "kd-tree pbrt build",
        {"kdtree": (("build", "pbrt"),)},
        ("5.1-a",),
        "pbrt-v3's build (edges sorted at every node), as the report's kd-tree follows pbrt",
    ),
    Ablation(
        "the report's LBVH build (Algorithm 2)",
        {"lbvh": (("build", "report"),), "bvh": ()},
        LBVH_BUILD_CLAIMS,
        "Algorithm 2 as written: each node's box fitted from its primitives and a linear scan "
        "for the split, where ours is Karras 2012's O(N) build; the same tree; the median BVH "
        "measured beside it",
    ),
    Ablation(
        "the report's LBVH as measured (the median BVH's build after Morton codes and a radix sort)",
        {"lbvh": (("build", "median"),), "bvh": ()},
        LBVH_BUILD_CLAIMS,
        "its section 5.2 has the LBVH build the BVH's tree with three extra stages (Morton "
        "codes, a radix sort, the split search) and its published code builds the LBVH's "
        "subtrees with the median BVH's builder: the median BVH's tree after the codes and the "
        "sort, the median BVH measured beside it",
    ),
    Ablation("the report's render floor", {}, ("5.1-d", "5.1-g", "5.1-h"), FLOOR_WHY, cost_model=True),
    Ablation(
        "the report's render floor at its Table 2 settings",
        KD_PRIMARY,
        ("5.1-d", "5.1-g", "5.1-h"),
        FLOOR_WHY + ", on the rows closest to the report's Table 2: b_e = 0, primary rays counted "
        "once per triangle, the bunny at its N = 35,947",
        config="configs/ablations-primary.yaml",
        cost_model=True,
        models=REPORT_N,
    ),
]


# ---- noise -------------------------------------------------------------------------------

TIMED_METRICS = ("build", "render")
NOISE_DRAWS = 64


def timing_spread(results: Results) -> tuple[float, str]:
    """The run's own timing spread, relative: the larger of (a) the widest gap between two
    measurements of one combination in two configs (the same combo_id) and (b) the median
    relative half-width of the repetitions' confidence intervals. Returns (spread, how)."""
    rows = results.ok()
    rows = rows[~is_ablation(rows)]
    parts, spread = [], 0.0
    for col in ("build_s_median", "render_s_median"):
        if col not in rows or "combo_id" not in rows:
            continue
        g = rows.groupby("combo_id")[col]
        gap = (g.max() / g.min() - 1).where(g.count() > 1).dropna()
        if not gap.empty and float(gap.max()) > spread:
            spread = float(gap.max())
            parts = [f"{col.split('_')[0]} {spread:.0%} between two configs' measurements of one combination"]
    for col in ("build_s", "render_s"):
        lo, hi, med = f"{col}_ci_lo", f"{col}_ci_hi", f"{col}_median"
        if lo in rows and hi in rows:
            half = ((rows[hi] - rows[lo]) / 2 / rows[med]).replace([float("inf")], float("nan")).dropna()
            if not half.empty and float(half.median()) > spread:
                spread = float(half.median())
                parts = [f"median confidence half-width of {col.split('_')[0]} {spread:.0%}"]
    return spread, (parts[0] if parts else "no repeated measurement")


class PerturbedSource(AdjustedSource):
    """Our numbers with every timed value scaled by its own factor in [1 - s, 1 + s]: a
    failing claim that holds under some draw is a verdict inside the run's spread."""

    def __init__(self, base: OurSource, spread: float, seed: int):
        super().__init__(base)
        self.spread = spread
        self.rng = random.Random(seed)
        self.factors: dict[tuple, float] = {}

    def adjust(self, model: str, structure: str, metric: str, setting: str, value: float) -> float:
        if metric not in TIMED_METRICS:
            return value
        key = (model, structure, metric, setting)
        if key not in self.factors:
            self.factors[key] = self.rng.uniform(1 - self.spread, 1 + self.spread)
        return value * self.factors[key]


def holds_within(c: Claim, base: OurSource, spread: float, verdict: str = HOLDS) -> bool:
    """Whether some draw of the timed values within the run's spread gives `verdict`."""
    if spread <= 0:
        return False
    return any(
        evaluate(c, PerturbedSource(base, spread, seed)).verdict == verdict for seed in range(NOISE_DRAWS)
    )


# ---- evaluation and output ----------------------------------------------------------------

BY_CONSTRUCTION, WITHIN_NOISE = "by construction", "within noise"
CLASSES = ("report-numbers", "implementation", "stand-in", "noise", "reading")
CSV_COLUMNS = (
    "claim",
    "text",
    "report_value",
    "our_value",
    "verdict",
    "class",
    "reason",
    "ablation",
    "ablation_value",
    "ablation_verdict",
)


@dataclass
class Finding:
    verdict: str
    evidence: str


def evaluate(c: Claim, src) -> Finding:
    src.begin()
    try:
        holds, evidence = c.check(src)
    except Missing as e:
        return Finding(NOT_COMPARABLE, f"missing data: {e}")
    except ZeroDivisionError:
        return Finding(NOT_COMPARABLE, "a value the claim divides by is zero")
    groups = src.groups()
    if len(groups) > 1:
        return Finding(
            NOT_COMPARABLE,
            f"{evidence} — but the rows come from different provenance groups ({', '.join(sorted(groups))})",
        )
    return Finding(HOLDS if holds else FAILS, evidence)


@dataclass
class ClaimRow:
    claim: Claim
    report: Finding
    ours: Finding
    reference: Finding | None = None  # on the committed reference run, when compared with one
    verdict: str = ""  # ours, with `within noise` and `by construction` (the CSV's verdict)
    cls: str = ""
    reason: str = ""
    ablation: str = ""
    ablation_finding: Finding | None = None
    models_used: set[str] = field(default_factory=set)
    # The same claim on our BVH/LBVH rows with ordered traversal (nearer child first), where
    # the run measured both and the verdict differs from the report's traversal's.
    ordered: Finding | None = None
    # Machine-dependent claims only: whether this run's spread reaches the reference run's
    # verdict (then the difference between the runs is noise).
    flip_within_noise: bool | None = None
    # Where an ablation reproduces the claim: whether a draw of the timed values within the
    # run's spread makes it fail again (the ablation's margin is noise-sized).
    ablation_in_noise: bool | None = None
    # The claim's ablation on the committed reference run, where its verdict differs from
    # this run's (holds on one, not on the other), and whether this run's spread reaches it.
    reference_ablation: Finding | None = None
    reference_ablation_within_noise: bool | None = None

    @property
    def machine_dependent(self) -> bool:
        """Judged on both runs with opposite verdicts: the same code holds the claim on one
        machine and not on the other."""
        return self.reference is not None and {self.ours.verdict, self.reference.verdict} == {HOLDS, FAILS}

    @property
    def ablation_verdict_holds(self) -> bool:
        """Explained by an ablation of this run that makes the claim hold."""
        return (
            self.cls == "implementation"
            and self.ablation_finding is not None
            and (self.ablation_finding.verdict == HOLDS)
        )

    def csv_row(self) -> dict[str, str]:
        a = self.ablation_finding
        return {
            "claim": self.claim.id,
            "text": self.claim.text,
            "report_value": self.report.evidence,
            "our_value": self.ours.evidence,
            "verdict": self.verdict,
            "class": self.cls,
            "reason": self.reason,
            "ablation": self.ablation,
            "ablation_value": a.evidence if a else "",
            "ablation_verdict": a.verdict if a and a.verdict in (HOLDS, FAILS) else "",
        }


class RecordingSource(OurSource):
    """OurSource that remembers which of the report's models a claim read."""

    def __init__(self, *args, **kw):
        super().__init__(*args, **kw)
        self.models_read: set[str] = set()

    def get(self, model: str, structure: str, metric: str, setting: str = "default") -> float:
        self.models_read.add(model)
        return super().get(model, structure, metric, setting)


def stand_ins(src: OurSource, models: set[str]) -> list[str]:
    """The report models among `models` that we measure on another model."""
    return sorted(m for m in models if src.model(m) != m and m in REPORT_MODEL)


def classify(row: ClaimRow, src: RecordingSource, spread: float, spread_how: str, ablated) -> None:
    """Verdict, class and reason of one claim (the CSV's columns), from the measured rows:
    by construction > holds > an ablation that reproduces it > the report's own numbers >
    the run's spread > stand-in models (when the claim reads only stand-ins) > our
    implementation (no ablation of the run reproduces the report's verdict)."""
    c, ours = row.claim, row.ours
    row.verdict = ours.verdict
    if ours.verdict == HOLDS and c.by_construction:
        row.verdict, row.reason = BY_CONSTRUCTION, f"cannot fail: {c.by_construction}"
        return
    if ours.verdict != FAILS:
        return
    for abl, finding in ablated:
        row.ablation, row.ablation_finding = abl.describe(), finding
        if finding.verdict == HOLDS:
            row.cls = "implementation"
            row.reason = f"holds at {abl.name} ({abl.why}): {finding.evidence}"
            return
    if row.report.verdict == FAILS:
        row.cls = "report-numbers"
        row.reason = f"the report's own numbers do not support it either: {row.report.evidence}"
        return
    if holds_within(c, src, spread):
        row.verdict, row.cls = WITHIN_NOISE, "noise"
        row.reason = (
            f"holds with the timed values moved within the run's spread ({spread_how}): {ours.evidence}"
        )
        return
    used = row.models_used & set(c.decisive) if c.decisive else row.models_used
    subs = stand_ins(src, used)
    if subs and len(subs) == len(used):  # read only stand-ins: they decide it
        row.cls = "stand-in"
        row.reason = (
            "decided on stand-in models ("
            + ", ".join(f"{REPORT_MODEL[m].short} → {src.model(m)}" for m in subs)
            + f"): {ours.evidence}"
        )
        return
    row.cls = "implementation"
    row.reason = f"no ablation of this run reproduces the report here; measured: {ours.evidence}"
    if row.ablation_finding is not None:
        last = next(a for a, _ in ablated if a.describe() == row.ablation)
        row.reason += f"; at {last.name}: {row.ablation_finding.evidence}"


# Claims that compare the kd-tree with the BVH on large and small models: where they fail,
# the reason adds how that ratio moves with the model's size on both sides, so a reader
# sees whether ours follows the report's trend and only misses its crossing.
SIZE_TRENDS = {"5.2-h": "nodes", "5.2-i": "prim_tests"}


def size_trend(src, metric: str) -> str:
    """kd-tree/BVH `metric` on each Table 4 model the source has, in the table's order."""
    parts = []
    for m in TABLE4_MODELS:
        try:
            parts.append(f"{short(m)} {fmt_sig(src.get(m, 'kdtree', metric) / src.get(m, 'bvh', metric))}")
        except (Missing, ZeroDivisionError):
            continue
    return ", ".join(parts) if parts else "none measured"


def sweep_fits(results: Results, report_nums: pd.DataFrame) -> tuple[dict, dict]:
    """The cost model's fits of every Table 2 sweep: (the report's, ours)."""
    return fit_all(ReportSource(report_nums), Missing), fit_all(OurSource(results, report_nums), Missing)


def evaluate_all(
    results: Results, report_nums: pd.DataFrame, reference: Results | None = None, fits: tuple | None = None
) -> tuple[list[ClaimRow], OurSource]:
    """fits: sweep_fits(results, report_nums) where the caller has them already."""
    rsrc, osrc = ReportSource(report_nums), RecordingSource(results, report_nums)
    refsrc = OurSource(reference, report_nums) if reference is not None else None
    spread, how = timing_spread(results)
    fits = fits or sweep_fits(results, report_nums)
    ordered = OurSource(results, report_nums, traversal="ordered")
    abl_srcs = [(a, s) for a in ABLATIONS if (s := a.source(results, report_nums, fits)) is not None]
    ref_abl = {}
    if reference is not None:
        ref_fits = sweep_fits(reference, report_nums)
        ref_abl = {
            a.describe(): s
            for a in ABLATIONS
            if (s := a.source(reference, report_nums, ref_fits)) is not None
        }
    rows = []
    for c in CLAIMS:
        osrc.models_read = set()
        row = ClaimRow(c, evaluate(c, rsrc), evaluate(c, osrc))
        row.models_used = set(osrc.models_read)
        row.reference = evaluate(c, refsrc) if refsrc is not None else None
        ablated = [(a, evaluate(c, s)) for a, s in abl_srcs if c.id in a.claims]
        classify(row, osrc, spread, how, ablated)
        if row.ablation_verdict_holds:
            abl_src = next(s for a, s in abl_srcs if a.describe() == row.ablation)
            row.ablation_in_noise = holds_within(c, abl_src, spread, FAILS)
            if row.ablation_in_noise:
                row.reason += (
                    f"; by a margin inside the run's spread ({how}): some draw of the timed values "
                    "within it fails it"
                )
        if row.ablation_finding is not None and row.ablation in ref_abl:
            theirs = evaluate(c, ref_abl[row.ablation])
            if {theirs.verdict, row.ablation_finding.verdict} == {HOLDS, FAILS}:
                row.reference_ablation = theirs
                here = next(s for a, s in abl_srcs if a.describe() == row.ablation)
                row.reference_ablation_within_noise = holds_within(c, here, spread, theirs.verdict)
        if row.verdict == FAILS and not row.ablation_verdict_holds and c.id in SIZE_TRENDS:
            metric = SIZE_TRENDS[c.id]
            row.reason += (
                f"; kd-tree/BVH {metric} by model: ours {size_trend(osrc, metric)}; "
                f"the report's {size_trend(rsrc, metric)}"
            )
        note_traversal(row, evaluate(c, ordered))
        if row.machine_dependent:
            row.flip_within_noise = holds_within(c, osrc, spread, row.reference.verdict)
        rows.append(row)
    return rows, osrc


def note_traversal(row: ClaimRow, ordered: Finding) -> None:
    """Our verdicts read the BVH/LBVH rows with the report's traversal (its Algorithm 1: every
    hit collected, then the nearest taken). A claim whose verdict changes with ordered
    traversal holds only because of that traversal: say so beside it."""
    if ordered.verdict not in (HOLDS, FAILS) or ordered.verdict == row.ours.verdict:
        return
    row.ordered = ordered
    note = (
        f"with ordered traversal (nearer child first, early exit) it {'holds' if ordered.verdict == HOLDS else 'does not hold'}: "
        f"{ordered.evidence}"
    )
    if row.verdict == HOLDS:
        note = "holds only with the report's traversal (Algorithm 1, every hit collected); " + note
    row.reason = f"{row.reason}; {note}" if row.reason else note


def summary_line(rows: list[ClaimRow]) -> str:
    failing = [r for r in rows if r.verdict in (FAILS, WITHIN_NOISE)]
    n = {k: sum(r.cls == k for r in failing) for k in CLASSES}
    reproduced = sum(r.ablation_verdict_holds for r in failing)
    narrow = sum(bool(r.ablation_verdict_holds and r.ablation_in_noise) for r in failing)
    return (
        f"Of {len(failing)} claims that do not hold at our settings: {reproduced} reproduced under an "
        f"ablation"
        + (f" ({narrow} of them by a margin inside the run's timing spread)" if narrow else "")
        + f", {n['report-numbers']} contradicted by the report's own tables, {n['stand-in']} "
        f"decided by stand-ins, {n['noise']} within noise"
        + (f", {n['reading']} another reading of the text" if n["reading"] else "")
        + f", {n['implementation'] - reproduced} an implementation difference no ablation of this run "
        "reproduces (the reason names it)."
    )


def reference_ablation_text(rows: list[ClaimRow]) -> str:
    """The claims whose ablation holds on one run and not on the other, and whether this
    run's timing spread reaches the reference run's verdict (then it is noise)."""
    differ = [r for r in rows if r.reference_ablation is not None]
    if not differ:
        return "Every ablation judged on both runs has the same verdict on both."
    return (
        "Ablation verdicts that differ from the reference run's: "
        + "; ".join(
            f"{r.claim.id} at {md_escape(r.ablation)} (here {r.ablation_finding.verdict}: "
            f"{md_escape(r.ablation_finding.evidence)}; reference run {r.reference_ablation.verdict}: "
            f"{md_escape(r.reference_ablation.evidence)}; "
            + (
                "within this run's timing spread, so noise)"
                if r.reference_ablation_within_noise
                else "beyond this run's timing spread)"
            )
            for r in differ
        )
        + "."
    )


def tolerance_text() -> str:
    lo12, hi12 = approx_range(1.2)
    lo2, hi2 = approx_range(2)
    return (
        f"Tolerances (accelbench_analysis/claims.py): '~N x' holds when the measured factor "
        f"lies within a factor {APPROX_FACTOR} of N and keeps at least "
        f"{APPROX_MIN_EFFECT:.0%} of the claimed effect in log terms (~1.2x accepts "
        f"{fmt_sig(lo12)}-{fmt_sig(hi12)}x, ~2x accepts {fmt_sig(lo2)}-{fmt_sig(hi2)}x); "
        f"'about the same' = within a factor {SIMILAR_FACTOR} (node counts: 1.1); 'the same "
        f"tree' = node counts within {SAME_TREE_RTOL:.0%}; 'best' = within {BEST_TOL:.0%} "
        f"of the lowest; trends may reverse by at most {TREND_NOISE:.0%} per step. 'most' "
        f"= more than half of the models. Our side uses medians."
    )


def claims_markdown(
    rows: list[ClaimRow], results: Results, osrc: OurSource, reference: Results | None = None
) -> str:
    out = ["# The report's claims, checked", ""]
    out += [f"> **Warning:** {md_escape(w)}" + "\n" for w in results.warnings]
    counts = {
        v: sum(r.verdict == v for r in rows)
        for v in (HOLDS, FAILS, WITHIN_NOISE, NOT_COMPARABLE, BY_CONSTRUCTION)
    }
    unsupported = [r.claim.id for r in rows if r.report.verdict == FAILS]
    out += [
        summary_line(rows),
        "",
        "Each claim of the report's sections 5.1-6, evaluated twice by the same code: on the "
        "report's own numbers (results/report/report-tables.csv) and on ours. Model stand-ins "
        "as in the tables (Stanford dragon for the Asian Dragon, happy-buddha-100k for the "
        "Happy Buddha, procedural forest/city for Trees/City); a claim about a stand-in tests "
        "the claim's idea, not the report's scene. A claim that does not hold gets a class "
        "(implementation: an ablation or our implementation decides it; report-numbers: the "
        "report's own numbers do not support it; noise: it holds with the timed values moved "
        "within the run's spread; stand-in: decided on a stand-in model) and the reason, "
        "from the rows of this run; the same table is in claims.csv.",
        "",
        f"Ours: {counts[HOLDS]} hold, {counts[BY_CONSTRUCTION]} by construction, {counts[FAILS]} do "
        f"not hold, {counts[WITHIN_NOISE]} within noise, {counts[NOT_COMPARABLE]} not comparable. "
        f"The report's own numbers do not support: {', '.join(unsupported) if unsupported else 'none'}.",
        "",
        tolerance_text(),
        "",
    ]
    if osrc.variants_used:
        out += [
            f"Our BVH/LBVH rows use traversal={', '.join(sorted(osrc.variants_used))} "
            f"(the report's order is preferred where both modes were measured).",
            "",
        ]
    head = "| # | claim | report's evidence | report's data | our evidence | verdict (ours) | class | reason | ablation |"
    rule = "|:---|:---|:---|:---|:---|:---|:---|:---|:---|"
    if reference is not None:
        dependent = [r.claim.id for r in rows if r.machine_dependent]
        out += [
            f"The last columns: the same claim on the committed reference run "
            f"({'; '.join(g.describe() for g in reference.groups)}). Machine-dependent "
            f"(holds on one run, not on the other): "
            f"{', '.join(dependent) if dependent else 'none'}. " + reference_ablation_text(rows),
            "",
        ]
        head += " verdict (reference run) | |"
        rule += ":---|:---|"
    out += [head, rule]
    for r in rows:
        a = r.ablation_finding
        abl = f"{md_escape(r.ablation)}: {a.verdict} ({md_escape(a.evidence)})" if a else ""
        line = (
            f"| {r.claim.id} | {md_escape(r.claim.text)} | {md_escape(r.report.evidence)} | "
            f"{r.report.verdict} | {md_escape(r.ours.evidence)} | **{r.verdict}** | {r.cls} | "
            f"{md_escape(r.reason)} | {abl} |"
        )
        if reference is not None:
            flag = "**machine-dependent**" if r.machine_dependent else ""
            line += f" {r.reference.verdict} | {flag} |"
        out.append(line)
    return "\n".join(out) + "\n"


def write_claims(
    results: Results, report_nums: pd.DataFrame, out_dir: Path, reference: Results | None = None
) -> tuple[Path, list[ClaimRow]]:
    out_dir.mkdir(parents=True, exist_ok=True)
    fits = sweep_fits(results, report_nums)
    rows, osrc = evaluate_all(results, report_nums, reference, fits)
    write_cost_model_files(fits, rows, out_dir)
    path = out_dir / "claims.md"
    path.write_text(claims_markdown(rows, results, osrc, reference))
    pd.DataFrame([r.csv_row() for r in rows], columns=list(CSV_COLUMNS)).to_csv(
        out_dir / "claims.csv", index=False
    )
    return path, rows


def write_cost_model_files(fits: tuple[dict, dict], rows: list[ClaimRow], out_dir: Path) -> None:
    """tables/cost_model.csv (both sides' fits, point by point) and cost_model.md (its text,
    which REPORT.md's cost model section shows)."""
    report_fits, our_fits = fits
    if not report_fits or not our_fits:
        return
    floor = next(a for a in ABLATIONS if a.cost_model).describe()
    decided = [
        r.claim.id
        for r in rows
        if r.ablation == floor and r.ablation_finding and r.ablation_finding.verdict == HOLDS
    ]
    write_cost_model(report_fits, our_fits, out_dir)
    text = ["# A cost model of render time", ""] + cost_model_lines(report_fits, our_fits, decided)
    (out_dir / "cost_model.md").write_text("\n".join(text) + "\n")
