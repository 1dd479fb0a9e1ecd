"""The report's claims (sections 5.1 to 6), each a small check over a *source* of numbers:
the report's (report-tables.csv) or ours at one setting (claim_checks.OurSource). The same
check computes both sides, so a verdict is never typed in: it follows from the data. A claim
whose numbers are missing on one side, or whose rows come from different builds/machines,
is "not comparable", with the reason. The machinery and the tolerances: claim_checks.py.
"""

from __future__ import annotations

from ...mapping.formatting import fmt_sig
from .claim_checks import (
    ALL_MODELS,
    APPROX_FACTOR,
    BEST_TOL,
    BUNNY,
    FAILS,
    HOLDS,
    LARGE_MODELS,
    NOT_COMPARABLE,
    SAME_TREE_RTOL,
    SMALL_MODELS,
    STRUCTURE_SHORT,
    TABLE4_MODELS,
    TABLE5_MODELS,
    TREND_NOISE,
    Claim,
    Finding,
    Missing,
    OurSource,
    ReportSource,
    approx,
    approx_range,
    best_setting,
    compare,
    evaluate,
    factor,
    holds_within,
    is_ablation,
    kd,
    kd_factor,
    large_models,
    more_than,
    quantify,
    ranking,
    registrar,
    short,
    similar,
    tolerance_text,
    trend,
    without_ablations,
)

# The names other modules import from here with the claims.
__all__ = [
    "APPROX_FACTOR",
    "CLAIMS",
    "FAILS",
    "HOLDS",
    "NOT_COMPARABLE",
    "Claim",
    "Finding",
    "Missing",
    "OurSource",
    "ReportSource",
    "approx",
    "approx_range",
    "compare",
    "evaluate",
    "holds_within",
    "is_ablation",
    "tolerance_text",
    "without_ablations",
]

CLAIMS: list[Claim] = []
claim = registrar(CLAIMS)

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


def tree_depth(src, model: str, structure: str, setting: str = "default") -> float:
    """The depth of the built tree; the report prints none."""
    if isinstance(src, ReportSource):
        raise Missing("the report prints no tree depths")
    return src.get(model, structure, "depth", setting)


@claim("5.1-k", "5.1", "The larger maxPrims (1 → 10 → 100), the less the kd-tree takes to build")
def _(src):
    vals = [kd(src, "build", s) for s in MP]
    ok = all(b <= a * (1 + TREND_NOISE) for a, b in zip(vals, vals[1:]))
    return ok, "build " + " → ".join(
        fmt_sig(v) for v in vals
    ) + f" (each step may rise by ≤ {TREND_NOISE:.0%})"


@claim("5.1-l", "5.1", "A larger maxPrims makes the kd-tree shallower (maxPrims 1 → 100)")
def _(src):
    a, b = tree_depth(src, BUNNY, "kdtree", "maxPrims=1"), tree_depth(src, BUNNY, "kdtree", "maxPrims=100")
    return b < a, f"depth {fmt_sig(a)} → {fmt_sig(b)}"


@claim("5.1-m", "5.1", "Depth 100 plays no role in performance: the same total time as depth 28")
def _(src):
    a, b = kd(src, "total", "maxDepth=28"), kd(src, "total", "maxDepth=100")
    return abs(b / a - 1) <= BEST_TOL, (
        f"total {fmt_sig(a)} vs {fmt_sig(b)} ({fmt_sig(b / a)}x; the same within {BEST_TOL:.0%})"
    )


@claim("5.2-j", "5.2", "BVH and LBVH give about the same #int. tests")
def _(src):
    return similar(src, TABLE4_MODELS, "lbvh", "bvh", "prim_tests", "most")


@claim("5.2-k", "5.2", "A multithreaded LBVH builds faster than the BVH")
def _(src):
    flags, parts = [], []
    for m in TABLE4_MODELS:
        lb, b = src.get(m, "lbvh", "build", "threads=2"), src.get(m, "bvh", "build")
        flags.append(lb < b)
        parts.append(f"{short(m)} {fmt_sig(lb)} {'<' if flags[-1] else '≥'} {fmt_sig(b)}")
    return quantify(flags, "most"), "LBVH (2 build threads) vs BVH build: " + "; ".join(parts)


@claim("5.3-g", "5.3", "Trees: the kd-tree has almost 4.5x the BVH's and LBVH's nodes")
def _(src):
    return factor(
        src,
        [
            ((lambda s=s: src.get("trees", "kdtree", "nodes")), (lambda s=s: src.get("trees", s, "nodes")))
            for s in ("bvh", "lbvh")
        ],
        4.5,
        "Trees kd-tree/BVH-LBVH nodes",
    )


@claim("5.3-h", "5.3", "The kd-tree's render advantage is larger on Trees than on Igea and the Dragon")
def _(src):
    def edge(m):
        return src.get(m, "bvh", "render") / src.get(m, "kdtree", "render")

    t, others = edge("trees"), {m: edge(m) for m in ("igea", "asian-dragon")}
    return all(t > v for v in others.values()), (
        f"BVH/kd-tree render: Trees {fmt_sig(t)}x; "
        + ", ".join(f"{short(m)} {fmt_sig(v)}x" for m, v in others.items())
    )


@claim("5.3-i", "5.3", "City: the kd-tree has fewer nodes than on the bunny")
def _(src):
    c, b = src.get("sci-fi-city", "kdtree", "nodes"), src.get(BUNNY, "kdtree", "nodes")
    return c < b, f"kd-tree nodes City {fmt_sig(c)} vs bunny {fmt_sig(b)}"


@claim("5.3-j", "5.3", "City: ~21x the bunny's kd-tree #int. tests but only ~2.6x its render time")
def _(src):
    ok_t, ev_t = factor(
        src,
        [
            (
                lambda: src.get("sci-fi-city", "kdtree", "prim_tests"),
                lambda: src.get(BUNNY, "kdtree", "prim_tests"),
            )
        ],
        21,
        "City/bunny kd-tree tests",
    )
    ok_r, ev_r = factor(
        src,
        [(lambda: src.get("sci-fi-city", "kdtree", "render"), lambda: src.get(BUNNY, "kdtree", "render"))],
        2.6,
        "render",
    )
    return ok_t and ok_r, f"{ev_t}; {ev_r}"


@claim("6-e", "6", "The kd-tree builds deeper trees than the BVH and LBVH (most of the six scenes)")
def _(src):
    flags, parts = [], []
    for m in ALL_MODELS:
        k = tree_depth(src, m, "kdtree")
        others = {s: tree_depth(src, m, s) for s in ("bvh", "lbvh")}
        flags.append(all(k > v for v in others.values()))
        parts.append(
            f"{short(m)} kd-tree {fmt_sig(k)} vs "
            + ", ".join(f"{STRUCTURE_SHORT[s]} {fmt_sig(v)}" for s, v in others.items())
        )
    return quantify(flags, "most"), "depth: " + "; ".join(parts)


CLAIMS.sort(key=lambda c: (c.section, c.id))  # ids follow the report's sections
