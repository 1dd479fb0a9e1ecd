"""The machinery the report's claims are checked with (claims.py holds the claims).

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
from dataclasses import dataclass, replace

import pandas as pd

from ...inputs.report_numbers import REPORT_MODEL, TABLE4_MODELS, TABLE5_MODELS, our_model, report_value
from ...inputs.schema import Results
from ...mapping.formatting import fmt_sig
from ...mapping.metrics import METRIC, preferred_variant
from ...mapping.selection import Picker, Spec, setting_spec
from ...mapping.settings import CLAIMS_ONLY_CONFIGS, DEFAULT, SETTING, Setting
from .cost_model import AdjustedSource

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


def is_ablation(rows: pd.DataFrame) -> pd.Series:
    """The rows the claims judge alone (the faithful setting, its factors, the ablations):
    never shown in the report's tables."""
    return (
        rows["config"].isin(CLAIMS_ONLY_CONFIGS) if "config" in rows else pd.Series(False, index=rows.index)
    )


def without_ablations(results: Results) -> Results:
    return replace(results, rows=results.rows[~is_ablation(results.rows)])


# Our metrics beyond the tables' (the report prints none of these).
OUR_COLUMN = {"depth": "tree_depth"}


class OurSource:
    """Our numbers at one setting (mapping/settings.py; by default our defaults): the rows
    of the setting's configs, each structure's rows with the setting's parameters (a
    model's own values replacing the structure's), its model labels. Remembers what a claim
    read: the (combo_id, metric) pairs, for its spread, and the report's models."""

    name = "ours"

    def __init__(self, results: Results, report_nums: pd.DataFrame, setting: Setting = SETTING[DEFAULT]):
        rows = results.rows
        if "config" in rows:
            configs = rows["config"]
            rows = rows[
                configs.isin(setting.configs) if setting.configs else ~configs.isin(CLAIMS_ONLY_CONFIGS)
            ]
        self.results = replace(results, rows=rows)
        self.picker = Picker(self.results)
        self.setting = setting
        present = self.picker.models
        self.models = {
            m: next((x for x in labels if x in present), labels[0]) for m, labels in setting.models
        }
        self.depths = [
            s.split("=")[1]
            for s in report_nums.loc[report_nums["table"] == 2, "setting"]
            if s.startswith("maxDepth=")
        ]
        self._specs: dict[tuple[str, str, str], tuple[Spec, str | None]] = {}
        self.begin()

    def begin(self) -> None:
        self._groups: set[str] = set()
        self.read: set[tuple[str, str]] = set()
        self.models_read: set[str] = set()

    def groups(self) -> set[str]:
        return self._groups

    def model(self, report_model: str) -> str:
        return self.models.get(report_model) or our_model(report_model, self.picker.models)

    def primitives(self, model: str) -> float:
        rows = self.results.rows[self.results.rows["model"] == self.model(model)]
        if rows.empty:
            raise Missing(f"no rows for {self.model(model)}")
        return float(rows["triangles"].iloc[0])

    def spec(self, model: str, structure: str, setting: str) -> tuple[Spec, str | None]:
        """The spec of one of the report's settings ("default", a Table 2 setting, or
        "threads=N": Table 3's setting built on N threads) at this source's setting, and
        the traversal variant to read (the setting's, else the preferred one measured)."""
        key = (model, structure, setting)
        if key not in self._specs:
            self._specs[key] = self._spec(model, structure, setting)
        return self._specs[key]

    def _spec(self, model: str, structure: str, setting: str) -> tuple[Spec, str | None]:
        threads = setting.partition("=")[2] if setting.startswith("threads=") else None
        ours = self.model(model)
        spec = setting_spec("default" if threads else setting, structure, self.picker, ours, self.depths)
        wanted = dict(spec.required)
        wanted.update(self.setting.params_of(structure, model))
        if threads:
            wanted["threads"] = threads
        spec = replace(spec, required=tuple(wanted.items()))
        variants = self.picker.variants([ours], spec)
        variant = wanted.get("traversal") or preferred_variant(variants)
        return spec, variant if variant in variants else None

    def get(self, model: str, structure: str, metric: str, setting: str = "default") -> float:
        if metric == "total":
            return self.get(model, structure, "build", setting) + self.get(
                model, structure, "render", setting
            )
        self.models_read.add(model)
        ours = self.model(model)
        spec, variant = self.spec(model, structure, setting)
        pick = self.picker.pick(ours, spec, variant)
        what = f"{STRUCTURE_SHORT.get(structure, structure)} ({setting}) on {ours}"
        if not pick.ok:
            raise Missing(f"{what}: {pick.reason}")
        v = pick.value(OUR_COLUMN.get(metric) or METRIC[metric].ours)
        if v is None:
            raise Missing(f"{what} has no {metric}")
        self._groups.add(str(pick.row["prov_group"]))
        self.read.add((str(pick.row.get("combo_id", "")), metric))
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


def registrar(claims: list[Claim]):
    """The decorator that registers a check into `claims`."""

    def claim(id_: str, section: str, text: str, by_construction: str = "", decisive: tuple[str, ...] = ()):
        def register(fn):
            claims.append(Claim(id_, section, text, fn, by_construction, decisive))
            return fn

        return register

    return claim


# ---- evaluation and noise ----------------------------------------------------------------


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


TIMED_METRICS = ("build", "render")
NOISE_DRAWS = 64


class PerturbedSource(AdjustedSource):
    """Our numbers with every timed value scaled by its own factor in [1 / (1 + s), 1 + s]
    (log-uniform): a failing claim that holds under some draw is a verdict inside the run's
    spread. The spread is a ratio of two measurements less one (max / min - 1), so a value
    may lie that far above or below; the factor stays positive at any spread (a spread over
    100%, [1 - s, 1 + s] would reach zero and below)."""

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
            self.factors[key] = (1 + self.spread) ** self.rng.uniform(-1.0, 1.0)
        return value * self.factors[key]


def holds_within(c: Claim, base: OurSource, spread: float, verdict: str = HOLDS) -> bool:
    """Whether some draw of the timed values within the run's spread gives `verdict`."""
    if spread <= 0:
        return False
    return any(
        evaluate(c, PerturbedSource(base, spread, seed)).verdict == verdict for seed in range(NOISE_DRAWS)
    )


def tolerance_text() -> str:
    lo12, hi12 = approx_range(1.2)
    lo2, hi2 = approx_range(2)
    return (
        f"Tolerances (outputs/report/claim_checks.py): '~N x' holds when the measured factor "
        f"lies within a factor {APPROX_FACTOR} of N and keeps at least "
        f"{APPROX_MIN_EFFECT:.0%} of the claimed effect in log terms (~1.2x accepts "
        f"{fmt_sig(lo12)}-{fmt_sig(hi12)}x, ~2x accepts {fmt_sig(lo2)}-{fmt_sig(hi2)}x); "
        f"'about the same' = within a factor {SIMILAR_FACTOR} (node counts: 1.1); 'the same "
        f"tree' = node counts within {SAME_TREE_RTOL:.0%}; 'best' = within {BEST_TOL:.0%} "
        f"of the lowest; trends may reverse by at most {TREND_NOISE:.0%} per step. 'most' "
        f"= more than half of the models. Our side uses medians."
    )
