"""Claims of the report's sections 5.1-6 beyond the first 29: each a check the report's text
makes and its numbers (or ours) can test, registered into the same CLAIMS list."""

from __future__ import annotations

from .claims import (
    BEST_TOL,
    BUNNY,
    CLAIMS,
    STRUCTURE_SHORT,
    TABLE4_MODELS,
    TREND_NOISE,
    Missing,
    ReportSource,
    claim,
    factor,
    kd,
    quantify,
    short,
    similar,
)
from .formatting import fmt_sig

MP = ("maxPrims=1", "maxPrims=10", "maxPrims=100")
ALL_SIX = TABLE4_MODELS + ["trees", "sci-fi-city"]


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
    for m in ALL_SIX:
        k = tree_depth(src, m, "kdtree")
        others = {s: tree_depth(src, m, s) for s in ("bvh", "lbvh")}
        flags.append(all(k > v for v in others.values()))
        parts.append(
            f"{short(m)} kd-tree {fmt_sig(k)} vs "
            + ", ".join(f"{STRUCTURE_SHORT[s]} {fmt_sig(v)}" for s, v in others.items())
        )
    return quantify(flags, "most"), "depth: " + "; ".join(parts)


CLAIMS.sort(key=lambda c: (c.section, c.id))
